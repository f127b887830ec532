#include "model/effects/compliance.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"

namespace jointcomp {

ComplianceEffect::ComplianceEffect(const Robot& robot, std::vector<double> stiffness_nm_per_rad) {
  for (const Joint& joint : robot.joints) joint_names_.push_back(joint.name);
  if (static_cast<int>(stiffness_nm_per_rad.size()) != robot.dof()) {
    throw ParameterError("compliance: expected " + std::to_string(robot.dof()) + " stiffnesses, found " +
                         std::to_string(stiffness_nm_per_rad.size()));
  }
  setParameters(stiffness_nm_per_rad);
}

std::unique_ptr<Effect> ComplianceEffect::fromJson(const nlohmann::json& json, const Robot& robot, const std::string& path) {
  JsonFields fields(json, path);
  fields.text("type");
  const std::vector<double> stiffness = fields.numbers("stiffness_nm_per_rad", robot.dof());
  for (std::size_t i = 0; i < stiffness.size(); ++i) {
    if (!(stiffness[i] > 0.0)) fields.fail("stiffness_nm_per_rad[" + std::to_string(i) + "]", "must be positive");
  }
  const std::string note = fields.textOr("estimate", "");
  fields.rejectUnknownKeys();
  auto effect = std::make_unique<ComplianceEffect>(robot, stiffness);
  effect->estimate_note = note;
  return effect;
}

void ComplianceEffect::addJointError(const Robot&, const JointContext& ctx, JointVector& dq) const {
  dq -= ctx.load_torque.cwiseProduct(compliance_);
}

std::vector<std::string> ComplianceEffect::parameterNames() const {
  std::vector<std::string> names;
  for (const auto& joint : joint_names_) names.push_back(joint + ".stiffness_nm_per_rad");
  return names;
}

void ComplianceEffect::setParameters(const std::vector<double>& values) {
  if (values.size() != joint_names_.size()) throw ParameterError("compliance: wrong number of parameters");
  // Check everything before changing anything: a rejected update leaves the effect as it was.
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i]) || !(values[i] > 0.0)) {
      throw ParameterError("compliance: " + joint_names_[i] + ".stiffness_nm_per_rad must be positive and finite");
    }
  }
  compliance_.resize(static_cast<int>(values.size()));
  for (std::size_t i = 0; i < values.size(); ++i) compliance_[static_cast<int>(i)] = 1.0 / values[i];
  stiffness_ = values;
}

nlohmann::json ComplianceEffect::toJson() const {
  nlohmann::json json = {{"type", kType}, {"stiffness_nm_per_rad", stiffness_}};
  if (!estimate_note.empty()) json["estimate"] = estimate_note;
  return json;
}

}  // namespace jointcomp
