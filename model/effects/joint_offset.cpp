#include "model/effects/joint_offset.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"

namespace jointcomp {

JointOffsetEffect::JointOffsetEffect(const Robot& robot, std::vector<double> offsets_rad) {
  for (const Joint& joint : robot.joints) joint_names_.push_back(joint.name);
  if (static_cast<int>(offsets_rad.size()) != robot.dof()) {
    throw ParameterError("offset: expected " + std::to_string(robot.dof()) + " offsets, found " +
                         std::to_string(offsets_rad.size()));
  }
  setParameters(offsets_rad);
}

std::unique_ptr<Effect> JointOffsetEffect::fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain&,
                                                    const std::string& path) {
  JsonFields fields(json, path);
  fields.text("type");
  const std::vector<double> offsets = fields.numbers("offset_rad", robot.dof());
  const std::string note = fields.textOr("estimate", "");
  fields.rejectUnknownKeys();
  auto effect = std::make_unique<JointOffsetEffect>(robot, offsets);
  effect->estimate_note = note;
  return effect;
}

void JointOffsetEffect::addJointError(const Robot&, const JointContext&, JointVector& dq) const {
  for (std::size_t i = 0; i < offsets_.size(); ++i) dq[static_cast<int>(i)] += offsets_[i];
}

std::vector<std::string> JointOffsetEffect::parameterNames() const {
  std::vector<std::string> names;
  for (const auto& joint : joint_names_) names.push_back(joint + ".offset_rad");
  return names;
}

void JointOffsetEffect::setParameters(const std::vector<double>& values) {
  if (values.size() != joint_names_.size()) {
    throw ParameterError("offset: expected " + std::to_string(joint_names_.size()) + " parameters, found " +
                         std::to_string(values.size()));
  }
  // Check everything before changing anything: a rejected update leaves the effect as it was.
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) throw ParameterError("offset: " + joint_names_[i] + ".offset_rad must be finite");
  }
  offsets_ = values;
}

nlohmann::json JointOffsetEffect::toJson() const {
  nlohmann::json json = {{"type", kType}, {"offset_rad", offsets_}};
  if (!estimate_note.empty()) json["estimate"] = estimate_note;
  return json;
}

void JointOffsetDiscovery::offer(const DiscoveryData&, int joint, std::vector<DiscoveryCandidate>& candidates) const {
  if (joint < 0) return;
  DiscoveryCandidate candidate;
  candidate.type = name();
  candidate.joint = joint;
  candidate.releases = {CalibrationParameter::Offset};
  candidates.push_back(std::move(candidate));
}

}  // namespace jointcomp
