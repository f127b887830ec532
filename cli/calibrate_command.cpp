// `jointcomp calibrate`: kinematic calibration (instrument frame, target, joint offsets, joint placements,
// joint compliance) from a measurement campaign, checked on held-out campaigns. Writes the calibrated
// URDF, the updated parameter file, report.json, summary.txt, residuals.csv and a plot.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <sys/stat.h>

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "model/common/errors.hpp"
#include "model/identify/geometric_calibration.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/measurement_campaign.hpp"
#include "model/io/parameter_file.hpp"
#include "model/io/urdf_writer.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp::cli {
namespace {

std::string baseName(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

nlohmann::ordered_json statisticsJson(const ErrorStatistics& s) {
  return {{"rows", s.rows}, {"mean_mm", s.mean * 1e3}, {"rms_mm", s.rms * 1e3}, {"max_mm", s.max * 1e3}};
}

std::string tableRow(const std::string& name, int rows, const ErrorStatistics& before, const ErrorStatistics& after) {
  char line[256];
  std::snprintf(line, sizeof(line), "%-34s %6d  %7.3f %7.3f %7.3f   %7.3f %7.3f %7.3f\n", name.c_str(), rows,
                before.mean * 1e3, before.rms * 1e3, before.max * 1e3, after.mean * 1e3, after.rms * 1e3,
                after.max * 1e3);
  return line;
}

struct HoldoutRun {
  std::string path;
  HoldoutEvaluation before, after, shared_frame;
};

std::string parameterLine(const ParameterEstimate& p) {
  const bool angle = p.unit == "rad";
  const bool length = p.unit == "m";
  const double scale = length ? 1e3 : angle ? 180.0 / 3.14159265358979323846 : 1.0;
  const char* unit = length ? "mm" : angle ? "deg" : "rad/(N m)";
  char line[320];
  if (p.identified) {
    std::snprintf(line, sizeof(line), "  %-34s %14.6g +- %-10.3g %s (nominal %.6g)\n", p.name.c_str(),
                  p.value * scale, p.sigma * scale, unit, p.nominal * scale);
  } else {
    std::snprintf(line, sizeof(line), "  %-34s fixed at %.6g %s: %s\n", p.name.c_str(), p.value * scale, unit,
                  p.fixed_because.c_str());
  }
  return line;
}

}  // namespace

int runCalibrate(int argc, char** argv) {
  // --holdout may be given more than once (and each may list files separated by commas).
  std::vector<std::string> holdouts;
  std::vector<char*> rest = {argv[0]};
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--holdout") {
      if (i + 1 >= argc) throw std::invalid_argument("option --holdout needs a value");
      for (const std::string& item : splitCommaList(argv[++i])) holdouts.push_back(item);
      continue;
    }
    rest.push_back(argv[i]);
  }
  const Options options(static_cast<int>(rest.size()), rest.data(),
                        {"urdf", "campaign", "params", "out", "loss", "loss-scale-mm", "pivot-threshold", "fix",
                         "no-plot"},
                        {"no-plot"});
  if (!options.has("campaign") || !options.has("out")) {
    throw std::invalid_argument(
        "calibrate needs --campaign CAMPAIGN.csv and --out DIR (and --urdf FILE, --params FILE, --holdout FILE)");
  }
  const std::string urdf = options.get("urdf", JOINTCOMP_DATA_DIR "/robots/ur10.urdf");
  const std::string campaign_path = options.get("campaign", "");
  const std::string out = options.get("out", "");
  const auto started = std::chrono::steady_clock::now();

  auto robot = std::make_shared<const Robot>(loadRobotFromUrdfFile(urdf));
  const bool has_params = options.has("params");
  const JointErrorModel prior = has_params ? loadParameterFile(options.get("params", ""), robot)
                                           : JointErrorModel(robot, GearTrain::direct(robot->dof()), {});
  GeometricCalibrationOptions calibration;
  calibration.loss = parseRobustLoss(options.get("loss", "huber"));
  if (options.has("loss-scale-mm")) calibration.loss_scale = std::stod(options.get("loss-scale-mm", "0")) * 1e-3;
  if (options.has("pivot-threshold")) {
    calibration.identifiability.relative_pivot_threshold = std::stod(options.get("pivot-threshold", "1e-4"));
  }
  calibration.fixed = splitCommaList(options.get("fix", ""));

  std::printf("jointcomp calibrate: robot %s (%s), campaign %s\n", robot->name.c_str(), urdf.c_str(),
              campaign_path.c_str());
  const MeasurementCampaign campaign = readCampaignFile(campaign_path);
  const auto fit_started = std::chrono::steady_clock::now();
  const GeometricCalibrationResult result = calibrateGeometry(prior, campaign, calibration);
  const double fit_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - fit_started).count();

  std::vector<HoldoutRun> runs;
  for (const std::string& path : holdouts) {
    const MeasurementCampaign held = readCampaignFile(path);
    HoldoutRun run;
    run.path = path;
    run.before = evaluateOnCampaign(prior, nominalParameters(prior, held), held, true, calibration);
    run.after = evaluateOnCampaign(prior, result.estimate, held, true, calibration);
    run.shared_frame = evaluateOnCampaign(prior, result.estimate, held, false, calibration);
    runs.push_back(run);
  }

  // Outputs.
  ::mkdir(out.c_str(), 0755);
  auto calibrated_robot = std::make_shared<const Robot>(correctedRobot(*robot, result.estimate));
  const std::string urdf_out = out + "/" + robot->name + "_calibrated.urdf";
  saveRobotUrdf(*calibrated_robot, urdf_out,
                "  " + robot->name + " after kinematic calibration by jointcomp calibrate\n  nominal: " + urdf +
                    "\n  campaign: " + campaign_path +
                    "\n  Joint placements corrected; joint offsets and compliance are in the parameter file.");
  std::vector<std::string> left_out;
  const JointErrorModel calibrated = calibratedJointErrorModel(prior, calibrated_robot, result, left_out);
  std::vector<DriveParameters> drives;
  if (has_params) {
    try {
      drives = loadDriveParameters(options.get("params", ""), *robot);
    } catch (const ParameterError&) {
      drives.clear();  // the prior has no plant section: none is written
    }
  }
  const std::string params_out = out + "/parameters.json";
  saveParameterFile(calibrated, params_out, drives);

  // residuals.csv: one line per used row of every campaign.
  std::ostringstream csv;
  csv.precision(9);
  csv << "campaign,role,row,before_mm,after_mm,weight\n";
  for (std::size_t k = 0; k < result.row.size(); ++k) {
    csv << baseName(campaign_path) << ",calibration," << result.row[k] << ',' << result.error_before[k] * 1e3 << ','
        << result.error_after[k] * 1e3 << ',' << result.weight[k] << "\n";
  }
  for (const HoldoutRun& run : runs) {
    for (std::size_t k = 0; k < run.after.row.size(); ++k) {
      csv << baseName(run.path) << ",holdout," << run.after.row[k] << ',' << run.before.error[k] * 1e3 << ','
          << run.after.error[k] * 1e3 << ',' << run.after.weight[k] << "\n";
    }
  }
  writeFileAtomically(out + "/residuals.csv", csv.str());

  // report.json
  nlohmann::ordered_json report;
  report["format"] = "jointcomp-calibration-report/1";
  report["robot"] = robot->name;
  report["urdf"] = urdf;
  report["params"] = has_params ? nlohmann::ordered_json(options.get("params", "")) : nlohmann::ordered_json(nullptr);
  report["campaign"] = campaign_path;
  report["model"] =
      "measured = Exp(frame_r) * FK(q_cmd + offset - compliance .* tau(q_cmd) + other effects) * target + frame_t; "
      "joint placements corrected by placement * Trans(d) * Exp(r)";
  report["solver"] = {{"method", "Levenberg-Marquardt (dense, Eigen), robust loss by IRLS"},
                      {"iterations", result.iterations},
                      {"stop_reason", result.stop_reason},
                      {"seconds", fit_seconds}};
  report["rows"] = {{"total", campaign.size()},
                    {"used", result.used_rows},
                    {"skipped_not_measured", result.skipped_rows},
                    {"downweighted", result.downweighted_rows},
                    {"downweighted_below_half", result.outlier_rows}};
  report["loss"] = {{"type", robustLossName(result.loss)}, {"scale_mm", result.loss_scale * 1e3}};
  report["residual_sigma_per_axis_mm"] = result.residual_sigma * 1e3;
  report["identifiability"] = {{"relative_pivot_threshold", calibration.identifiability.relative_pivot_threshold},
                               {"identified", result.free.size()},
                               {"fixed", result.names.size() - result.free.size()},
                               {"condition_number_at_start", result.condition_number_at_start},
                               {"condition_number", result.condition_number}};
  nlohmann::ordered_json parameters = nlohmann::ordered_json::array();
  for (const ParameterEstimate& p : result.parameters) {
    nlohmann::ordered_json entry = {{"name", p.name}, {"unit", p.unit}, {"nominal", p.nominal}, {"value", p.value},
                                    {"identified", p.identified}, {"pivot", p.pivot}};
    if (p.identified) {
      entry["sigma"] = p.sigma;
    } else {
      entry["fixed_because"] = p.fixed_because;
      nlohmann::ordered_json with = nlohmann::ordered_json::array();
      for (const auto& r : p.redundant_with) with.push_back({{"name", r.first}, {"ratio", r.second}});
      if (!with.empty()) entry["redundant_with"] = with;
    }
    parameters.push_back(entry);
  }
  report["parameters"] = parameters;
  report["compliance_left_out"] = left_out;
  nlohmann::ordered_json campaigns = nlohmann::ordered_json::array();
  campaigns.push_back({{"file", campaign_path},
                       {"role", "calibration"},
                       {"rows", result.used_rows},
                       {"before", statisticsJson(result.before)},
                       {"after", statisticsJson(result.after)},
                       {"downweighted_rows", result.downweighted_rows},
                       {"downweighted_below_half_rows", result.outlier_rows}});
  for (const HoldoutRun& run : runs) {
    campaigns.push_back({{"file", run.path},
                         {"role", "holdout (robot fixed, instrument frame re-fitted)"},
                         {"rows", run.after.statistics.rows},
                         {"skipped_not_measured", run.after.skipped_rows},
                         {"before", statisticsJson(run.before.statistics)},
                         {"after", statisticsJson(run.after.statistics)},
                         {"downweighted_rows", run.after.downweighted_rows},
                         {"downweighted_below_half_rows", run.after.outlier_rows},
                         {"after_with_calibration_frame", statisticsJson(run.shared_frame.statistics)}});
  }
  report["campaigns"] = campaigns;
  report["outputs"] = {{"urdf", urdf_out}, {"parameters", params_out}, {"residuals", out + "/residuals.csv"}};
  writeFileAtomically(out + "/report.json", report.dump(2) + "\n");

  // summary.txt and the console.
  std::ostringstream summary;
  summary << "Kinematic calibration of " << robot->name << " on " << campaign_path << "\n";
  char line[512];
  std::snprintf(line, sizeof(line),
                "%d rows used, %d skipped (no measured position), %d down-weighted by the %s loss (scale %.3f mm), "
                "%d of them below half weight\n",
                result.used_rows, result.skipped_rows, result.downweighted_rows, robustLossName(result.loss),
                result.loss_scale * 1e3, result.outlier_rows);
  summary << line;
  std::snprintf(line, sizeof(line),
                "%zu of %zu parameters identified; condition number of the scaled Jacobian %.3g (at the start %.3g); "
                "residual sigma %.4f mm per axis; %d LM iterations, %.2f s\n",
                result.free.size(), result.names.size(), result.condition_number, result.condition_number_at_start,
                result.residual_sigma * 1e3, result.iterations, fit_seconds);
  summary << line;
  summary << "\n3-D error [mm]                      rows     before (nominal, frame fitted)   after (calibrated)\n";
  summary << "                                           mean     rms     max      mean     rms     max\n";
  summary << tableRow(baseName(campaign_path) + " (calibration)", result.used_rows, result.before, result.after);
  for (const HoldoutRun& run : runs) {
    summary << tableRow(baseName(run.path) + " (held out, frame re-fitted)", run.after.statistics.rows,
                        run.before.statistics, run.after.statistics);
  }
  for (const HoldoutRun& run : runs) {
    std::snprintf(line, sizeof(line),
                  "%s: %d rows down-weighted in its frame fit (scale %.3f mm), %d of them below half weight\n",
                  baseName(run.path).c_str(), run.after.downweighted_rows, run.after.loss_scale * 1e3,
                  run.after.outlier_rows);
    summary << line;
    std::snprintf(line, sizeof(line),
                  "%s with the calibration campaign's frame (not re-fitted): RMS %.3f mm%s\n", baseName(run.path).c_str(),
                  run.shared_frame.statistics.rms * 1e3,
                  run.shared_frame.statistics.rms > 3.0 * run.after.statistics.rms + 1e-4
                      ? ": the campaigns do not share the instrument frame"
                      : ": the campaigns share the instrument frame");
    summary << line;
  }
  summary << "\nIdentified parameters (1 sigma):\n";
  for (const ParameterEstimate& p : result.parameters) {
    if (p.identified) summary << parameterLine(p);
  }
  summary << "\nFixed parameters:\n";
  for (const ParameterEstimate& p : result.parameters) {
    if (!p.identified) summary << parameterLine(p);
  }
  if (!left_out.empty()) {
    summary << "\nCompliance effect NOT written to the parameter file (the effect needs a positive stiffness for "
               "every joint; pass --params with a compliance effect to supply the missing ones):\n";
    for (const std::string& item : left_out) summary << "  " << item << "\n";
  }
  summary << "\nWrote " << urdf_out << ", " << params_out << ", " << out << "/report.json, " << out
          << "/residuals.csv\n";
  writeFileAtomically(out + "/summary.txt", summary.str());
  std::fputs(summary.str().c_str(), stdout);

  if (!options.has("no-plot")) {
    const std::string command = "/usr/bin/python3 '" JOINTCOMP_SOURCE_DIR "/cli/plots/plot_calibration.py' '" + out +
                                "/residuals.csv' '" + out + "/calibration.png'";
    if (std::system(command.c_str()) == 0) {
      std::printf("wrote %s/calibration.png\n", out.c_str());
    } else {
      std::printf("no plot: %s failed (needs Debian's python3-matplotlib)\n", command.c_str());
    }
  }
  std::printf("done in %.2f s\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
  return 0;
}

}  // namespace jointcomp::cli
