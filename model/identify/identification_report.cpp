#include "model/identify/identification_report.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "model/effects/transmission_error.hpp"

namespace jointcomp {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;

std::string format(const char* pattern, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, pattern, value);
  return buffer;
}

nlohmann::ordered_json sourcesJson(const ReportSources& s) {
  nlohmann::ordered_json json;
  json["campaign"] = s.campaign;
  json["nominal_parameters"] = s.parameters;
  json["robot"] = s.robot;
  if (!s.updated_parameters.empty()) json["updated_parameters"] = s.updated_parameters;
  return json;
}

// JSON has no infinity: an unbounded interval end is null.
nlohmann::ordered_json finiteOrNull(double value) {
  return std::isfinite(value) ? nlohmann::ordered_json(value) : nlohmann::ordered_json(nullptr);
}

double trueStiffness(const JointErrorModel* truth, int joint) {
  if (!truth) return std::nan("");
  const int index = truth->jointSprings();
  if (index < 0 || joint >= truth->robot().dof()) return std::nan("");
  return truth->effect(index).jointStiffness(joint);
}

nlohmann::ordered_json estimateJson(const StiffnessEstimate& e, bool local, double truth) {
  nlohmann::ordered_json json;
  json["identified"] = e.identified;
  json["method"] = e.method;
  if (!e.reason.empty()) json["reason"] = e.reason;
  if (e.points == 0) return json;
  if (e.identified) {
    json["stiffness_nm_per_rad"] = e.stiffness;
    json["stiffness_se_nm_per_rad"] = e.stiffness_se;
    json["stiffness_interval_nm_per_rad"] = {e.stiffness_low, finiteOrNull(e.stiffness_high)};
  }
  json["compliance_rad_per_nm"] = e.compliance;
  json["compliance_se_rad_per_nm"] = e.compliance_se;
  json["points"] = e.points;
  json["poses"] = e.groups;
  json["residual_dof"] = e.dof;
  if (local) {
    json["residual_rms_deg"] = e.residual_rms / kDegree;
  } else {
    json["residual_rms_mm"] = e.residual_rms * 1e3;
  }
  json["reduced_chi2"] =
      e.reduced_chi2 > 0.0 ? nlohmann::ordered_json(e.reduced_chi2) : nlohmann::ordered_json(nullptr);
  if (std::isfinite(truth) && e.identified) {
    json["interval_covers_truth"] = truth >= e.stiffness_low && truth <= e.stiffness_high;
    json["error_over_se"] = (e.stiffness - truth) / e.stiffness_se;
  }
  if (local) {
    nlohmann::ordered_json torque = nlohmann::ordered_json::array();
    nlohmann::ordered_json deflection = nlohmann::ordered_json::array();
    nlohmann::ordered_json sigma = nlohmann::ordered_json::array();
    for (std::size_t k = 0; k < e.torque.size(); ++k) {
      torque.push_back(e.torque[k]);
      deflection.push_back(e.deflection[k] / kDegree);
      sigma.push_back(e.deflection_sigma[k] / kDegree);
    }
    json["torque_nm"] = torque;
    json["deflection_deg"] = deflection;
    json["deflection_sigma_deg"] = sigma;
  }
  return json;
}

std::string stiffnessCell(const StiffnessEstimate& e) {
  if (!e.identified) return "-";
  const std::string high =
      std::isfinite(e.stiffness_high) ? format("%.1f", e.stiffness_high / 1e3) : std::string("inf");
  return format("%.1f", e.stiffness / 1e3) + " [" + format("%.1f", e.stiffness_low / 1e3) + ", " + high + "]";
}

