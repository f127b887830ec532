#include "model/identify/calibration_report.hpp"

#include <chrono>
#include <cstdio>
#include <sstream>

namespace jointcomp {
namespace {

std::string baseName(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

std::string tableRow(const std::string& name, int rows, const ErrorStatistics& before, const ErrorStatistics& after) {
  char line[256];
  std::snprintf(line, sizeof(line), "%-34s %6d  %7.3f %7.3f %7.3f   %7.3f %7.3f %7.3f\n", name.c_str(), rows,
                before.mean * 1e3, before.rms * 1e3, before.max * 1e3, after.mean * 1e3, after.rms * 1e3,
                after.max * 1e3);
  return line;
}

std::string parameterLine(const ParameterEstimate& p) {
  // The value in the unit its name says (target.x_m in m: the names of --fix and report.json), then in the
  // unit people read (mm, deg, ppm).
  const bool angle = p.unit == "rad";
  const bool length = p.unit == "m";
  const bool ratio = p.unit == "1";  // the instrument's scale
  const double scale = length ? 1e3 : angle ? 180.0 / 3.14159265358979323846 : ratio ? 1e6 : 1.0;
  const char* unit = length ? "mm" : angle ? "deg" : ratio ? "ppm" : "";
  const std::string si_unit = p.unit == "1" ? "" : p.unit;
  char line[400];
  if (p.identified) {
    if (*unit) {
      std::snprintf(line, sizeof(line), "  %-34s %13.6g +- %-9.3g %-4s = %.6g +- %.3g %s (nominal %.6g %s)\n",
                    p.name.c_str(), p.value, p.sigma, si_unit.c_str(), p.value * scale, p.sigma * scale, unit,
                    p.nominal * scale, unit);
    } else {
      std::snprintf(line, sizeof(line), "  %-34s %13.6g +- %-9.3g %s (nominal %.6g)\n", p.name.c_str(), p.value,
                    p.sigma, si_unit.c_str(), p.nominal);
    }
  } else if (*unit) {
    std::snprintf(line, sizeof(line), "  %-34s fixed at %.6g %s = %.6g %s: %s\n", p.name.c_str(), p.value,
                  si_unit.c_str(), p.value * scale, unit, p.fixed_because.c_str());
  } else {
    std::snprintf(line, sizeof(line), "  %-34s fixed at %.6g %s: %s\n", p.name.c_str(), p.value, si_unit.c_str(),
                  p.fixed_because.c_str());
  }
  return line;
}

}  // namespace

nlohmann::ordered_json errorStatisticsJson(const ErrorStatistics& s) {
  return {{"rows", s.rows}, {"mean_mm", s.mean * 1e3}, {"rms_mm", s.rms * 1e3}, {"max_mm", s.max * 1e3}};
}

CalibrationRun runCalibration(const JointErrorModel& prior, const MeasurementCampaign& campaign,
                              const std::vector<std::pair<std::string, MeasurementCampaign>>& holdouts,
                              const GeometricCalibrationOptions& options) {
  return runCalibration(prior, std::vector<MeasurementCampaign>{campaign}, holdouts, options);
}

CalibrationRun runCalibration(const JointErrorModel& prior, const std::vector<MeasurementCampaign>& campaigns,
                              const std::vector<std::pair<std::string, MeasurementCampaign>>& holdouts,
                              const GeometricCalibrationOptions& options) {
  const auto started = std::chrono::steady_clock::now();
  GeometricCalibrationResult result = calibrateGeometry(prior, campaigns, options);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  // After: what the written files give (the calibrated robot's load torques), as the fitted rows' figures.
  const CalibratedView written =
      options.calibrated_torques ? asWritten(prior, result.estimate) : CalibratedView{prior, result.estimate};
  std::vector<CalibrationHoldoutRun> runs;
  for (const auto& [name, held] : holdouts) {
    CalibrationHoldoutRun run;
    run.name = name;
    run.before = evaluateOnCampaign(prior, nominalParameters(prior, held), held, true, options);
    run.after = evaluateOnCampaign(written.model, written.parameters, held, true, options);
    run.shared_frame = evaluateOnCampaign(written.model, written.parameters, held, false, options);
    run.residual = rowResiduals(written.model, run.after.parameters, held);
    runs.push_back(std::move(run));
  }
  auto calibrated_robot = std::make_shared<const Robot>(correctedRobot(prior.robot(), result.estimate));
  std::vector<std::string> left_out;
  JointErrorModel calibrated = calibratedJointErrorModel(prior, calibrated_robot, result, left_out);
  // Each row's residual in its own set-up's frame, from the rows the fit saw; the pose analysis on all of
  // them, in one time line.
  const MeasurementCampaign whole = concatenateCampaigns(campaigns);
  std::vector<RowResidual> residual =
      rowResiduals(written.model, written.parameters, campaigns, result.setup_of_campaign);
  std::vector<JointVector> pose_q;
  std::vector<Eigen::Vector3d> pose_error;
  std::vector<double> pose_time;
  for (std::size_t k = 0; k < residual.size(); ++k) {
    const std::size_t row = static_cast<std::size_t>(residual[k].row);
    pose_q.push_back(whole.command[row]);
    pose_error.push_back(residual[k].error);
    pose_time.push_back(whole.time[row]);
    residual[k].row = result.row[k];  // its row in its own campaign, as the report names it
  }
  std::vector<std::size_t> campaign_rows;
  for (const MeasurementCampaign& c : campaigns) campaign_rows.push_back(c.size());
  CalibrationRun run{
      std::move(result),       std::move(runs), calibrated_robot,    std::move(calibrated),
      std::move(left_out),     seconds,         std::move(residual), posePredictability(pose_q, pose_error, pose_time),
      std::move(campaign_rows)};
  return run;
}

namespace {

std::vector<std::string> fittedFiles(const CalibrationSources& sources) {
  return sources.campaigns.empty() ? std::vector<std::string>{sources.campaign} : sources.campaigns;
}

// Fitted campaign c's file as the user named it, or the campaign's own name when the files are not given.
const std::string& fileOf(const std::vector<std::string>& files, const GeometricCalibrationResult& result,
                          std::size_t c) {
  return c < files.size() ? files[c] : result.sources[c];
}

// The before/after statistics of the rows of fitted campaign `c`.
std::pair<ErrorStatistics, ErrorStatistics> campaignStatistics(const GeometricCalibrationResult& result, int c) {
  std::vector<double> before, after;
  for (std::size_t k = 0; k < result.campaign_of_row.size(); ++k) {
    if (result.campaign_of_row[k] != c) continue;
    before.push_back(result.error_before[k]);
    after.push_back(result.error_after[k]);
  }
  return {errorStatistics(before), errorStatistics(after)};
}

}  // namespace

nlohmann::ordered_json instrumentSetUpsJson(const GeometricCalibrationResult& result,
                                            const std::vector<std::string>& files) {
  nlohmann::ordered_json setups = nlohmann::ordered_json::array();
  for (int s = 0; s < result.estimate.setUpCount(); ++s) {
    nlohmann::ordered_json members = nlohmann::ordered_json::array();
    for (std::size_t c = 0; c < result.setup_of_campaign.size(); ++c) {
      if (result.setup_of_campaign[c] == s) members.push_back(fileOf(files, result, c));
    }
    const GeometricParameters own = result.estimate.ofSetUp(s);
    setups.push_back(
        {{"setup", s + 1},
         {"campaigns", members},
         {"frame_translation_m", {own.frame_translation.x(), own.frame_translation.y(), own.frame_translation.z()}},
         {"frame_rotation_vector_rad", {own.frame_rotation.x(), own.frame_rotation.y(), own.frame_rotation.z()}},
         {"instrument_scale", own.instrument_scale}});
  }
  return setups;
}

std::string describeInstrumentSetUps(const GeometricCalibrationResult& result, const std::vector<std::string>& files) {
  const int setups = result.estimate.setUpCount();
  std::ostringstream text;
  char rule[128];
  std::snprintf(rule, sizeof(rule), " agree within %.0f mm and %.0f deg share one):", kSameSetUpDistance * 1e3,
                kSameSetUpAngle * 180.0 / 3.14159265358979323846);
  text << result.setup_of_campaign.size() << " campaigns from " << setups
       << (setups == 1 ? std::string(" instrument set-up (one frame fitted for all)")
                       : std::string(" instrument set-ups, each with its own frame (campaigns whose frames, fitted "
                                     "on the nominal robot,") +
                             rule);
  for (int s = 0; s < setups && setups > 1; ++s) {
    text << (s ? ";" : "") << " set-up " << s + 1 << ":";
    for (std::size_t c = 0; c < result.setup_of_campaign.size(); ++c) {
      if (result.setup_of_campaign[c] == s) text << " " << baseName(fileOf(files, result, c));
    }
  }
  return text.str();
}

namespace {

// Each parameter of the fit: nominal and fitted value, and its sigma or why it was held.
nlohmann::ordered_json parametersJson(const GeometricCalibrationResult& result) {
  nlohmann::ordered_json parameters = nlohmann::ordered_json::array();
  for (const ParameterEstimate& p : result.parameters) {
    nlohmann::ordered_json entry = {
        {"name", p.name},  {"unit", p.unit}, {"nominal", p.nominal}, {"value", p.value}, {"identified", p.identified},
        {"pivot", p.pivot}};
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
  return parameters;
}

// The identified parameters' correlation matrix, by name.
nlohmann::ordered_json correlationJson(const GeometricCalibrationResult& result) {
  nlohmann::ordered_json names = nlohmann::ordered_json::array(), matrix = nlohmann::ordered_json::array();
  const Eigen::VectorXd sigma = result.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  for (std::size_t a = 0; a < result.free.size(); ++a) {
    names.push_back(result.names[static_cast<std::size_t>(result.free[a])]);
    nlohmann::ordered_json row = nlohmann::ordered_json::array();
    for (std::size_t b = 0; b < result.free.size(); ++b) {
      const double scale = sigma[a] * sigma[b];
      row.push_back(a == b ? 1.0 : scale > 0.0 ? result.covariance(a, b) / scale : 0.0);
    }
    matrix.push_back(row);
  }
  return {{"parameters", names}, {"matrix", matrix}};
}

// The fitted campaigns (`files`, as fittedFiles names them) and the held-out ones, before and after.
nlohmann::ordered_json campaignsJson(const CalibrationRun& run, const std::vector<std::string>& files) {
  const GeometricCalibrationResult& result = run.result;
  nlohmann::ordered_json campaigns = nlohmann::ordered_json::array();
  const bool several = result.sources.size() > 1;
  for (std::size_t c = 0; c < result.sources.size(); ++c) {
    const auto [before, after] =
        several ? campaignStatistics(result, static_cast<int>(c)) : std::make_pair(result.before, result.after);
    nlohmann::ordered_json entry = {{"file", fileOf(files, result, c)},
                                    {"role", "calibration"},
                                    {"rows", after.rows},
                                    {"before", errorStatisticsJson(before)},
                                    {"after", errorStatisticsJson(after)}};
    if (several) {
      entry["setup"] = result.setup_of_campaign[c] + 1;
    } else {
      entry["downweighted_rows"] = result.downweighted_rows;
      entry["downweighted_below_half_rows"] = result.outlier_rows;
    }
    campaigns.push_back(entry);
  }
  for (const CalibrationHoldoutRun& held : run.holdouts) {
    campaigns.push_back({{"file", held.name},
                         {"role", result.frame_fitted ? "holdout (robot fixed, instrument frame re-fitted)"
                                                      : "holdout (robot fixed, base frame)"},
                         {"rows", held.after.statistics.rows},
                         {"skipped_not_measured", held.after.skipped_rows},
                         {"before", errorStatisticsJson(held.before.statistics)},
                         {"after", errorStatisticsJson(held.after.statistics)},
                         {"downweighted_rows", held.after.downweighted_rows},
                         {"downweighted_below_half_rows", held.after.outlier_rows},
                         {"after_with_calibration_frame", errorStatisticsJson(held.shared_frame.statistics)}});
  }
  return campaigns;
}

}  // namespace

nlohmann::ordered_json calibrationReportJson(const CalibrationRun& run, const GeometricCalibrationOptions& options,
                                             const CalibrationSources& sources) {
  const GeometricCalibrationResult& result = run.result;
  nlohmann::ordered_json report;
  report["format"] = "jointcomp-calibration-report/1";
  report["robot"] = run.calibrated_robot->name;
  report["urdf"] = sources.urdf;
  report["params"] =
      sources.parameters.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(sources.parameters);
  report["campaign"] = sources.campaign;
  report["model"] =
      "measured = Exp(frame_r) * FK(q_cmd + offset - compliance .* tau(q_cmd) + other effects) * target + frame_t; "
      "joint placements corrected by placement * Trans(d) * Exp(r)";
  report["solver"] = {{"method", "Levenberg-Marquardt (dense, Eigen), robust loss by IRLS"},
                      {"iterations", result.iterations},
                      {"stop_reason", result.stop_reason},
                      {"seconds", run.seconds}};
  std::size_t total_rows = 0;
  for (std::size_t rows : run.campaign_rows) total_rows += rows;
  report["rows"] = {{"total", total_rows},
                    {"used", result.used_rows},
                    {"skipped_not_measured", result.skipped_rows},
                    {"downweighted", result.downweighted_rows},
                    {"downweighted_below_half", result.outlier_rows}};
  report["loss"] = {{"type", robustLossName(result.loss)}, {"scale_mm", result.loss_scale * 1e3}};
  report["residual_sigma_per_axis_mm"] = result.residual_sigma * 1e3;
  report["identifiability"] = {{"relative_pivot_threshold", options.identifiability.relative_pivot_threshold},
                               {"identified", result.free.size()},
                               {"fixed", result.names.size() - result.free.size()},
                               {"condition_number_at_start", result.condition_number_at_start},
                               {"condition_number", result.condition_number}};
  report["parameters"] = parametersJson(result);
  // The identified parameters' correlation (from the fit's covariance): what Monte Carlo studies need
  // beyond the sigmas, since placements, offsets and the target trade off against each other.
  if (result.covariance.rows() == static_cast<Eigen::Index>(result.free.size()) && !result.free.empty()) {
    report["correlation"] = correlationJson(result);
  }
  report["compliance_left_out"] = run.compliance_left_out;
  const std::vector<std::string> files = fittedFiles(sources);
  if (result.sources.size() > 1) report["instrument_setups"] = instrumentSetUpsJson(result, files);
  report["campaigns"] = campaignsJson(run, files);
  report["pose_predictability"] = posePredictabilityJson(run.pose);
  report["outputs"] = sources.outputs;
  return report;
}

std::string calibrationSummary(const CalibrationRun& run, const CalibrationSources& sources) {
  const GeometricCalibrationResult& result = run.result;
  std::ostringstream summary;
  summary << "Kinematic calibration of " << run.calibrated_robot->name << " on " << sources.campaign << "\n";
  const std::vector<std::string> files = fittedFiles(sources);
  if (result.sources.size() > 1) summary << describeInstrumentSetUps(result, files) << "\n";
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
                result.residual_sigma * 1e3, result.iterations, run.seconds);
  summary << line;
  const bool frame = result.frame_fitted;  // campaigns in the instrument frame: a frame is fitted to each
  summary << "\n3-D error [mm]                      rows     before (nominal"
          << (frame ? ", frame fitted)" : ", base frame)  ") << "   after (calibrated)\n";
  summary << "                                           mean     rms     max      mean     rms     max\n";
  if (result.sources.size() > 1) {
    for (std::size_t c = 0; c < result.sources.size(); ++c) {
      const auto [before, after] = campaignStatistics(result, static_cast<int>(c));
      summary << tableRow(baseName(fileOf(files, result, c)) + " (calibration)", after.rows, before, after);
    }
    summary << tableRow("all calibration rows", result.used_rows, result.before, result.after);
  } else {
    summary << tableRow(baseName(sources.campaign) + " (calibration)", result.used_rows, result.before, result.after);
  }
  for (const CalibrationHoldoutRun& held : run.holdouts) {
    summary << tableRow(baseName(held.name) + (frame ? " (held out, frame re-fitted)" : " (held out)"),
                        held.after.statistics.rows, held.before.statistics, held.after.statistics);
    if (frame) {
      summary << tableRow(baseName(held.name) + " (held out, calibration's frame)", held.shared_frame.statistics.rows,
                          held.before.statistics, held.shared_frame.statistics);
    }
  }
  for (const CalibrationHoldoutRun& held : run.holdouts) {
    if (!frame) continue;  // the base frame: no frame fit, nothing weighed down in one
    std::snprintf(line, sizeof(line),
                  "%s: %d rows down-weighted in its frame fit (scale %.3f mm), %d of them below half weight\n",
                  baseName(held.name).c_str(), held.after.downweighted_rows, held.after.loss_scale * 1e3,
                  held.after.outlier_rows);
    summary << line;
    // A frame that fits three times worse than the re-fitted one means the set-ups differ.
    summary << baseName(held.name)
            << (held.shared_frame.statistics.rms > 3.0 * held.after.statistics.rms + 1e-4
                    ? ": with the calibration's frame three times worse than re-fitted: the campaigns do not share "
                      "the instrument frame\n"
                    : ": with the calibration's frame as good as re-fitted: the campaigns share the instrument "
                      "frame\n");
  }
  summary << "\nWhat the calibration leaves. " << describePosePredictability(run.pose) << "\n";
  summary << "\nIdentified parameters (1 sigma):\n";
  for (const ParameterEstimate& p : result.parameters) {
    if (p.identified) summary << parameterLine(p);
  }
  summary << "\nFixed parameters:\n";
  for (const ParameterEstimate& p : result.parameters) {
    if (!p.identified) summary << parameterLine(p);
  }
  if (!run.compliance_left_out.empty()) {
    summary << "\nCompliance effect in the parameter file: 1 / the fitted compliance where it was identified and "
               "positive (or the prior's stiffness where it was not fitted); these joints are written as rigid "
               "(stiffness null: nothing to compensate; give a parameter file with a compliance effect to supply "
               "them):\n";
    for (const std::string& item : run.compliance_left_out) summary << "  " << item << "\n";
  }
  return summary.str();
}

nlohmann::ordered_json posePredictabilityJson(const PosePredictability& pose) {
  if (!pose.computed) return nullptr;
  return {{"neighbours", pose.neighbours},
          {"min_gap_s", pose.min_gap_s},
          {"scored_rows", pose.scored_rows},
          {"residual_rms_mm", pose.residual_rms * 1e3},
          {"left_other_times_rms_mm", pose.left_other_times_rms * 1e3},
          {"left_any_time_rms_mm", pose.left_any_time_rms * 1e3},
          {"median_distance_other_times_rad", pose.median_distance_other_times},
          {"median_distance_any_time_rad", pose.median_distance_any_time},
          {"smooth_share", pose.smooth_share}};
}

std::string calibrationResidualsCsv(const CalibrationRun& run, const CalibrationSources& sources) {
  const GeometricCalibrationResult& result = run.result;
  std::ostringstream csv;
  csv.precision(9);
  csv << "campaign,role,row,before_mm,after_mm,weight,dx_mm,dy_mm,dz_mm";
  for (const Joint& joint : run.calibrated_robot->joints) csv << ",dq_" << joint.name << "_mrad";
  csv << "\n";
  auto residualColumns = [&csv](const RowResidual& r) {
    for (int a = 0; a < 3; ++a) csv << ',' << r.error[a] * 1e3;
    for (int j = 0; j < r.joint_error.size(); ++j) csv << ',' << r.joint_error[j] * 1e3;
    csv << "\n";
  };
  const std::vector<std::string> files = fittedFiles(sources);
  for (std::size_t k = 0; k < result.row.size(); ++k) {
    const std::size_t c = k < result.campaign_of_row.size() ? static_cast<std::size_t>(result.campaign_of_row[k]) : 0;
    csv << baseName(c < files.size() ? files[c] : sources.campaign) << ",calibration," << result.row[k] << ','
        << result.error_before[k] * 1e3 << ',' << result.error_after[k] * 1e3 << ',' << result.weight[k];
    residualColumns(run.residual[k]);
  }
  for (const CalibrationHoldoutRun& held : run.holdouts) {
    for (std::size_t k = 0; k < held.after.row.size(); ++k) {
      csv << baseName(held.name) << ",holdout," << held.after.row[k] << ',' << held.before.error[k] * 1e3 << ','
          << held.after.error[k] * 1e3 << ',' << held.after.weight[k];
      residualColumns(held.residual[k]);
    }
  }
  return csv.str();
}

}  // namespace jointcomp
