#include "model/effects/thermal_drift.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/common/json_fields.hpp"

namespace jointcomp {

ThermalDriftEffect::ThermalDriftEffect(const Robot& robot, std::vector<double> coefficient_rad_per_degc,
                                       double reference_temperature_degc, std::vector<double> drift_rad_per_s,
                                       double reference_time_s)
    : t0_degc_(reference_temperature_degc), t0_s_(reference_time_s) {
  for (const Joint& joint : robot.joints) joint_names_.push_back(joint.name);
  if (!std::isfinite(t0_degc_)) throw ParameterError("thermal: reference_temperature_degc must be finite");
  if (!std::isfinite(t0_s_)) throw ParameterError("thermal: reference_time_s must be finite");
  if (coefficient_rad_per_degc.size() != joint_names_.size() || drift_rad_per_s.size() != joint_names_.size()) {
    throw ParameterError("thermal: expected " + std::to_string(joint_names_.size()) +
                         " coefficients and drifts, found " + std::to_string(coefficient_rad_per_degc.size()) + " and " +
                         std::to_string(drift_rad_per_s.size()));
  }
  std::vector<double> all = coefficient_rad_per_degc;
  all.insert(all.end(), drift_rad_per_s.begin(), drift_rad_per_s.end());
  setParameters(all);
}

std::unique_ptr<Effect> ThermalDriftEffect::fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain&,
                                                     const std::string& path) {
  JsonFields fields(json, path);
  fields.text("type");
  const std::vector<double> coefficient = fields.numbers("coefficient_rad_per_degc", robot.dof());
  const double t0 = fields.numberOr("reference_temperature_degc", 20.0);
  std::vector<double> drift(static_cast<std::size_t>(robot.dof()), 0.0);
  if (json.contains("drift_rad_per_s")) drift = fields.numbers("drift_rad_per_s", robot.dof());
  const double time0 = fields.numberOr("reference_time_s", 0.0);
  const std::string note = fields.textOr("estimate", "");
  fields.rejectUnknownKeys();
  auto effect = std::make_unique<ThermalDriftEffect>(robot, coefficient, t0, drift, time0);
  effect->estimate_note = note;
  return effect;
}

void ThermalDriftEffect::addJointError(const Robot&, const JointContext& ctx, JointVector& dq) const {
  const double dt = ctx.temperature - t0_degc_;
  const double dtime = ctx.time - t0_s_;
  for (std::size_t i = 0; i < coefficient_.size(); ++i) {
    dq[static_cast<int>(i)] += coefficient_[i] * dt + drift_[i] * dtime;
  }
}

std::vector<std::string> ThermalDriftEffect::parameterNames() const {
  std::vector<std::string> names;
  for (const auto& joint : joint_names_) names.push_back(joint + ".thermal_rad_per_degc");
  for (const auto& joint : joint_names_) names.push_back(joint + ".drift_rad_per_s");
  return names;
}

std::vector<double> ThermalDriftEffect::parameters() const {
  std::vector<double> all = coefficient_;
  all.insert(all.end(), drift_.begin(), drift_.end());
  return all;
}

void ThermalDriftEffect::setParameters(const std::vector<double>& values) {
  const std::size_t n = joint_names_.size();
  if (values.size() != 2 * n) {
    throw ParameterError("thermal: expected " + std::to_string(2 * n) + " parameters, found " +
                         std::to_string(values.size()));
  }
  const std::vector<std::string> names = parameterNames();
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) throw ParameterError("thermal: " + names[i] + " must be finite");
  }
  coefficient_.assign(values.begin(), values.begin() + static_cast<long>(n));
  drift_.assign(values.begin() + static_cast<long>(n), values.end());
}

nlohmann::json ThermalDriftEffect::toJson() const {
  nlohmann::json json = {{"type", kType},
                         {"coefficient_rad_per_degc", coefficient_},
                         {"reference_temperature_degc", t0_degc_},
                         {"drift_rad_per_s", drift_},
                         {"reference_time_s", t0_s_}};
  if (!estimate_note.empty()) json["estimate"] = estimate_note;
  return json;
}

void ThermalDriftDiscovery::offer(const DiscoveryData& data, int joint, std::vector<DiscoveryCandidate>& candidates) const {
  if (joint < 0) return;
  DiscoveryCandidate candidate;
  candidate.type = name();
  candidate.joint = joint;
  candidate.releases = {CalibrationParameter::Offset};
  if (data.have_temperature) {
    candidate.part = "temperature";
    candidate.detail = " (temperature)";
    candidate.columns = featureColumn(data, [&](int i) { return data.temperature[i] - data.temperature0; });
    candidates.push_back(candidate);
  }
  candidate.part = "time";
  candidate.detail = " (time)";
  candidate.columns = featureColumn(data, [&](int i) { return data.time[i] - data.time0; });
  candidates.push_back(std::move(candidate));
}

std::unique_ptr<Effect> ThermalDriftDiscovery::makeEffect(const DiscoveryData& data,
                                                          const std::vector<FittedCandidate>& accepted) const {
  const std::size_t n = static_cast<std::size_t>(data.robot->dof());
  std::vector<double> thermal(n, 0.0), drift(n, 0.0);
  for (const FittedCandidate& a : accepted) {
    (a.candidate->part == "time" ? drift : thermal)[static_cast<std::size_t>(a.candidate->joint)] += a.theta[0];
  }
  return std::make_unique<ThermalDriftEffect>(*data.robot, thermal, data.temperature0, drift, data.time0);
}

std::vector<NamedEstimate> ThermalDriftDiscovery::describe(const FittedCandidate& fitted, const JointErrorModel& model) const {
  const std::string& joint = model.robot().joints[static_cast<std::size_t>(fitted.candidate->joint)].name;
  const char* suffix = fitted.candidate->part == "time" ? ".drift_rad_per_s" : ".thermal_rad_per_degc";
  return {{joint + suffix, fitted.theta[0], fitted.sigma[0]}};
}

}  // namespace jointcomp
