#include "model/effects/thermal_drift.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"
#include "model/effects/joint_error_model.hpp"

namespace jointcomp {

const std::vector<PerJointEffect::Field>& ThermalDriftEffect::layout() {
  static const std::vector<Field> fields = {{"coefficient_rad_per_degc", "thermal_rad_per_degc"},
                                            {"drift_rad_per_s", "drift_rad_per_s", Check::Finite, true}};
  return fields;
}

const std::vector<PerJointEffect::Scalar>& ThermalDriftEffect::scalarLayout() {
  static const std::vector<Scalar> scalars = {{"reference_temperature_degc", 20.0}, {"reference_time_s", 0.0}};
  return scalars;
}

ThermalDriftEffect::ThermalDriftEffect(const Robot& robot, const std::vector<double>& coefficient_rad_per_degc,
                                       double reference_temperature_degc, const std::vector<double>& drift_rad_per_s,
                                       double reference_time_s)
    : PerJointEffect(robot, layout(), scalarLayout()) {
  setScalars({reference_temperature_degc, reference_time_s});
  if (coefficient_rad_per_degc.size() != jointCount() || drift_rad_per_s.size() != jointCount()) {
    throw ParameterError("thermal: expected " + std::to_string(jointCount()) + " coefficients and drifts, found " +
                         std::to_string(coefficient_rad_per_degc.size()) + " and " +
                         std::to_string(drift_rad_per_s.size()));
  }
  setParameters(joined({&coefficient_rad_per_degc, &drift_rad_per_s}));
}

std::unique_ptr<Effect> ThermalDriftEffect::fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain&,
                                                     const std::string& path) {
  return readAs<ThermalDriftEffect>(json, robot, path);
}

std::unique_ptr<Effect> ThermalDriftEffect::fromValues(const Robot& robot, const std::vector<double>& values,
                                                       const std::vector<double>& scalars) {
  const auto n = static_cast<long>(robot.dof());
  return std::make_unique<ThermalDriftEffect>(robot, std::vector<double>(values.begin(), values.begin() + n),
                                              scalars[0], std::vector<double>(values.begin() + n, values.end()),
                                              scalars[1]);
}

void ThermalDriftEffect::addJointError(const Robot&, const JointContext& ctx, JointVector& dq) const {
  const double dt = ctx.temperature - scalar(0);
  const double dtime = ctx.time - scalar(1);
  const std::vector<double>& coefficient = field(0);
  const std::vector<double>& drift = field(1);
  for (std::size_t i = 0; i < coefficient.size(); ++i) {
    dq[static_cast<int>(i)] += coefficient[i] * dt + drift[i] * dtime;
  }
}

void ThermalDriftDiscovery::offer(const DiscoveryData& data, int joint,
                                  std::vector<DiscoveryCandidate>& candidates) const {
  if (joint < 0) return;
  DiscoveryCandidate candidate;
  candidate.type = name();
  candidate.joint = joint;
  candidate.releases = {CalibrationParameter::Offset};
  if (data.have_temperature) {
    candidate.part = "temperature";
    candidate.detail = " (temperature)";
    candidate.report_fields = {{"variant", candidate.part}};
    candidate.columns = featureColumn(data, [&](int i) { return data.temperature[i] - data.temperature0; });
    candidates.push_back(candidate);
  }
  candidate.part = "time";
  candidate.detail = " (time)";
  candidate.report_fields = {{"variant", candidate.part}};
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

std::vector<NamedEstimate> ThermalDriftDiscovery::describe(const FittedCandidate& fitted,
                                                           const JointErrorModel& model) const {
  const std::string& joint = model.robot().joints[static_cast<std::size_t>(fitted.candidate->joint)].name;
  const char* suffix = fitted.candidate->part == "time" ? ".drift_rad_per_s" : ".thermal_rad_per_degc";
  return {{joint + suffix, fitted.theta[0], fitted.sigma[0]}};
}

}  // namespace jointcomp
