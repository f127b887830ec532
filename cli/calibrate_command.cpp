// `jointcomp calibrate`: kinematic calibration (instrument frame, target, joint offsets, joint placements,
// joint compliance) from one measurement campaign or several (from one or more instrument set-ups, a
// frame each), checked on held-out campaigns. Writes the calibrated
// URDF, the updated parameter file, report.json, summary.txt, residuals.csv and a plot.
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

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/output_paths.hpp"
#include "cli/plot.hpp"
#include "cli/robot_setup.hpp"
#include "model/common/errors.hpp"
#include "model/identify/calibration_report.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/measurement_campaign.hpp"
#include "model/io/parameter_file.hpp"
#include "model/io/urdf_writer.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp::cli {

int runCalibrate(int argc, char** argv) {
  // --campaign and --holdout may be given more than once (and each may list files separated by commas).
  std::vector<std::string> campaign_paths, holdouts;
  std::vector<char*> rest = {argv[0]};
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--campaign" || arg == "--holdout") {
      if (i + 1 >= argc) throw std::invalid_argument("option " + arg + " needs a value");
      for (const std::string& item : splitCommaList(argv[++i])) {
        (arg == "--campaign" ? campaign_paths : holdouts).push_back(item);
      }
      continue;
    }
    rest.push_back(argv[i]);
  }
  const Options options(static_cast<int>(rest.size()), rest.data(),
                        {"urdf", "base-link", "tip-link", "campaign", "holdout", "params", "out", "loss",
                         "loss-scale-mm", "pivot-threshold", "fix", "no-plot", "quiet"},
                        {"no-plot", "quiet"});
  if (campaign_paths.empty() || !options.has("out")) {
    throw std::invalid_argument(
        "calibrate needs --campaign CAMPAIGN.csv[,MORE.csv] and --out DIR (and --urdf FILE, --params FILE, "
        "--holdout FILE)");
  }
  const RobotSetup setup = loadRobotSetup(options, robotFile("ur10"));
  const std::string& urdf = setup.urdf;
  std::string campaign_path;  // as the reports name it
  for (const std::string& path : campaign_paths) campaign_path += (campaign_path.empty() ? "" : ",") + path;
  const std::string out = options.get("out", "");
  prepareOutputFolder(out);
  const auto started = std::chrono::steady_clock::now();

  const std::shared_ptr<const Robot>& robot = setup.robot;
  const JointErrorModel& prior = setup.parameters.model;
  GeometricCalibrationOptions calibration;
  calibration.loss = parseRobustLoss(options.get("loss", "huber"));
  // Not given: 0, the automatic scale; given, it must be a positive number (0, -1 and nan fell back to it).
  calibration.loss_scale = options.number("loss-scale-mm", 0.0, {0.0, 1e6, true}) * 1e-3;
  calibration.identifiability.relative_pivot_threshold =
      options.number("pivot-threshold", calibration.identifiability.relative_pivot_threshold, {0.0, 1.0, true});
  calibration.fixed = splitCommaList(options.get("fix", ""));
  calibration.progress = consoleProgress(options);

  std::printf("jointcomp calibrate: robot %s (%s), campaign %s\n", robot->name.c_str(), urdf.c_str(),
              campaign_path.c_str());
  std::vector<MeasurementCampaign> campaigns;
  for (const std::string& path : campaign_paths) campaigns.push_back(readCampaignFile(path));
  std::vector<std::pair<std::string, MeasurementCampaign>> held;
  for (const std::string& path : holdouts) held.emplace_back(path, readCampaignFile(path));
  const CalibrationRun run = runCalibration(prior, campaigns, held, calibration);

  const std::string urdf_out = out + "/" + plainFileName(robot->name) + "_calibrated.urdf";  // inside --out
  saveRobotUrdf(*run.calibrated_robot, urdf_out,
                "  " + robot->name + " after kinematic calibration by jointcomp calibrate\n  nominal: " + urdf +
                    "\n  campaign: " + campaign_path + "\n  Joint placements corrected; " +
                    (run.compliance_left_out.empty()
                         ? std::string("joint offsets and compliance are in the parameter file.")
                         : "joint offsets are in the parameter file, with the compliance of all joints but " +
                               std::to_string(run.compliance_left_out.size()) +
                               ", which it writes as rigid (summary.txt says which and why)."));
  const std::string params_out = out + "/parameters.json";
  saveParameterFile(run.calibrated, params_out, setup.parameters.drives);  // the prior's drives, if any

  CalibrationSources sources;
  sources.urdf = urdf;
  sources.parameters = setup.params;
  sources.campaign = campaign_path;
  sources.campaigns = campaign_paths;
  sources.outputs = {{"urdf", urdf_out}, {"parameters", params_out}, {"residuals", out + "/residuals.csv"}};
  writeFileAtomically(out + "/residuals.csv", calibrationResidualsCsv(run, sources));
  writeFileAtomically(out + "/report.json", calibrationReportJson(run, calibration, sources).dump(2) + "\n");
  const std::string summary = calibrationSummary(run, sources) + "\nWrote " + urdf_out + ", " + params_out + ", " +
                              out + "/report.json, " + out + "/residuals.csv\n";
  writeFileAtomically(out + "/summary.txt", summary);
  std::fputs(summary.c_str(), stdout);

  if (!options.has("no-plot")) drawPlot("plot_calibration.py", out + "/residuals.csv", out + "/calibration.png");
  std::printf("as an FMU: %s\n", exportFmuCommand(urdf_out, params_out, setup.parameters.hasDrives(), robot->name,
                                                  out + "/" + plainFileName(robot->name) + ".fmu")
                                     .c_str());

  std::printf("done in %.2f s\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
  return 0;
}

}  // namespace jointcomp::cli
