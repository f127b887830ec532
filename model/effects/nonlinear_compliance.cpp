#include "model/effects/nonlinear_compliance.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/common/json_fields.hpp"

namespace jointcomp {

NonlinearComplianceEffect::NonlinearComplianceEffect(const Robot& robot, std::vector<double> cubic_rad_per_nm3) {
  for (const Joint& joint : robot.joints) joint_names_.push_back(joint.name);
  setParameters(cubic_rad_per_nm3);
}

std::unique_ptr<Effect> NonlinearComplianceEffect::fromJson(const nlohmann::json& json, const Robot& robot,
                                                            const GearTrain&, const std::string& path) {
  JsonFields fields(json, path);
  fields.text("type");
  const std::vector<double> cubic = fields.numbers("cubic_compliance_rad_per_nm3", robot.dof());
  const std::string note = fields.textOr("estimate", "");
  fields.rejectUnknownKeys();
  auto effect = std::make_unique<NonlinearComplianceEffect>(robot, cubic);
  effect->estimate_note = note;
  return effect;
}

void NonlinearComplianceEffect::addJointError(const Robot&, const JointContext& ctx, JointVector& dq) const {
  if (ctx.load_torque.size() != dq.size()) return;
  for (std::size_t i = 0; i < cubic_.size(); ++i) {
    const int j = static_cast<int>(i);
    dq[j] += cubic_[i] * feature(ctx.load_torque[j]);
  }
}

std::vector<std::string> NonlinearComplianceEffect::parameterNames() const {
  std::vector<std::string> names;
  for (const auto& joint : joint_names_) names.push_back(joint + ".cubic_compliance_rad_per_nm3");
  return names;
}

void NonlinearComplianceEffect::setParameters(const std::vector<double>& values) {
  if (values.size() != joint_names_.size()) {
    throw ParameterError("nonlinear_compliance: expected " + std::to_string(joint_names_.size()) +
                         " coefficients, found " + std::to_string(values.size()));
  }
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) {
      throw ParameterError("nonlinear_compliance: " + joint_names_[i] + ".cubic_compliance_rad_per_nm3 must be finite");
    }
  }
  cubic_ = values;
}

nlohmann::json NonlinearComplianceEffect::toJson() const {
  nlohmann::json json = {{"type", kType}, {"cubic_compliance_rad_per_nm3", cubic_}};
  if (!estimate_note.empty()) json["estimate"] = estimate_note;
  return json;
}

void NonlinearComplianceDiscovery::offer(const DiscoveryData& data, int joint,
                                         std::vector<DiscoveryCandidate>& candidates) const {
  if (joint < 0 || !data.torque_known) return;
  DiscoveryCandidate candidate;
  candidate.type = name();
  candidate.joint = joint;
  candidate.columns = featureColumn(data, [&](int i) { return NonlinearComplianceEffect::feature(data.load_torque[i][joint]); });
  candidates.push_back(std::move(candidate));
}

std::unique_ptr<Effect> NonlinearComplianceDiscovery::makeEffect(const DiscoveryData& data,
                                                                 const std::vector<FittedCandidate>& accepted) const {
  std::vector<double> cubic(static_cast<std::size_t>(data.robot->dof()), 0.0);
  for (const FittedCandidate& a : accepted) cubic[static_cast<std::size_t>(a.candidate->joint)] += a.theta[0];
  return std::make_unique<NonlinearComplianceEffect>(*data.robot, cubic);
}

std::vector<NamedEstimate> NonlinearComplianceDiscovery::describe(const FittedCandidate& fitted,
                                                                  const JointErrorModel& model) const {
  const std::string& joint = model.robot().joints[static_cast<std::size_t>(fitted.candidate->joint)].name;
  return {{joint + ".cubic_compliance_rad_per_nm3", fitted.theta[0], fitted.sigma[0]}};
}

}  // namespace jointcomp
