// Identification, calibration and discovery behind the C API: campaign files in, a new robot handle and a
// report handle out. The work is the model's (model/identify); this file reads the options, runs it, and
// builds the reports with the same functions as the command-line tool, so both give the same documents.
#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "api_support.hpp"
#include "json_options.hpp"
#include "model/common/json_fields.hpp"
#include "model/common/strict_json.hpp"
#include "model/experiment/campaign_simulation.hpp"
#include "model/identify/calibration_report.hpp"
#include "model/identify/discovery_report.hpp"
#include "model/identify/identification_report.hpp"
#include "model/identify/kinematic_calibration.hpp"
#include "model/io/measurement_campaign.hpp"
#include "model/io/parameter_file.hpp"
#include "model/io/urdf_writer.hpp"

using namespace jointcomp;
using namespace jointcomp::capi;

namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

int positiveInteger(JsonFields& fields, const std::string& key) {
  const int value = fields.integer(key);
  if (value < 1) fields.fail(key, "must be at least 1");
  return value;
}

RobustLoss lossOption(JsonFields& fields) {
  const std::string name = fields.text("loss");
  if (name != "none" && name != "huber" && name != "cauchy")
    fields.fail("loss", "must be \"huber\", \"cauchy\" or \"none\"");
  return parseRobustLoss(name);
}

// "max_offset_deg", "max_placement_shift_mm", "max_placement_turn_deg": how far the fitted geometry may go
// (GeometryLimits; the defaults where not given).
void readGeometryLimits(JsonFields& fields, GeometryLimits& limits) {
  if (fields.has("max_offset_deg")) limits.offset = fields.positiveNumber("max_offset_deg") * kDegree;
  if (fields.has("max_placement_shift_mm"))
    limits.placement_shift = fields.positiveNumber("max_placement_shift_mm") * 1e-3;
  if (fields.has("max_placement_turn_deg"))
    limits.placement_turn = fields.positiveNumber("max_placement_turn_deg") * kDegree;
}

std::vector<std::string> textList(JsonFields& fields, const std::string& key) {
  std::vector<std::string> items;
  const nlohmann::json& array = fields.array(key);
  for (std::size_t k = 0; k < array.size(); ++k) {
    if (!array[k].is_string()) fields.fail(key, "item " + std::to_string(k) + " is not a string");
    items.push_back(array[k].get<std::string>());
  }
  return items;
}

// A newline-separated list of paths ("\r\n" tolerated, blank lines skipped).
std::vector<std::string> pathList(const char* paths, const char* name, bool required) {
  std::vector<std::string> items;
  if (!paths) {
    if (required) invalid(std::string(name) + " is NULL");
    return items;
  }
  std::string current;
  for (const char* c = paths;; ++c) {
    if (*c == '\n' || *c == '\0') {
      if (!current.empty() && current.back() == '\r') current.pop_back();
      if (!current.empty()) items.push_back(current);
      current.clear();
      if (*c == '\0') break;
    } else {
      current.push_back(*c);
    }
  }
  if (required && items.empty()) invalid(std::string(name) + " names no file");
  return items;
}

std::string robotSource(const jc_robot& handle) { return handle.robot->name + " (a jc_robot handle)"; }

// Hands the results over only when everything has succeeded, so that a failed call leaves the outputs
// untouched.
void deliver(std::unique_ptr<jc_robot> robot, jc_robot** robot_out, std::unique_ptr<jc_report> report,
             jc_report** report_out) {
  if (robot_out) *robot_out = publish(std::move(robot));
  if (report_out) *report_out = publish(std::move(report));
}

// The tables' knots, the priors' largest weights and the transfer check's settings (discovery.hpp); the
// library checks their ranges.
void readSelectionOptions(JsonFields& fields, DiscoveryOptions& options) {
  if (fields.has("table_knots")) {
    options.table_knots.clear();
    for (double knots : fields.numbers("table_knots")) {
      if (knots != std::floor(knots) || knots < 1 || knots > 1e6) fields.fail("table_knots", "must be whole numbers");
      options.table_knots.push_back(static_cast<int>(knots));
    }
  }
  if (fields.has("max_prior_weight")) options.max_prior_weight = fields.nonNegativeNumber("max_prior_weight");
  if (fields.has("max_ridge_weight")) options.max_ridge_weight = fields.nonNegativeNumber("max_ridge_weight");
  if (fields.has("transfer_significance"))
    options.transfer_significance = fields.nonNegativeNumber("transfer_significance");
  if (fields.has("min_group_share")) options.min_group_share = fields.nonNegativeNumber("min_group_share");
  if (fields.has("angle_ranges")) options.angle_ranges = fields.integer("angle_ranges");
  options.pairs = fields.flagOr("pairs", options.pairs);
}

}  // namespace

