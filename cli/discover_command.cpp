// `jointcomp discover`: residual discovery. Fits the base model (frame, target; optionally the textbook
// geometry) to the fitted campaigns, then adds, one at a time, the candidate effect that best lowers the
// time-blocked cross-validated error and the BIC, refitting everything each time, until none helps.
// Writes report.json (effect types from the fixed vocabulary), summary.txt, steps.csv, the extended
// parameter file (parameters.json, with the calibrated URDF beside it) and a plot.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <sys/stat.h>
#include <nlohmann/json.hpp>

#include "cli/campaign_frames.hpp"
#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/output_paths.hpp"
#include "cli/plot.hpp"
#include "cli/robot_setup.hpp"
#include "model/common/errors.hpp"
#include "model/effects/periodic_table.hpp"
#include "model/identify/discovery_report.hpp"
#include "model/identify/kinematic_calibration.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/measurement_campaign.hpp"
#include "model/io/parameter_file.hpp"
#include "model/io/urdf_writer.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp::cli {
namespace {

// --folds: at most one per kMinRowsPerFold rows of the fitted campaigns (300 folds of 300 rows took 4.5 GB).
void checkFoldsFitRows(int folds, const std::vector<MeasurementCampaign>& fitted) {
  std::size_t rows = 0;
  for (const MeasurementCampaign& campaign : fitted) rows += campaign.size();
  if (static_cast<std::size_t>(folds) * kMinRowsPerFold > rows) {
    throw UsageError("--folds: " + std::to_string(folds) + " folds need at least " +
                     std::to_string(folds * kMinRowsPerFold) + " rows; the fitted campaigns have " +
                     std::to_string(rows));
  }
}

// The resolution of the tables, the weights of their priors and the rules of the transfer check.
void readSelectionOptions(const Options& options, DiscoveryOptions& discovery) {
  if (options.has("table-knots")) {
    discovery.table_knots.clear();
    for (double knots : numberList(options.get("table-knots", ""), "table-knots",
                                   {static_cast<double>(PeriodicTableEffect::kMinKnots),
                                    static_cast<double>(PeriodicTableEffect::kMaxKnots)})) {
      if (knots != std::floor(knots))
        throw UsageError("--table-knots: " + std::to_string(knots) + " is not a whole number");
      discovery.table_knots.push_back(static_cast<int>(knots));
    }
  }
  discovery.max_prior_weight = options.number("max-prior-weight", discovery.max_prior_weight, {0.0, 1e6});
  discovery.max_ridge_weight = options.number("max-ridge-weight", discovery.max_ridge_weight, {0.0, 1e6});
  discovery.transfer_significance =
      options.number("transfer-significance", discovery.transfer_significance, {0.0, 100.0});
  discovery.min_group_share = options.number("min-group-share", discovery.min_group_share, {0.0, 0.49});
  discovery.angle_ranges = static_cast<int>(options.integer("angle-ranges", discovery.angle_ranges, 2, 50));
  discovery.pairs = !options.has("no-pairs");
  discovery.heldout_same_instrument = options.has("holdout-same-instrument");
}

// The discovered URDF and parameter file, report.json, steps.csv, summary.txt (printed too) and the plot.
void writeDiscoveryOutputs(const DiscoveryResult& result, const DiscoveryOptions& discovery, const RobotSetup& setup,
                           const MeasurementCampaign& first, const std::vector<std::string>& campaigns,
                           const std::vector<std::string>& holdouts, const std::string& out, double seconds,
                           bool plot) {
  const std::shared_ptr<const Robot>& robot = setup.robot;
  const std::string& urdf = setup.urdf;
  const std::string urdf_out = out + "/" + plainFileName(robot->name) + "_discovered.urdf";
  // The fitted target on the flange: the URDF ends at it (a link of its own), the parameter file says where;
  // the frame the campaigns were measured in (fitted or kept), as calibrate writes it.
  const std::string params_out = out + "/parameters.json";
  const CalibratedFrames frames = calibratedFrames(*robot, first, result.calibration.estimate);
  saveCalibratedRobot(result.model, setup.parameters.drives,  // the prior's drives, if any
                      &frames.tool, frames.base_frame ? &*frames.base_frame : nullptr, urdf_out,
                      "  " + robot->name + " after jointcomp discover\n  nominal: " + urdf +
                          "\n  Joint placements corrected; the chain ends at link '" + frames.tool.link +
                          "', the fitted target; joint offsets, compliance and the discovered effects are in the "
                          "parameter file.",
                      params_out);

  DiscoverySources sources;
  sources.urdf = urdf;
  sources.parameters = setup.params;
  sources.campaigns = campaigns;
  sources.held_out = holdouts;
  sources.outputs = {{"parameters", params_out}, {"urdf", urdf_out}};
  writeFileAtomically(out + "/report.json", discoveryReportJson(result, discovery, sources, seconds).dump(2) + "\n");
  writeFileAtomically(out + "/steps.csv", discoveryStepsCsv(result));
  const std::string summary = discoverySummary(result, discovery, sources) + "Wrote " + params_out + ", " + urdf_out +
                              ", " + out + "/report.json, " + out + "/steps.csv\n";
  writeFileAtomically(out + "/summary.txt", summary);
  std::fputs(summary.c_str(), stdout);
  if (plot) drawPlot("plot_discovery.py", out + "/steps.csv", out + "/discovery.png");
  std::printf("as an FMU: %s\n", exportFmuCommand(urdf_out, params_out, setup.parameters.hasDrives(), robot->name,
                                                  out + "/" + plainFileName(robot->name) + ".fmu")
                                     .c_str());
}

// Every option of the discovery itself, read whole and range-checked.
DiscoveryOptions discoveryOptionsFrom(const Options& options) {
  DiscoveryOptions discovery;
  discovery.calibration.loss = parseRobustLoss(options.get("loss", "huber"));
  discovery.calibration.progress = consoleProgress(options);
  discovery.calibration.fixed = expandedFixNames(splitCommaList(options.get("fix", "")));
  discovery.calibration.limits = geometryLimitsFrom(options);
  const std::string base = options.get("base", "textbook");
  if (base != "frame" && base != "textbook")
    throw std::invalid_argument("--base must be frame or textbook, not '" + base + "'");
  discovery.base_geometry = base == "textbook";
  discovery.max_steps = static_cast<int>(options.integer("max-steps", discovery.max_steps, 0, kMaxDiscoverySteps));
  discovery.max_harmonic_order =
      static_cast<int>(options.integer("orders", discovery.max_harmonic_order, 1, kMaxHarmonicOrder));
  discovery.folds = static_cast<int>(options.integer("folds", discovery.folds, 2, kMaxFolds));
  discovery.min_cv_gain = options.number("min-cv-gain", discovery.min_cv_gain, {0.0, 1.0});
  discovery.noise_floor = options.number("noise-floor-mm", 0.0, {0.0, 1e3}) * 1e-3;
  readSelectionOptions(options, discovery);
  discovery.types = splitCommaList(options.get("types", ""));
  for (const std::string& type : discovery.types) {
    bool known = false;
    for (const std::string& t : discoveryEffectTypes()) known = known || t == type;
    if (!known) throw std::invalid_argument("--types: unknown effect type '" + type + "'");
  }
  return discovery;
}

}  // namespace

