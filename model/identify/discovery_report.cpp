#include "model/identify/discovery_report.hpp"

#include <cstdio>
#include <sstream>

#include "model/identify/calibration_report.hpp"

namespace jointcomp {
namespace {

std::string campaignName(const DiscoverySources& sources, bool held_out, int k) {
  const std::vector<std::string>& names = held_out ? sources.held_out : sources.campaigns;
  const std::size_t index = static_cast<std::size_t>(k);
  if (index < names.size()) return names[index];
  return (held_out ? "held-out campaign " : "fitted campaign ") + std::to_string(k + 1);
}

nlohmann::ordered_json stateJson(const DiscoveryState& s, const DiscoverySources& sources) {
  nlohmann::ordered_json held = nlohmann::ordered_json::array();
  for (std::size_t k = 0; k < s.heldout.size(); ++k) {
    nlohmann::ordered_json entry = errorStatisticsJson(s.heldout[k]);
    entry["campaign"] = campaignName(sources, true, static_cast<int>(k));
    held.push_back(entry);
  }
  // Ra and Rz of the Z error on every campaign that is a path (isPathCampaign); [] when none is.
  nlohmann::ordered_json paths = nlohmann::ordered_json::array();
  for (const PathRoughness& p : s.paths) {
    paths.push_back({{"campaign", campaignName(sources, p.held_out, p.campaign)},
                     {"set", p.held_out ? "held_out" : "fitted"},
                     {"rows", p.rows},
                     {"ra_mm", p.ra * 1e3},
                     {"rz_mm", p.rz * 1e3}});
  }
  return {{"fitted", errorStatisticsJson(s.fitted)},
          {"held_out", held},
          {"cv_rms_per_axis_mm", s.cv_rms * 1e3},
          {"ra_rz_on_paths", paths}};
}

// Every held-out campaign's RMS in mm, "name 0.4270, name 0.3100"; "-" without one.
std::string heldRms(const DiscoveryState& s, const DiscoverySources& sources) {
  if (s.heldout.empty()) return "-";
  std::string text;
  for (std::size_t k = 0; k < s.heldout.size(); ++k) {
    char value[64];
    std::snprintf(value, sizeof(value), "%.4f", s.heldout[k].rms * 1e3);
    text += (k ? ", " : "") + campaignName(sources, true, static_cast<int>(k)) + " " + value;
  }
  return text;
}

nlohmann::ordered_json coverageJson(const DiscoveryResult& result, const DiscoverySources& sources) {
  constexpr double kDeg = 180.0 / 3.14159265358979323846;
  nlohmann::ordered_json fitted = nlohmann::ordered_json::array();
  const Robot& robot = result.model.robot();
  for (std::size_t j = 0; j < result.coverage.visited.size(); ++j) {
    nlohmann::ordered_json intervals = nlohmann::ordered_json::array();
    for (const AngleInterval& i : result.coverage.visited[j]) intervals.push_back({i.low * kDeg, i.high * kDeg});
    fitted.push_back({{"joint", robot.joints[j].name}, {"visited_deg", intervals}});
  }
  nlohmann::ordered_json held = nlohmann::ordered_json::array();
  for (std::size_t k = 0; k < result.heldout_coverage.size(); ++k) {
    held.push_back({{"campaign", campaignName(sources, true, static_cast<int>(k))},
                    {"fraction_outside_per_joint", result.heldout_coverage[k].fraction_outside},
                    {"flagged", result.heldout_coverage[k].flagged},
                    {"median_distance_to_fitted_pose_rad", result.heldout_coverage[k].median_pose_distance}});
  }
  return {{"half_width_deg", kCoverageHalfWidth * kDeg},
          {"flag_fraction", kCoverageFlagFraction},
          {"fitted", fitted},
          {"held_out", held}};
}

std::string baseName(const DiscoveryOptions& options) { return options.base_geometry ? "textbook" : "frame"; }

// Where the final fit's residual lies: joints, repeating orders of their angles, time blocks.
nlohmann::ordered_json unexplainedJson(const DiscoveryResult& result) {
  const UnexplainedResidual& u = result.unexplained;
  const Robot& robot = result.model.robot();
  nlohmann::ordered_json joints = nlohmann::ordered_json::array();
  for (int j : u.joints) {
    joints.push_back({{"joint", robot.joints[j].name},
                      {"rms_rad", u.joint_rms_rad[j]},
                      {"rms_at_target_mm", u.joint_rms_m[j] * 1e3}});
  }
  nlohmann::ordered_json orders = nlohmann::ordered_json::array();
  for (const ResidualOrder& o : u.orders) {
    orders.push_back({{"joint", robot.joints[o.joint].name},
                      {"angle", o.angle},
                      {"order", o.order},
                      {"amplitude_rad", o.amplitude_rad},
                      {"stands_out", o.stands_out}});
  }
  nlohmann::ordered_json blocks = nlohmann::ordered_json::array();
  for (double b : u.block_rms) blocks.push_back(b * 1e3);
  return {
      {"above_noise_floor", u.floor_known ? nlohmann::ordered_json(u.above_floor) : nlohmann::ordered_json(nullptr)},
      {"fitted_over_floor", u.over_floor},
      {"joints_by_rms", joints},
      {"strongest_orders", orders},
      {"time_block_rms_mm", blocks},
      {"pose_predictability", posePredictabilityJson(u.pose)},
      {"summary", u.summary}};
}

}  // namespace

std::string discoveryStepLabel(const DiscoveryStep& step) {
  if (step.joint < 0) return step.type + (step.detail.empty() ? std::string(" (robot)") : step.detail);
  return step.type + " " + step.joint_name + step.detail;
}

namespace {

// How discovery chose: the cross-validation, the criterion, the transfer check and their settings.
nlohmann::ordered_json selectionJson(const DiscoveryResult& result, const DiscoveryOptions& options) {
  return {{"cross_validation", "time-blocked K-fold (blocks of consecutive rows)"},
          {"folds", options.folds},
          {"min_cv_gain", options.min_cv_gain},
          {"criterion", "dBIC = N ln(RSS_c/RSS_0) + dk ln N + 2 ln(candidates) < 0"},
          {"transfer",
           "predicted from the other groups, no time block, joint-space part (at least "
           "min_group_share of the rows) or range of a candidate's joint angle more than 1 % and "
           "transfer_significance standard errors worse"},
          {"transfer_significance", options.transfer_significance},
          {"min_group_share", options.min_group_share},
          {"angle_ranges", options.angle_ranges},
          {"pairs", options.pairs},
          {"table_knots", options.table_knots},
          {"max_prior_weight", options.max_prior_weight},
          {"max_ridge_weight", options.max_ridge_weight},
          {"ties",
           "within one standard error of the fold-wise CV differences or a quarter of "
           "min_cv_gain: the fewest parameters, then the lowest BIC"},
          {"base", baseName(options)},
          {"max_steps", options.max_steps},
          {"max_harmonic_order", options.max_harmonic_order},
          {"candidates", result.candidates}};
}

// Each step: the effect added, its parameters, the evidence for it, and the errors before and after.
nlohmann::ordered_json stepsJson(const DiscoveryResult& result, const DiscoverySources& sources) {
  nlohmann::ordered_json steps = nlohmann::ordered_json::array();
  int index = 0;
  for (const DiscoveryStep& s : result.steps) {
    // payload belongs to no joint: joint and joint_index null.
    nlohmann::ordered_json entry = {
        {"step", ++index},
        {"type", s.type},
        {"joint", s.joint >= 0 ? nlohmann::ordered_json(s.joint_name) : nlohmann::ordered_json(nullptr)},
        {"joint_index", s.joint >= 0 ? nlohmann::ordered_json(s.joint + 1) : nlohmann::ordered_json(nullptr)}};
    if (s.joints.size() > 1) {
      nlohmann::ordered_json joints = nlohmann::ordered_json::array();
      for (int j : s.joints)
        joints.push_back(j >= 0 ? nlohmann::ordered_json(result.model.robot().joints[static_cast<std::size_t>(j)].name)
                                : nlohmann::ordered_json(nullptr));
      entry["joints"] = joints;
      entry["label"] = discoveryStepLabel(s);
    }
    for (const auto& [key, value] : s.report_fields.items()) entry[key] = value;
    nlohmann::ordered_json parameters = nlohmann::ordered_json::array();
    for (const DiscoveredParameter& p : s.parameters)
      parameters.push_back({{"name", p.name}, {"value", p.value}, {"sigma", p.sigma}});
    entry["parameters"] = parameters;
    entry["evidence"] = {{"cv_rms_per_axis_mm_before", s.cv_rms_before * 1e3},
                         {"cv_rms_per_axis_mm_after", s.cv_rms_after * 1e3},
                         {"delta_bic", s.delta_bic},
                         {"candidates_tried", s.candidates_tried},
                         {"runner_up", s.runner_up},
                         {"rejected_not_transferring", s.rejected}};
    entry["before"] = stateJson(s.before, sources);
    entry["after"] = stateJson(s.after, sources);
    steps.push_back(entry);
  }
  return steps;
}

nlohmann::ordered_json noiseFloorJson(const DiscoveryResult& result) {
  // The final error over the floor: of the first held-out campaign (or the fitted rows), and of each held-out one.
  auto overFloor = [&](double rms) {
    return result.noise_floor > 0.0 ? nlohmann::ordered_json(rms / result.noise_floor)
                                    : nlohmann::ordered_json(nullptr);
  };
  const double final_held =
      result.final_state.heldout.empty() ? result.final_state.fitted.rms : result.final_state.heldout[0].rms;
  nlohmann::ordered_json per_heldout = nlohmann::ordered_json::array();
  for (const ErrorStatistics& h : result.final_state.heldout) per_heldout.push_back(overFloor(h.rms));
  return {{"rms_3d_mm", result.noise_floor * 1e3},
          {"final_over_floor", overFloor(final_held)},
          {"fitted_over_floor", overFloor(result.final_state.fitted.rms)},
          {"held_out_over_floor", per_heldout}};
}

}  // namespace

nlohmann::ordered_json discoveryReportJson(const DiscoveryResult& result, const DiscoveryOptions& options,
                                           const DiscoverySources& sources, double seconds) {
  nlohmann::ordered_json report;
  report["format"] = "jointcomp-discovery-report/1";
  report["robot"] = result.model.robot().name;
  report["urdf"] = sources.urdf;
  report["params"] =
      sources.parameters.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(sources.parameters);
  report["campaigns"] = sources.campaigns;
  report["held_out"] = sources.held_out;
  report["vocabulary"] = discoveryEffectTypes();
  report["selection"] = selectionJson(result, options);
  report["fitted_rows"] = result.fitted_rows;
  if (sources.campaigns.size() > 1)
    report["instrument_setups"] = instrumentSetUpsJson(result.calibration, sources.campaigns);
  report["coverage"] = coverageJson(result, sources);
  report["initial"] = stateJson(result.initial, sources);
  report["initial"]["joint_residual_rms_rad"] = result.joint_residual_rms_initial;
  report["steps"] = stepsJson(result, sources);
  report["final"] = stateJson(result.final_state, sources);
  report["final"]["joint_residual_rms_rad"] = result.joint_residual_rms_final;
  report["stop_reason"] = result.stop_reason;
  report["rejected_at_stop"] = result.rejected_at_stop;
  report["noise_floor"] = noiseFloorJson(result);
  report["unexplained"] = unexplainedJson(result);
  report["not_candidates"] = nlohmann::ordered_json::array();
  report["seconds"] = seconds;
  report["outputs"] = sources.outputs;
  return report;
}

namespace {

// The discovered effects' parameters as the last refit left them (the steps above print each at its step).
std::string finalParameters(const DiscoveryResult& result) {
  std::ostringstream out;
  char line[256];
  for (int e = 0; e < result.model.effectCount(); ++e) {
    const Effect& effect = result.model.effect(e);
    if (effect.estimate_note != "found by jointcomp discover") continue;
    const std::vector<std::string> names = effect.parameterNames();
    const std::vector<double> values = effect.parameters();
    if (out.tellp() == 0) out << "final values of the discovered effects (after the last refit):\n";
    if (values.size() > 12) {
      std::snprintf(line, sizeof(line), "    %s: %zu coefficients (parameters.json)\n", effect.type().c_str(),
                    values.size());
      out << line;
      continue;
    }
    for (std::size_t k = 0; k < values.size() && k < names.size(); ++k) {
      std::snprintf(line, sizeof(line), "    %-48s %.6g\n", names[k].c_str(), values[k]);
      out << line;
    }
  }
  return out.str();
}

}  // namespace

std::string discoverySummary(const DiscoveryResult& result, const DiscoveryOptions& options,
                             const DiscoverySources& sources) {
  std::ostringstream summary;
  summary << "jointcomp discover: " << result.model.robot().name << ", " << result.fitted_rows << " fitted rows, "
          << result.candidates << " candidates, base " << baseName(options) << "\n";
  if (sources.campaigns.size() > 1) summary << describeInstrumentSetUps(result.calibration, sources.campaigns) << "\n";
  char line[512];
  std::snprintf(line, sizeof(line), "base model: fitted RMS %.4f mm, held-out RMS [mm] %s\n",
                result.initial.fitted.rms * 1e3, heldRms(result.initial, sources).c_str());
  summary << line;
  for (std::size_t k = 0; k < result.heldout_coverage.size(); ++k) {
    const HeldoutCoverage& c = result.heldout_coverage[k];
    std::snprintf(line, sizeof(line), "held-out %s: its poses lie %.3f rad (median) from the nearest fitted pose\n",
                  campaignName(sources, true, static_cast<int>(k)).c_str(), c.median_pose_distance);
    summary << line;
    if (!c.flagged) continue;
    summary << "warning: held-out " << campaignName(sources, true, static_cast<int>(k))
            << " visits joint angles the fit never covered:";
    for (std::size_t j = 0; j < c.fraction_outside.size(); ++j) {
      if (c.fraction_outside[j] > kCoverageFlagFraction) {
        std::snprintf(line, sizeof(line), " %s %.0f %% of rows", result.model.robot().joints[j].name.c_str(),
                      100.0 * c.fraction_outside[j]);
        summary << line;
      }
    }
    summary << " (fitted coverage in report.json)\n";
  }
  int index = 0;
  for (const DiscoveryStep& s : result.steps) {
    std::snprintf(line, sizeof(line), "step %d: %-44s CV %.4f -> %.4f mm/axis, dBIC %.1f; fitted RMS %.4f -> %.4f mm\n",
                  ++index, discoveryStepLabel(s).c_str(), s.cv_rms_before * 1e3, s.cv_rms_after * 1e3, s.delta_bic,
                  s.before.fitted.rms * 1e3, s.after.fitted.rms * 1e3);
    summary << line;
    if (!s.after.heldout.empty()) {
      summary << "    held-out RMS [mm] before: " << heldRms(s.before, sources) << "\n";
      summary << "    held-out RMS [mm] after:  " << heldRms(s.after, sources) << "\n";
    }
    for (std::size_t k = 0; k < s.after.heldout.size() && k < s.before.heldout.size(); ++k) {
      if (s.after.heldout[k].rms <= s.before.heldout[k].rms * 1.005) continue;
      std::snprintf(line, sizeof(line), "    warning: this step makes held-out %s worse (%.4f -> %.4f mm)\n",
                    campaignName(sources, true, static_cast<int>(k)).c_str(), s.before.heldout[k].rms * 1e3,
                    s.after.heldout[k].rms * 1e3);
      summary << line;
    }
    for (const DiscoveredParameter& p : s.parameters) {
      // A derived figure without its own uncertainty (a table's spectrum) is printed without "+- 0".
      if (p.sigma > 0.0)
        std::snprintf(line, sizeof(line), "    %-48s %.6g +- %.3g\n", p.name.c_str(), p.value, p.sigma);
      else
        std::snprintf(line, sizeof(line), "    %-48s %.6g\n", p.name.c_str(), p.value);
      summary << line;
    }
    if (!s.rejected.empty()) summary << "    rejected: " << s.rejected << "\n";
  }
  char floor[64] = "not known (--noise-floor-mm gives it)";
  if (result.noise_floor > 0.0) std::snprintf(floor, sizeof(floor), "%.4f mm (3-D RMS)", result.noise_floor * 1e3);
  std::snprintf(line, sizeof(line), "stopped: %s\nfinal: fitted RMS %.4f mm, held-out RMS [mm] %s; noise floor %s\n",
                result.stop_reason.c_str(), result.final_state.fitted.rms * 1e3,
                heldRms(result.final_state, sources).c_str(), floor);
  summary << line;
  if (!result.rejected_at_stop.empty()) summary << "rejected: " << result.rejected_at_stop << "\n";
  summary << finalParameters(result);
  if (result.unexplained.above_floor || !result.unexplained.floor_known) summary << result.unexplained.summary << "\n";
  // Paths: Ra and Rz of the Z error, base model -> final model.
  for (std::size_t k = 0; k < result.final_state.paths.size() && k < result.initial.paths.size(); ++k) {
    const PathRoughness& a = result.initial.paths[k];
    const PathRoughness& b = result.final_state.paths[k];
    std::snprintf(line, sizeof(line), "path %s (%s, %d rows): Ra %.4f -> %.4f mm, Rz %.4f -> %.4f mm\n",
                  campaignName(sources, b.held_out, b.campaign).c_str(), b.held_out ? "held out" : "fitted", b.rows,
                  a.ra * 1e3, b.ra * 1e3, a.rz * 1e3, b.rz * 1e3);
    summary << line;
  }
  return summary.str();
}

std::string discoveryStepsCsv(const DiscoveryResult& result) {
  std::ostringstream csv;
  csv << "step,effect,fitted_rms_mm,cv_rms_mm";
  // One column per held-out campaign, in the order of report.json's "held_out" (the first keeps its old name).
  for (std::size_t k = 0; k < result.initial.heldout.size(); ++k)
    csv << (k == 0 ? std::string(",heldout_rms_mm") : ",heldout" + std::to_string(k + 1) + "_rms_mm");
  csv << "\n";
  auto row = [&csv](int step, const std::string& label, const DiscoveryState& s) {
    csv << step << ',' << label << ',' << s.fitted.rms * 1e3 << ',' << s.cv_rms * 1e3;
    for (const ErrorStatistics& h : s.heldout) csv << ',' << h.rms * 1e3;
    csv << "\n";
  };
  row(0, "base", result.initial);
  int index = 0;
  for (const DiscoveryStep& s : result.steps) row(++index, discoveryStepLabel(s), s.after);
  return csv.str();
}

}  // namespace jointcomp