extern "C" {

jc_status jc_robot_save(jc_robot* robot, const char* urdf_path, const char* parameter_path) {
  return CAPI_ENTRY({
    const jc_robot& handle = robotHandle(robot);
    if (!urdf_path && !parameter_path) invalid("urdf_path and parameter_path are both NULL: nothing to save");
    if (urdf_path && !*urdf_path) invalid("urdf_path is empty");
    if (parameter_path && !*parameter_path) invalid("parameter_path is empty");
    // The URDF of the handle's chain (it ends where the handle's does), with the instrument's frame as a link
    // fixed to the root; the parameter file with the target and that frame.
    saveCalibratedRobot(handle.model, handle.drives, nullptr, handle.base_frame ? &*handle.base_frame : nullptr,
                        urdf_path ? urdf_path : "", "  written by jc_robot_save", "");
    if (parameter_path) {
      saveParameterFile(handle.model, parameter_path, handle.drives, handle.tool ? &*handle.tool : nullptr,
                        handle.base_frame ? &*handle.base_frame : nullptr);
    }
  });
}

jc_status jc_simulate_campaign(jc_robot* truth, const char* options_json, const char* campaign_path) {
  return CAPI_ENTRY({
    const jc_robot& handle = robotHandle(truth, "truth");
    const std::string path = requireText(campaign_path, "campaign_path");
    if (path.empty()) invalid("campaign_path is empty");
    CampaignSimulationSpec spec;
    readOptions(options_json, [&](JsonFields& fields) {
      if (!fields.has("protocol")) {
        fields.fail("protocol", "is required: stiffness, joint-sweep, joint2-sweep, back-and-forth, spiral or random");
      }
      spec = defaultCampaignSpec(protocolFromName(fields.text("protocol")));
      if (fields.has("seed")) {
        const double seed = fields.number("seed");
        if (seed < 0.0 || seed != static_cast<double>(static_cast<std::uint64_t>(seed)) ||
            seed > 9.007199254740992e15) {
          fields.fail("seed", "must be a whole number from 0 to 2^53");
        }
        spec.seed = static_cast<std::uint64_t>(seed);
      }
      spec.noise = fields.flagOr("noise", true);
      if (fields.flagOr("plant", false)) {
        if (handle.drives.empty())
          fields.fail("plant", "needs drives: the robot's parameters have no \"plant\" object");
        spec.drives = handle.drives;
      }
      const int dof = handle.robot->dof();
      if (fields.has("joint")) {
        const int joint = positiveInteger(fields, "joint");
        if (joint > dof) fields.fail("joint", "the robot has " + std::to_string(dof) + " joints");
        spec.sweep.joint = joint - 1;
      }
      if (fields.has("from_deg")) spec.sweep.from_rad = fields.number("from_deg") * kDegree;
      if (fields.has("to_deg")) spec.sweep.to_rad = fields.number("to_deg") * kDegree;
      if (fields.has("step_deg")) spec.sweep.step_rad = fields.positiveNumber("step_deg") * kDegree;
      if (fields.has("settle_s")) spec.sweep.settle_s = fields.nonNegativeNumber("settle_s");
      if (fields.has("cycles")) spec.sweep.cycles = positiveInteger(fields, "cycles");
      if (fields.has("count")) spec.random.count = positiveInteger(fields, "count");
      if (fields.has("warm_up")) {
        const std::vector<double> warm_up = fields.numbers("warm_up");
        if (warm_up.empty() || warm_up.size() > 3)
          fields.fail("warm_up", "takes [rise_degc, time_constant_s, start_degc] (1 to 3 numbers)");
        spec.temperature.enabled = true;
        spec.temperature.rise_degc = warm_up[0];
        if (warm_up.size() > 1) spec.temperature.time_constant_s = warm_up[1];
        if (warm_up.size() > 2) spec.temperature.start_degc = warm_up[2];
        if (!(spec.temperature.time_constant_s > 0.0)) fields.fail("warm_up", "the time constant must be positive");
      }
      if (fields.has("pose_deg")) {
        const std::vector<double> pose = fields.numbers("pose_deg", dof);
        JointVector q(dof);
        for (int j = 0; j < dof; ++j) q[j] = pose[static_cast<std::size_t>(j)] * kDegree;
        spec.stiffness.pose = q;
        spec.sweep.pose = q;
      }
    });
    // Refused before a simulation that may take minutes: a campaign file the call could not write.
    const std::filesystem::path folder = std::filesystem::path(path).parent_path();
    std::error_code ignored;
    if (!folder.empty() && !std::filesystem::is_directory(folder, ignored)) {
      throw ApiError(JC_ERROR_FILE, "campaign_path: the folder '" + folder.string() + "' does not exist");
    }
    spec.metadata["truth"] = robotSource(handle) + ", through jc_simulate_campaign";
    writeCampaignFile(simulateCampaign(handle.model, spec), path);
  });
}

jc_status jc_identify_stiffness(jc_robot* nominal, const char* campaign_path, const char* options_json,
                                jc_robot** identified, jc_report** report) {
  return CAPI_ENTRY({
    const jc_robot& handle = robotHandle(nominal, "nominal");
    const std::string path = requireText(campaign_path, "campaign_path");
    std::string method = "local";
    readOptions(options_json, [&](JsonFields& fields) {
      method = fields.textOr("method", "local");
      if (method != "local" && method != "global") fields.fail("method", "must be \"local\" or \"global\"");
    });
    const MeasurementCampaign campaign = readCampaignFile(path);
    const StiffnessIdentificationResult result = identifyStiffness(handle.model, campaign);
    ReportSources sources;
    sources.campaign = path;
    sources.parameters = robotSource(handle);
    sources.robot = handle.robot->name;
    sources.method_used = method;
    auto updated = std::make_unique<jc_robot>(
        handle.robot, withIdentifiedStiffness(handle.model, result, method == "global", path), handle.drives);
    auto made = std::make_unique<jc_report>(stiffnessReportJson(result, sources, nullptr).dump(2),
                                            stiffnessSummary(result, sources, nullptr));
    deliver(std::move(updated), identified, std::move(made), report);
  });
}

jc_status jc_identify_transmission_error(jc_robot* nominal, const char* campaign_path, const char* options_json,
                                         jc_robot** identified, jc_report** report) {
  return CAPI_ENTRY({
    const jc_robot& handle = robotHandle(nominal, "nominal");
    const std::string path = requireText(campaign_path, "campaign_path");
    TransmissionIdentificationOptions options;
    readOptions(options_json, [&](JsonFields& fields) {
      const int dof = handle.robot->dof();
      if (fields.has("joint")) {
        const int joint = positiveInteger(fields, "joint");
        if (joint > dof) fields.fail("joint", "the robot has " + std::to_string(dof) + " joints");
        options.joint = joint - 1;
      }
      if (fields.has("stage")) options.stage = positiveInteger(fields, "stage");
      if (fields.has("orders")) {
        options.candidate_orders = fields.numbers("orders");
        if (options.candidate_orders.empty()) fields.fail("orders", "is empty");
        for (double order : options.candidate_orders) {
          if (!(order > 0.0)) fields.fail("orders", "every order must be positive");
        }
      }
    });
    const MeasurementCampaign campaign = readCampaignFile(path);
    const TransmissionIdentificationResult result = identifyTransmissionError(handle.model, campaign, options);
    ReportSources sources;
    sources.campaign = path;
    sources.parameters = robotSource(handle);
    sources.robot = handle.robot->name;
    auto updated =
        std::make_unique<jc_robot>(handle.robot, withIdentifiedHarmonics(handle.model, result, path), handle.drives);
    auto made = std::make_unique<jc_report>(transmissionReportJson(result, sources, nullptr).dump(2),
                                            transmissionSummary(result, sources, nullptr));
    deliver(std::move(updated), identified, std::move(made), report);
  });
}

jc_status jc_calibrate(jc_robot* nominal, const char* campaign_path, const char* holdout_paths,
                       const char* options_json, jc_robot** calibrated, jc_report** report) {
  return CAPI_ENTRY({
    const jc_robot& handle = robotHandle(nominal, "nominal");
    // One path, or several separated by newlines (campaigns from one or several instrument set-ups).
    const std::vector<std::string> paths = pathList(campaign_path, "campaign_path", true);
    const std::vector<std::string> holdouts = pathList(holdout_paths, "holdout_paths", false);
    GeometricCalibrationOptions options;
    readOptions(options_json, [&](JsonFields& fields) {
      if (fields.has("loss")) options.loss = lossOption(fields);
      if (fields.has("loss_scale_mm")) options.loss_scale = fields.positiveNumber("loss_scale_mm") * 1e-3;
      if (fields.has("pivot_threshold")) {
        options.identifiability.relative_pivot_threshold = fields.positiveNumber("pivot_threshold");
      }
      if (fields.has("fixed")) options.fixed = textList(fields, "fixed");
      readGeometryLimits(fields, options.limits);
    });
    std::vector<MeasurementCampaign> campaigns;
    std::string joined;
    for (const std::string& path : paths) {
      campaigns.push_back(readCampaignFile(path));
      joined += (joined.empty() ? "" : ",") + path;
    }
    std::vector<std::pair<std::string, MeasurementCampaign>> held;
    for (const std::string& name : holdouts) held.emplace_back(name, readCampaignFile(name));
    options.progress = threadProgress();
    CalibrationRun run = runCalibration(handle.model, campaigns, held, options);
    CalibrationSources sources;
    sources.urdf = robotSource(handle);
    sources.parameters = robotSource(handle);
    sources.campaign = joined;
    sources.campaigns = paths;
    auto made = std::make_unique<jc_report>(calibrationReportJson(run, options, sources).dump(2),
                                            calibrationSummary(run, sources));
    auto updated = std::make_unique<jc_robot>(run.calibrated_robot, std::move(run.calibrated), handle.drives);
    const CalibratedFrames frames = calibratedFrames(*handle.robot, campaigns.front(), run.result.estimate);
    updated->tool = frames.tool;
    updated->base_frame = frames.base_frame;
    deliver(std::move(updated), calibrated, std::move(made), report);
  });
}

jc_status jc_discover(jc_robot* nominal, const char* campaign_paths, const char* holdout_paths,
                      const char* options_json, jc_robot** extended, jc_report** report) {
  return CAPI_ENTRY({
    const jc_robot& handle = robotHandle(nominal, "nominal");
    const std::vector<std::string> campaigns = pathList(campaign_paths, "campaign_paths", true);
    const std::vector<std::string> holdouts = pathList(holdout_paths, "holdout_paths", false);
    DiscoveryOptions options;
    options.base_geometry = true;  // as `jointcomp discover`: from the textbook calibration
    readOptions(options_json, [&](JsonFields& fields) {
      readSelectionOptions(fields, options);
      if (fields.has("base")) {
        const std::string base = fields.text("base");
        if (base != "frame" && base != "textbook") fields.fail("base", "must be \"frame\" or \"textbook\"");
        options.base_geometry = base == "textbook";
      }
      if (fields.has("max_steps")) options.max_steps = positiveInteger(fields, "max_steps");
      if (fields.has("max_harmonic_order")) options.max_harmonic_order = positiveInteger(fields, "max_harmonic_order");
      if (fields.has("folds")) {
        options.folds = fields.integer("folds");
        if (options.folds < 2) fields.fail("folds", "must be at least 2");
      }
      if (fields.has("min_cv_gain")) options.min_cv_gain = fields.nonNegativeNumber("min_cv_gain");
      if (fields.has("noise_floor_mm")) options.noise_floor = fields.nonNegativeNumber("noise_floor_mm") * 1e-3;
      if (fields.has("loss")) options.calibration.loss = lossOption(fields);
      readGeometryLimits(fields, options.calibration.limits);
      if (fields.has("types")) {
        options.types = textList(fields, "types");
        for (const std::string& type : options.types) {
          bool known = false;
          for (const std::string& t : discoveryEffectTypes()) known = known || t == type;
          if (!known) fields.fail("types", "unknown effect type '" + type + "'");
        }
      }
    });
    std::vector<MeasurementCampaign> fitted, held;
    for (const std::string& name : campaigns) fitted.push_back(readCampaignFile(name));
    for (const std::string& name : holdouts) held.push_back(readCampaignFile(name));
    const auto started = std::chrono::steady_clock::now();
    options.calibration.progress = threadProgress();
    DiscoveryResult result = discoverEffects(handle.model, fitted, held, options);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    DiscoverySources sources;
    sources.urdf = robotSource(handle);
    sources.parameters = robotSource(handle);
    sources.campaigns = campaigns;
    sources.held_out = holdouts;
    auto made = std::make_unique<jc_report>(discoveryReportJson(result, options, sources, seconds).dump(2),
                                            discoverySummary(result, options, sources));
    const CalibratedFrames frames = calibratedFrames(*handle.robot, fitted.front(), result.calibration.estimate);
    auto updated = std::make_unique<jc_robot>(result.model.sharedRobot(), std::move(result.model), handle.drives);
    updated->tool = frames.tool;
    updated->base_frame = frames.base_frame;
    deliver(std::move(updated), extended, std::move(made), report);
  });
}

jc_status jc_report_json(jc_report* report, char* buffer, int32_t capacity, int32_t* length) {
  return CAPI_ENTRY({ copyText(reportHandle(report).json, buffer, capacity, length); });
}

jc_status jc_report_summary(jc_report* report, char* buffer, int32_t capacity, int32_t* length) {
  return CAPI_ENTRY({ copyText(reportHandle(report).summary, buffer, capacity, length); });
}

jc_status jc_report_free(jc_report* report) {
  return CAPI_ENTRY({ freeHandle(report, "report"); });
}

}  // extern "C"
