// `jointcomp paper`: the paper's experiment (Olabi et al. 2012, Table II) on a simulated RX170.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <sys/stat.h>
#include <nlohmann/json.hpp>

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/output_paths.hpp"
#include "cli/paper_output.hpp"
#include "cli/plot.hpp"
#include "cli/robot_setup.hpp"
#include "model/common/errors.hpp"
#include "model/effects/perturbation.hpp"
#include "model/experiment/paper_identification.hpp"
#include "model/experiment/spiral_experiment.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp::cli {
namespace {

// The feed rates `paper` accepts: a tenth of the paper's (the 30 s spiral takes 300 s, planned and simulated
// in ten times the paper's work) to 2 m/s. Slower plans grow without bound (1e-5 m/s: 3.6 GB after 120 s).
constexpr double kMinFeedRate = 0.003;
constexpr double kMaxFeedRate = 2.0;

// The FMUs of this build, handed out beside the results (in `folder`).
void handOutFmus(const std::string& folder) {
  prepareOutputFolder(folder, "--out (its fmu folder)");
  for (const char* name : {"jointcomp_fmi2.fmu", "jointcomp_fmi3.fmu"}) {
    const std::string built = fileLocations().fmus + "/" + name;
    std::ifstream source(built, std::ios::binary);
    if (!source) {
      std::printf("no FMU at %s (build the jointcomp_fmus target)\n", built.c_str());
      continue;
    }
    std::ostringstream bytes;
    bytes << source.rdbuf();
    writeFileAtomically(folder + "/" + name, bytes.str());
    std::printf("wrote %s/%s (FMI %s co-simulation of the plant with compensation)\n", folder.c_str(), name,
                name[13] == '2' ? "2.0" : "3.0");
  }
}

// The simulated robot, the truth's seed and the compensated joints from the options.
SpiralExperimentSpec specFromOptions(const Options& options, const ParameterSet& parameters, const std::string& path) {
  SpiralExperimentSpec spec;
  if (!options.has("quasi-static")) {
    if (!parameters.hasDrives()) {
      throw ParameterError(path +
                           ": no \"plant\" object (drives and controller gains) for the plant (or --quasi-static)");
    }
    spec.drives = parameters.drives;
  }
  spec.truth.seed =
      static_cast<std::uint64_t>(options.integer("seed", static_cast<long long>(spec.truth.seed), 0, kMaxSeed));
  if (options.has("feed-rate")) {
    const double speed = options.number("feed-rate", kPaperFeedRate, {kMinFeedRate, kMaxFeedRate});
    // The acceleration and jerk limits scale with the speed, so the ramps take the same time as the paper's.
    const double scale = speed / kPaperFeedRate;
    spec.feed_rate.speed = speed;
    spec.feed_rate.acceleration *= scale;
    spec.feed_rate.jerk *= scale;
  }
  // The fourth run wherever the plant runs: the dynamic correction needs the drives.
  spec.dynamic_correction = !spec.drives.empty() && !options.has("no-dynamic-correction");
  if (options.has("compensate-joints")) {
    for (const std::string& item : splitCommaList(options.get("compensate-joints", "")))
      spec.compensated_joints.push_back(static_cast<int>(parseInteger(item, "compensate-joints", 1, kMaxJoints)) - 1);
  }
  return spec;
}

// The identified and perfect models' runs, beside the nominal's (null with --nominal-only).
struct IdentifiedRuns {
  std::unique_ptr<PaperIdentification> identification;
  std::unique_ptr<SpiralExperimentResult> identified, perfect;
};

IdentifiedRuns identifyAndRun(const RobotSetup& setup, const JointErrorModel& truth, const SpiralExperimentSpec& spec,
                              const Progress& progress) {
  IdentifiedRuns runs;
  PaperIdentificationSpec identification;
  identification.seed = spec.truth.seed;
  runs.identification = std::make_unique<PaperIdentification>(
      identifyFromSimulatedCampaigns(setup.parameters.model, truth, identification, progress));
  progress("identification took " + std::to_string(runs.identification->seconds).substr(0, 4) + " s");
  SpiralExperimentSpec later = spec;
  later.first_run = 1;  // the uncorrected run does not depend on the model
  progress("the identified model's runs");
  runs.identified = std::make_unique<SpiralExperimentResult>(
      runSpiralExperiment(*runs.identification->identified, truth, later, progress));
  later.first_run = 2;  // the floor: the corrections computed from the truth itself
  progress("the perfect model's runs (the floor)");
  runs.perfect = std::make_unique<SpiralExperimentResult>(runSpiralExperiment(truth, truth, later, progress));
  return runs;
}

}  // namespace