nlohmann::ordered_json harmonicJson(const HarmonicEstimate& h, const JointErrorModel* truth, int joint, int stage,
                                    double confidence) {
  nlohmann::ordered_json json;
  json["cycles_per_revolution"] = h.order;
  json["amplitude_deg"] = h.amplitude_rad / kDegree;
  json["amplitude_se_deg"] = h.amplitude_se_rad / kDegree;
  json["amplitude_interval_deg"] = {h.amplitude_low_rad / kDegree, h.amplitude_high_rad / kDegree};
  json["phase_rad"] = h.phase_rad;
  json["phase_se_rad"] = h.phase_se_rad;
  json["phase_interval_rad"] = {h.phase_low_rad, h.phase_high_rad};
  json["interval_confidence"] = confidence;
  json["amplitude_over_se"] = h.amplitude_to_se;
  json["f_statistic"] = h.f_statistic;
  json["p_value"] = h.p_value;
  json["significant"] = h.significant;
  double amplitude = 0.0, phase = 0.0;
  if (truth && trueHarmonic(*truth, joint, stage, h.order, amplitude, phase)) {
    json["true_amplitude_deg"] = amplitude / kDegree;
    json["true_phase_rad"] = phase;
    json["amplitude_error_over_se"] = (h.amplitude_rad - amplitude) / h.amplitude_se_rad;
    json["phase_error_over_se"] = wrappedAngleDifference(h.phase_rad, phase) / h.phase_se_rad;
  }
  return json;
}

}  // namespace

double wrappedAngleDifference(double a, double b) {
  double d = std::remainder(a - b, 2.0 * kPi);
  if (d <= -kPi) d += 2.0 * kPi;
  return d;
}

bool trueHarmonic(const JointErrorModel& truth, int joint, int stage, double order, double& amplitude_rad,
                  double& phase_rad) {
  const int index = truth.findEffect(TransmissionErrorEffect::kType);
  if (index < 0) return false;
  for (const Harmonic& h : static_cast<const TransmissionErrorEffect&>(truth.effect(index)).harmonics()) {
    if (h.joint == joint && h.stage == stage && std::abs(h.cycles_per_revolution - order) < 1e-9) {
      amplitude_rad = h.amplitude_rad;
      phase_rad = h.phase_rad;
      return true;
    }
  }
  return false;
}

nlohmann::ordered_json stiffnessReportJson(const StiffnessIdentificationResult& result, const ReportSources& sources,
                                           const JointErrorModel* truth) {
  nlohmann::ordered_json json;
  json["identification"] = "stiffness";
  json["sources"] = sourcesJson(sources);
  json["parameter_file_uses"] = sources.method_used;
  json["confidence"] = result.confidence;
  json["campaign"] = {{"rows", result.rows},
                      {"rows_without_position", result.rows_without_position},
                      {"local_tests", result.local_groups},
                      {"poses_with_other_loads", result.global_groups},
                      {"poses_never_loaded", result.unused_groups},
                      {"global_shares_rows_with_local", result.global_shares_rows}};
  nlohmann::ordered_json joints = nlohmann::ordered_json::array();
  for (std::size_t j = 0; j < result.joint_names.size(); ++j) {
    const double truth_k = trueStiffness(truth, static_cast<int>(j));
    nlohmann::ordered_json entry;
    entry["joint"] = result.joint_names[j];
    entry["local"] = estimateJson(result.local[j], true, truth_k);
    entry["global"] = estimateJson(result.global[j], false, truth_k);
    if (std::isfinite(result.relative_difference[j])) {
      entry["global_minus_local_relative"] = result.relative_difference[j];
      entry["difference_z_score"] = result.z_score[j];
    }
    if (std::isfinite(truth_k)) entry["true_stiffness_nm_per_rad"] = truth_k;
    joints.push_back(entry);
  }
  json["joints"] = joints;
  json["notes"] = result.notes;
  return json;
}