int runDiscover(int argc, char** argv) {
  std::vector<std::string> campaigns, holdouts;
  std::vector<char*> rest = {argv[0]};
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--campaign" || arg == "--holdout") {
      if (i + 1 >= argc) throw std::invalid_argument("option " + arg + " needs a value");
      for (const std::string& item : splitCommaList(argv[++i]))
        (arg == "--campaign" ? campaigns : holdouts).push_back(item);
      continue;
    }
    rest.push_back(argv[i]);
  }
  const Options options(static_cast<int>(rest.size()), rest.data(),
                        {"urdf",
                         "base-link",
                         "tip-link",
                         "campaign",
                         "holdout",
                         "params",
                         "out",
                         "base",
                         "max-steps",
                         "orders",
                         "folds",
                         "types",
                         "noise-floor-mm",
                         "loss",
                         "min-cv-gain",
                         "table-knots",
                         "max-prior-weight",
                         "max-ridge-weight",
                         "transfer-significance",
                         "min-group-share",
                         "angle-ranges",
                         "target",
                         "base-frame",
                         "fix",
                         "geometry-limits",
                         "no-pairs",
                         "holdout-same-instrument",
                         "no-plot",
                         "quiet"},
                        {"no-pairs", "holdout-same-instrument", "no-plot", "quiet"});
  if (campaigns.empty() || !options.has("out")) {
    throw std::invalid_argument(
        "discover needs --campaign FILE[,FILE..] and --out DIR (and --urdf, --params, --holdout)");
  }
  const RobotSetup setup = loadRobotSetup(options, robotFile("ur10"));
  const std::string out = options.get("out", "");
  prepareOutputFolder(out);
  const auto started = std::chrono::steady_clock::now();
  const std::shared_ptr<const Robot>& robot = setup.robot;
  const JointErrorModel& prior = setup.parameters.model;
  const DiscoveryOptions discovery = discoveryOptionsFrom(options);
  const std::string base = discovery.base_geometry ? "textbook" : "frame";

  std::vector<MeasurementCampaign> fitted, held;
  for (const std::string& path : campaigns) fitted.push_back(readCampaignFile(path));
  for (const std::string& path : holdouts) held.push_back(readCampaignFile(path));
  checkFoldsFitRows(discovery.folds, fitted);
  std::printf("jointcomp discover: robot %s, %zu fitted and %zu held-out campaign(s), base %s\n", robot->name.c_str(),
              fitted.size(), held.size(), base.c_str());
  if (!setup.assumed().empty()) std::printf("  %s\n", setup.assumed().c_str());
  std::vector<MeasurementCampaign*> held_pointers;
  for (MeasurementCampaign& campaign : held) held_pointers.push_back(&campaign);
  applyCampaignFrames(options, setup, fitted, held_pointers);
  const auto fit_started = std::chrono::steady_clock::now();
  const DiscoveryResult result = discoverEffects(prior, fitted, held, discovery);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - fit_started).count();

  writeDiscoveryOutputs(result, discovery, setup, fitted.front(), campaigns, holdouts, out, seconds,
                        !options.has("no-plot"));

  std::printf("done in %.2f s (discovery %.2f s)\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(), seconds);
  return 0;
}

}  // namespace jointcomp::cli