int runPaper(int argc, char** argv) {
  const Options options(argc, argv,
                        {"urdf", "base-link", "tip-link", "params", "out", "seed", "compensate-joints", "no-plot",
                         "quasi-static", "feed-rate", "no-dynamic-correction", "nominal-only"},
                        {"no-plot", "quasi-static", "no-dynamic-correction", "nominal-only"});
  const std::string out = options.get("out", "out/paper");
  prepareOutputFolder(out);
  const auto started = std::chrono::steady_clock::now();

  std::printf("jointcomp paper: the spiral test of Olabi et al. (IEEE ICIT 2012), simulated\n");
  const RobotSetup setup = loadRobotSetup(options, robotFile("rx170"), "params", parameterFile("rx170"));
  std::printf("  robot %s\n  parameters %s\n", setup.urdf.c_str(), setup.params.c_str());
  const JointErrorModel& nominal = setup.parameters.model;
  const SpiralExperimentSpec spec = specFromOptions(options, setup.parameters, setup.params);
  std::printf("  simulated robot: %s\n", spec.drives.empty()
                                             ? "quasi-static (kinematics, elastostatics, transmission error)"
                                             : "flexible-joint plant integrated by CVODE");
  std::printf("  feed rate %.3g m/s (acceleration %.3g m/s^2, jerk %.3g m/s^3)%s\n", spec.feed_rate.speed,
              spec.feed_rate.acceleration, spec.feed_rate.jerk,
              spec.feed_rate.speed == kPaperFeedRate ? ", the paper's" : "");
  std::printf(
      "  truth: nominal parameters moved by up to %.0f %% (stiffness), %.0f %% (harmonic amplitudes), "
      "%.2f rad (phases); seed %llu\n",
      spec.truth.stiffness_relative * 100, spec.truth.amplitude_relative * 100, spec.truth.phase_absolute_rad,
      static_cast<unsigned long long>(spec.truth.seed));
  const Progress progress = [&](const std::string& what) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    std::printf("  [%6.2f s] %s\n", elapsed, what.c_str());
    std::fflush(stdout);
  };
  const JointErrorModel truth = perturbedModel(nominal, spec.truth);
  IdentifiedRuns identified;
  if (!options.has("nominal-only")) {
    progress("the paper's identification: measuring the simulated robot, then identifying it");
    try {
      identified = identifyAndRun(setup, truth, spec, progress);
    } catch (const Error& error) {
      // The message as it was, with the way round it (a parameter file the paper's campaigns cannot identify).
      throw std::runtime_error(std::string("the paper's identification: ") + error.what() +
                               " (--nominal-only runs the spiral with the nominal model, without identifying)");
    }
  }
  progress("the nominal model's runs");
  const SpiralExperimentResult result = runSpiralExperiment(nominal, truth, spec, progress);
  const PaperRuns runs{&result, identified.identified.get(), identified.perfect.get()};

  nlohmann::ordered_json identification;
  if (identified.identification) {
    std::printf("\n%s", identificationSummary(*identified.identification, truth).c_str());
    const IdentificationFiles files = writeIdentification(out + "/identification", *identified.identification, truth,
                                                          setup.parameters.drives, setup.params, setup.urdf);
    identification = identificationJson(*identified.identification, truth, files);
    std::printf("wrote %s/ (campaigns, identified params.json, report.json for jointcomp montecarlo --report)\n",
                files.folder.c_str());
  }
  writeFileAtomically(out + "/spiral_runs.csv", runsCsv(runs));
  writeFileAtomically(out + "/summary.json", summaryJson(runs, spec, setup.robot->name, identification));
  printTable(runs);
  std::printf("wrote %s/spiral_runs.csv and %s/summary.json\n", out.c_str(), out.c_str());
  handOutFmus(out + "/fmu");
  if (!options.has("no-plot"))
    drawPlot("plot_spiral_runs.py", out + "/spiral_runs.csv", out + "/spiral_z_error.png",
             " (in the manner of the paper's Fig. 13)");

  return 0;
}

}  // namespace jointcomp::cli
