// `jointcomp paper`: the paper's experiment (Olabi et al. 2012, Table II) on a simulated RX170.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>

#include <sys/stat.h>
#include <nlohmann/json.hpp>

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/output_paths.hpp"
#include "cli/plot.hpp"
#include "cli/robot_setup.hpp"
#include "model/common/errors.hpp"
#include "model/experiment/spiral_experiment.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp::cli {
namespace {

// Table II of Olabi et al. (IEEE ICIT 2012), in mm.
constexpr double kPaperRa[3] = {0.2032, 0.0459, 0.0312};
constexpr double kPaperRz[3] = {0.2882, 0.2097, 0.1502};
constexpr double kPaperFeedRate = 0.03;  // m/s
// The feed rates `paper` accepts: a tenth of the paper's (the 30 s spiral takes 300 s, planned and simulated
// in ten times the paper's work) to 2 m/s. Slower plans grow without bound (1e-5 m/s: 3.6 GB after 120 s).
constexpr double kMinFeedRate = 0.003;
constexpr double kMaxFeedRate = 2.0;

std::string runsCsv(const SpiralExperimentResult& result) {
  std::ostringstream csv;
  csv.precision(9);
  csv << "run,t_s,planned_x_mm,planned_y_mm,planned_z_mm,measured_x_mm,measured_y_mm,measured_z_mm,"
         "error_x_mm,error_y_mm,error_z_mm";
  const int dof = result.planned.q.front().size();
  for (int j = 1; j <= dof; ++j) csv << ",q_theo" << j << "_deg";
  for (int j = 1; j <= dof; ++j) csv << ",q_ref" << j << "_deg";
  csv << "\n";
  const double deg = 180.0 / 3.14159265358979323846;
  for (std::size_t r = 0; r < result.runs.size(); ++r) {
    const SpiralRun& run = result.runs[r];
    for (std::size_t k = 0; k < run.error.size(); ++k) {
      const Eigen::Vector3d p = result.planned.tool_position[k] * 1e3;
      const Eigen::Vector3d m = run.measured[k] * 1e3;
      const Eigen::Vector3d e = run.error[k] * 1e3;
      csv << r << ',' << result.planned.time[k] << ',' << p.x() << ',' << p.y() << ',' << p.z() << ',' << m.x() << ','
          << m.y() << ',' << m.z() << ',' << e.x() << ',' << e.y() << ',' << e.z();
      for (int j = 0; j < dof; ++j) csv << ',' << result.planned.q[k][j] * deg;
      for (int j = 0; j < dof; ++j) csv << ',' << run.reference[k][j] * deg;
      csv << "\n";
    }
  }
  return csv.str();
}

// What `jointcomp paper` writes beside the CSV: the runs' metrics against the paper's.
std::string summaryJson(const SpiralExperimentResult& result, const SpiralExperimentSpec& spec,
                        const std::string& robot_name) {
  nlohmann::ordered_json summary;
  summary["experiment"] = "Olabi et al. 2012 spiral, simulated " + robot_name;
  summary["robot"] = robot_name;
  summary["samples"] = result.planned.size();
  summary["duration_s"] = result.planned.time.back();
  summary["truth_seed"] = spec.truth.seed;
  summary["simulated_robot"] = result.dynamic ? "flexible-joint plant (CVODE)" : "quasi-static";
  summary["feed_rate_m_per_s"] = spec.feed_rate.speed;  // (no timings: the same inputs give the same file)
  for (std::size_t r = 0; r < result.runs.size(); ++r) {
    const SpiralRun& run = result.runs[r];
    nlohmann::ordered_json entry = {{"name", run.name},
                                    {"ra_mm", run.metrics.ra * 1e3},
                                    {"rz_mm", run.metrics.rz * 1e3},
                                    {"rms_3d_mm", run.metrics.rms * 1e3},
                                    {"max_3d_mm", run.metrics.max * 1e3}};
    if (r < 3) {
      entry["paper_ra_mm"] = kPaperRa[r];
      entry["paper_rz_mm"] = kPaperRz[r];
      entry["compensation_max_iterations"] = run.compensation.max_iterations;
      entry["compensation_max_correction_deg"] = run.compensation.max_correction * 180.0 / 3.14159265358979323846;
    } else {
      const DynamicCompensationReport& d = run.dynamic_compensation;
      entry["plant_runs"] = d.iterations;
      entry["closed_form_max_link_error_rad"] = d.initial_error_rad;
      entry["nominal_plant_max_link_error_rad"] = d.max_error_rad;
      entry["compensation_max_correction_deg"] = d.max_correction_rad * 180.0 / 3.14159265358979323846;
    }
    summary["runs"].push_back(entry);
  }

  return summary.dump(2) + "\n";
}

// The plant's speed and the Table II analogue, on the console.
void printTable(const SpiralExperimentResult& result) {
  if (result.dynamic) {
    const PlantStatistics& st = result.plant_statistics;
    std::printf(
        "  plant: %.1fx real time (%.3f s for %zu x %.1f s of motion); CVODE %ld steps, %ld right-hand sides, "
        "%ld Jacobians\n",
        static_cast<double>(result.runs.size()) * result.planned.time.back() / result.simulation_seconds,
        result.simulation_seconds, result.runs.size(), result.planned.time.back(), st.steps, st.rhs_evaluations,
        st.jacobian_evaluations);
    if (result.runs.size() > 3) {
      const DynamicCompensationReport& d = result.runs[3].dynamic_compensation;
      std::printf(
          "  dynamic correction: %.2f s; largest link error of the nominal plant %.2g rad in closed form, %.2g rad "
          "after %d runs\n",
          result.runs[3].compensation_seconds, d.initial_error_rad, d.max_error_rad, d.iterations);
    }
  }
  std::printf("\nTable II analogue (%zu samples, %.1f s of motion; errors measured by a simulated tracker)\n",
              result.planned.size(), result.planned.time.back());
  std::printf("%-36s %9s %9s %11s %11s %10s %10s\n", "run", "Ra [mm]", "Rz [mm]", "RMS3D [mm]", "max3D [mm]",
              "paper Ra", "paper Rz");
  for (std::size_t r = 0; r < result.runs.size(); ++r) {
    const AccuracyMetrics& m = result.runs[r].metrics;
    if (r < 3) {
      std::printf("%-36s %9.4f %9.4f %11.4f %11.4f %10.4f %10.4f\n", result.runs[r].name.c_str(), m.ra * 1e3,
                  m.rz * 1e3, m.rms * 1e3, m.max * 1e3, kPaperRa[r], kPaperRz[r]);
    } else {
      std::printf("%-36s %9.4f %9.4f %11.4f %11.4f %10s %10s\n", result.runs[r].name.c_str(), m.ra * 1e3, m.rz * 1e3,
                  m.rms * 1e3, m.max * 1e3, "-", "-");
    }
  }
  const double ra_gain = 1.0 - result.runs[2].metrics.ra / result.runs[0].metrics.ra;
  const double rz_gain = 1.0 - result.runs[2].metrics.rz / result.runs[0].metrics.rz;
  std::printf("reduction with both corrections: Ra %.0f %% (paper %.0f %%), Rz %.0f %% (paper %.0f %%)\n",
              ra_gain * 100, (1 - kPaperRa[2] / kPaperRa[0]) * 100, rz_gain * 100,
              (1 - kPaperRz[2] / kPaperRz[0]) * 100);
}

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

}  // namespace

int runPaper(int argc, char** argv) {
  const Options options(argc, argv,
                        {"urdf", "base-link", "tip-link", "params", "out", "seed", "compensate-joints", "no-plot",
                         "quasi-static", "feed-rate", "no-dynamic-correction"},
                        {"no-plot", "quasi-static", "no-dynamic-correction"});
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
  const SpiralExperimentResult result = runSpiralExperiment(nominal, spec, [&](const std::string& what) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    std::printf("  [%6.2f s] %s\n", elapsed, what.c_str());
    std::fflush(stdout);
  });

  writeFileAtomically(out + "/spiral_runs.csv", runsCsv(result));
  writeFileAtomically(out + "/summary.json", summaryJson(result, spec, setup.robot->name));
  printTable(result);
  std::printf("wrote %s/spiral_runs.csv and %s/summary.json\n", out.c_str(), out.c_str());
  handOutFmus(out + "/fmu");
  if (!options.has("no-plot"))
    drawPlot("plot_spiral_runs.py", out + "/spiral_runs.csv", out + "/spiral_z_error.png",
             " (in the manner of the paper's Fig. 13)");

  return 0;
}

}  // namespace jointcomp::cli