std::string stiffnessSummary(const StiffnessIdentificationResult& result, const ReportSources& sources,
                             const JointErrorModel* truth) {
  std::ostringstream out;
  out << "Joint stiffness identified from " << sources.campaign << "\n";
  out << "  nominal parameters " << sources.parameters << ", robot " << sources.robot << "\n";
  out << "  " << result.rows << " rows: " << result.local_groups << " local tests, " << result.global_groups
      << " poses with other loads, " << result.unused_groups << " poses never loaded\n";
  out << "  stiffness in 1e3 N m/rad, " << format("%.0f", result.confidence * 100)
      << " % intervals; diff = (global - local) / local\n\n";
  char line[256];
  std::snprintf(line, sizeof line, "%-9s %-8s %-28s %-28s %8s %7s %10s\n", "joint", "local by", "local", "global",
                "diff", "z", truth ? "true" : "");
  out << line;
  for (std::size_t j = 0; j < result.joint_names.size(); ++j) {
    const double truth_k = trueStiffness(truth, static_cast<int>(j));
    const std::string diff =
        std::isfinite(result.relative_difference[j]) ? format("%+.1f %%", 100 * result.relative_difference[j]) : "-";
    const std::string z = std::isfinite(result.z_score[j]) ? format("%+.2f", result.z_score[j]) : "-";
    std::snprintf(line, sizeof line, "%-9s %-8s %-28s %-28s %8s %7s %10s\n", result.joint_names[j].c_str(),
                  result.local[j].identified ? result.local[j].method.c_str() : "-",
                  stiffnessCell(result.local[j]).c_str(), stiffnessCell(result.global[j]).c_str(), diff.c_str(),
                  z.c_str(), std::isfinite(truth_k) ? format("%.1f", truth_k / 1e3).c_str() : "");
    out << line;
  }
  for (std::size_t j = 0; j < result.joint_names.size(); ++j) {
    for (const StiffnessEstimate* e : {&result.local[j], &result.global[j]}) {
      if (!e->identified && !e->reason.empty() && e->reason.rfind("no local test", 0) != 0) {
        out << "  " << result.joint_names[j] << " (" << (e == &result.local[j] ? "local" : "global")
            << "): " << e->reason << "\n";
      }
    }
  }
  for (const std::string& note : result.notes) out << "  note: " << note << "\n";
  if (!sources.updated_parameters.empty()) {
    out << "\nThe " << sources.method_used << " estimates went into " << sources.updated_parameters << ".\n";
  }
  return out.str();
}

nlohmann::ordered_json transmissionReportJson(const TransmissionIdentificationResult& result,
                                              const ReportSources& sources, const JointErrorModel* truth) {
  nlohmann::ordered_json json;
  json["identification"] = "transmission_error";
  json["sources"] = sourcesJson(sources);
  json["joint"] = result.joint_name;
  json["of"] = result.part;
  json["stage"] = result.stage;
  json["angle_source"] = result.angle_source;
  json["samples"] = result.samples;
  json["stage_revolutions"] = result.stage_revolutions;
  json["confidence"] = result.confidence;
  json["significance_family_wise"] = result.significance;
  json["residual_dof"] = result.dof;
  json["residual_rms_deg"] = result.residual_rms_rad / kDegree;
  json["noise_rms_deg"] = result.noise_rms_rad > 0.0 ? nlohmann::ordered_json(result.noise_rms_rad / kDegree)
                                                     : nlohmann::ordered_json(nullptr);
  json["reduced_chi2"] =
      result.reduced_chi2 > 0.0 ? nlohmann::ordered_json(result.reduced_chi2) : nlohmann::ordered_json(nullptr);
  nlohmann::ordered_json harmonics = nlohmann::ordered_json::array();
  for (const HarmonicEstimate& h : result.harmonics) {
    harmonics.push_back(harmonicJson(h, truth, result.joint, result.stage, result.confidence));
  }
  json["harmonics"] = harmonics;
  nlohmann::ordered_json candidates = nlohmann::ordered_json::array();
  for (const HarmonicEstimate& h : result.candidates) {
    candidates.push_back(harmonicJson(h, truth, result.joint, result.stage, result.confidence));
  }
  json["candidates_full_model"] = candidates;
  json["excluded_orders"] = result.excluded_orders;
  nlohmann::ordered_json spectrum_amplitude = nlohmann::ordered_json::array();
  for (double a : result.spectrum_amplitude_rad) spectrum_amplitude.push_back(a / kDegree);
  json["spectrum"] = {{"cycles_per_revolution", result.spectrum_orders}, {"amplitude_deg", spectrum_amplitude}};
  json["baseline"] = {{"polynomial_in", "x = (q - centre) / half_range"},
                      {"centre_deg", result.baseline_centre / kDegree},
                      {"half_range_deg", result.baseline_half_range / kDegree},
                      {"coefficients_deg", nlohmann::ordered_json::array()}};
  for (double c : result.baseline) json["baseline"]["coefficients_deg"].push_back(c / kDegree);
  nlohmann::ordered_json series;
  auto degrees = [](const std::vector<double>& values) {
    nlohmann::ordered_json list = nlohmann::ordered_json::array();
    for (double v : values) list.push_back(v / kDegree);
    return list;
  };
  series["command_deg"] = degrees(result.command);
  series["measured_deg"] = degrees(result.measured);
  series["stiffness_error_deg"] = degrees(result.stiffness_error);
  series["kinematic_error_deg"] = degrees(result.kinematic_error);
  series["fitted_deg"] = degrees(result.fitted);
  json["series"] = series;
  return json;
}

