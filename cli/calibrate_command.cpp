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

#include "cli/campaign_frames.hpp"
#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/output_paths.hpp"
#include "cli/plot.hpp"
#include "cli/robot_setup.hpp"
#include "model/common/errors.hpp"
#include "model/identify/calibration_report.hpp"
#include "model/identify/kinematic_calibration.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/measurement_campaign.hpp"
#include "model/io/parameter_file.hpp"
#include "model/io/urdf_writer.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp::cli {

namespace {

std::string urdfHeader(const Robot& robot, const std::string& urdf, const std::string& campaign_path,
                       const CalibrationRun& run, const ToolTarget& tool) {
  std::string rigid;
  for (const std::string& item : run.compliance_left_out) {
    rigid += (rigid.empty() ? "" : ", ") + item.substr(0, item.find(':'));
  }
  char target[160];
  std::snprintf(target, sizeof(target), "%.6f, %.6f, %.6f mm", tool.in_flange.x() * 1e3, tool.in_flange.y() * 1e3,
                tool.in_flange.z() * 1e3);
  return "  " + robot.name + " after kinematic calibration by jointcomp calibrate\n  nominal: " + urdf +
         "\n  campaign: " + campaign_path + "\n  Joint placements corrected. The chain ends at link '" + tool.link +
         "', the calibrated target (" + target + " from '" + robot.tip_link +
         "'): campaigns measured with this URDF need no target.\n" +
         "  Joint offsets and compliance are in the parameter file" +
         (rigid.empty() ? std::string(".")
                        : "; it writes the compliance of " + rigid + " as rigid (summary.txt says why).");
}

// --campaign and --holdout may be given more than once (and each may list files separated by commas):
// taken out of the arguments into their lists; the rest is returned for the option parser.
std::vector<char*> takeCampaignArguments(int argc, char** argv, std::vector<std::string>& campaign_paths,
                                         std::vector<std::string>& holdouts) {
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
  return rest;
}

}  // namespace

int runCalibrate(int argc, char** argv) {
  std::vector<std::string> campaign_paths, holdouts;
  std::vector<char*> rest = takeCampaignArguments(argc, argv, campaign_paths, holdouts);
  const Options options(
      static_cast<int>(rest.size()), rest.data(),
      {"urdf", "base-link", "tip-link", "campaign", "holdout", "params", "out", "loss", "loss-scale-mm",
       "pivot-threshold", "fix", "target", "base-frame", "geometry-limits", "no-plot", "quiet"},
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
  calibration.fixed = expandedFixNames(splitCommaList(options.get("fix", "")));
  calibration.limits = geometryLimitsFrom(options);
  calibration.progress = consoleProgress(options);

  std::printf("jointcomp calibrate: robot %s (%s), campaign %s\n", robot->name.c_str(), urdf.c_str(),
              campaign_path.c_str());
  if (!setup.assumed().empty()) std::printf("  %s\n", setup.assumed().c_str());
  std::vector<MeasurementCampaign> campaigns;
  for (const std::string& path : campaign_paths) campaigns.push_back(readCampaignFile(path));
  std::vector<std::pair<std::string, MeasurementCampaign>> held;
  for (const std::string& path : holdouts) held.emplace_back(path, readCampaignFile(path));
  std::vector<MeasurementCampaign*> held_campaigns;
  for (auto& entry : held) held_campaigns.push_back(&entry.second);
  applyCampaignFrames(options, setup, campaigns, held_campaigns);
  const CalibrationRun run = runCalibration(prior, campaigns, held, calibration);

  // The tool point the calibration fitted, in both files: the URDF ends at it (a link of its own, so that
  // kinematics, compensation and the plant work there), the parameter file says where it is on the flange;
  // the frame the campaigns were measured in (fitted or kept): a link fixed to the root, "base_frame".
  const std::string urdf_out = out + "/" + plainFileName(robot->name) + "_calibrated.urdf";  // inside --out
  const std::string params_out = out + "/parameters.json";
  const CalibratedFrames frames = calibratedFrames(*robot, campaigns.front(), run.result.estimate);
  saveCalibratedRobot(run.calibrated, setup.parameters.drives,  // the prior's drives, if any
                      &frames.tool, frames.base_frame ? &*frames.base_frame : nullptr, urdf_out,
                      urdfHeader(*robot, urdf, campaign_path, run, frames.tool), params_out);

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
