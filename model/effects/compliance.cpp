#include "model/effects/compliance.hpp"

#include <cmath>
#include <limits>

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
  // null marks a joint taken as rigid (no compliance known or identifiable).
  const nlohmann::json& list = fields.array("stiffness_nm_per_rad");
  if (static_cast<int>(list.size()) != robot.dof()) {
    fields.fail("stiffness_nm_per_rad", "expected " + std::to_string(robot.dof()) + " values, found " +
                                            std::to_string(list.size()));
  }
  std::vector<double> stiffness;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string element = "stiffness_nm_per_rad[" + std::to_string(i) + "]";
    if (list[i].is_null()) {
      stiffness.push_back(std::numeric_limits<double>::infinity());
      continue;
    }
    if (!list[i].is_number()) fields.fail(element, "expected a number or null (rigid)");
    const double value = list[i].get<double>();
    if (!std::isfinite(value)) fields.fail(element, "not finite");
    if (!(value > 0.0)) fields.fail(element, "must be positive");
    stiffness.push_back(value);
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
    if (std::isnan(values[i]) || !(values[i] > 0.0)) {
      throw ParameterError("compliance: " + joint_names_[i] +
                           ".stiffness_nm_per_rad must be positive (+infinity for a rigid joint)");
    }
  }
  compliance_.resize(static_cast<int>(values.size()));
  for (std::size_t i = 0; i < values.size(); ++i) compliance_[static_cast<int>(i)] = 1.0 / values[i];
  stiffness_ = values;
}

nlohmann::json ComplianceEffect::toJson() const {
  nlohmann::json stiffness = nlohmann::json::array();
  for (double k : stiffness_) stiffness.push_back(std::isinf(k) ? nlohmann::json(nullptr) : nlohmann::json(k));
  nlohmann::json json = {{"type", kType}, {"stiffness_nm_per_rad", stiffness}};
  if (!estimate_note.empty()) json["estimate"] = estimate_note;
  return json;
}

void ComplianceDiscovery::offer(const DiscoveryData& data, int joint, std::vector<DiscoveryCandidate>& candidates) const {
  if (joint < 0 || !data.torque_known) return;
  DiscoveryCandidate candidate;
  candidate.type = name();
  candidate.joint = joint;
  candidate.releases = {CalibrationParameter::Compliance};
  candidates.push_back(std::move(candidate));
}

}  // namespace jointcomp