std::string transmissionSummary(const TransmissionIdentificationResult& result, const ReportSources& sources,
                                const JointErrorModel* truth) {
  std::ostringstream out;
  out << "Transmission error of " << result.joint_name << " identified from " << sources.campaign << "\n";
  out << "  " << result.samples << " points (joint angle from the " << result.angle_source << "), "
      << format("%.2f", result.stage_revolutions) << " revolutions of " << result.part
      << "; harmonics per revolution of " << result.part << "\n";
  out << "  residual RMS " << format("%.2e", result.residual_rms_rad / kDegree) << " deg";
  if (result.noise_rms_rad > 0.0) {
    out << " (stated noise " << format("%.2e", result.noise_rms_rad / kDegree) << " deg, reduced chi2 "
        << format("%.2f", result.reduced_chi2) << ")";
  }
  out << "\n\n";
  char line[256];
  const int percent = static_cast<int>(std::lround(result.confidence * 100));
  std::snprintf(line, sizeof line, "%-6s %-30s %-26s %10s %9s %-24s\n", "order", "amplitude [1e-3 deg] (CI)",
                "phase [rad] (CI)", "A/se", "p", truth ? "true amplitude, phase" : "");
  out << "  " << percent << " % intervals; significant when p < " << format("%.1e", result.significance) << " / "
      << result.candidates.size() << "\n";
  out << line;
  for (const HarmonicEstimate& h : result.candidates) {
    const HarmonicEstimate* shown = &h;
    for (const HarmonicEstimate& final_estimate : result.harmonics) {
      if (final_estimate.order == h.order) shown = &final_estimate;
    }
    const std::string amplitude = format("%.3f", shown->amplitude_rad / kDegree * 1e3) + " [" +
                                  format("%.3f", shown->amplitude_low_rad / kDegree * 1e3) + ", " +
                                  format("%.3f", shown->amplitude_high_rad / kDegree * 1e3) + "]";
    const std::string phase = format("%+.3f", shown->phase_rad) + " [" + format("%+.3f", shown->phase_low_rad) + ", " +
                              format("%+.3f", shown->phase_high_rad) + "]";
    std::string true_text;
    double a = 0.0, p = 0.0;
    if (truth && trueHarmonic(*truth, result.joint, result.stage, h.order, a, p)) {
      true_text = format("%.3f", a / kDegree * 1e3) + ", " + format("%+.3f", p);
    } else if (truth) {
      true_text = "none";
    }
    std::snprintf(line, sizeof line, "%-6g %-30s %-26s %10.1f %9.1e %-24s%s\n", h.order, amplitude.c_str(),
                  phase.c_str(), h.amplitude_to_se, h.p_value, true_text.c_str(),
                  h.significant ? "" : "  (not significant)");
    out << line;
  }
  if (!result.excluded_orders.empty()) {
    out << "  orders left out (fewer periods than needed in the sweep):";
    for (double order : result.excluded_orders) out << " " << order;
    out << "\n";
  }
  if (!sources.updated_parameters.empty()) {
    out << "\n"
        << result.harmonics.size() << " significant harmonics went into " << sources.updated_parameters << ".\n";
  }
  return out.str();
}

}  // namespace jointcomp
