#include "model/effects/backlash.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/common/json_fields.hpp"

namespace jointcomp {

BacklashEffect::BacklashEffect(const Robot& robot, std::vector<double> width_rad, double velocity_scale)
    : velocity_scale_(velocity_scale) {
  for (const Joint& joint : robot.joints) joint_names_.push_back(joint.name);
  if (!(std::isfinite(velocity_scale) && velocity_scale > 0.0)) {
    throw ParameterError("backlash: velocity_scale_rad_per_s must be finite and positive");
  }
  setParameters(width_rad);
}

std::unique_ptr<Effect> BacklashEffect::fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain&,
                                                 const std::string& path) {
  JsonFields fields(json, path);
  fields.text("type");
  const std::vector<double> width = fields.numbers("width_rad", robot.dof());
  const double scale = fields.numberOr("velocity_scale_rad_per_s", kDefaultVelocityScale);
  const std::string note = fields.textOr("estimate", "");
  fields.rejectUnknownKeys();
  if (!(scale > 0.0)) throw ParameterError(path + ".velocity_scale_rad_per_s: must be positive");
  auto effect = std::make_unique<BacklashEffect>(robot, width, scale);
  effect->estimate_note = note;
  return effect;
}

void BacklashEffect::addJointError(const Robot&, const JointContext& ctx, JointVector& dq) const {
  if (ctx.velocity.size() != dq.size()) return;  // no motion known
  for (std::size_t i = 0; i < width_.size(); ++i) {
    const int j = static_cast<int>(i);
    dq[j] += width_[i] * feature(ctx.velocity[j], velocity_scale_);
  }
}

std::vector<std::string> BacklashEffect::parameterNames() const {
  std::vector<std::string> names;
  for (const auto& joint : joint_names_) names.push_back(joint + ".backlash_width_rad");
  return names;
}

void BacklashEffect::setParameters(const std::vector<double>& values) {
  if (values.size() != joint_names_.size()) {
    throw ParameterError("backlash: expected " + std::to_string(joint_names_.size()) + " widths, found " +
                         std::to_string(values.size()));
  }
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) throw ParameterError("backlash: " + joint_names_[i] + ".backlash_width_rad must be finite");
  }
  width_ = values;
}

nlohmann::json BacklashEffect::toJson() const {
  nlohmann::json json = {{"type", kType}, {"width_rad", width_}, {"velocity_scale_rad_per_s", velocity_scale_}};
  if (!estimate_note.empty()) json["estimate"] = estimate_note;
  return json;
}

void BacklashDiscovery::offer(const DiscoveryData& data, int joint, std::vector<DiscoveryCandidate>& candidates) const {
  if (joint < 0) return;
  DiscoveryCandidate candidate;
  candidate.type = name();
  candidate.joint = joint;
  candidate.columns = featureColumn(data, [&](int i) { return BacklashEffect::feature(data.velocity[i][joint], data.velocity_scale); });
  candidates.push_back(std::move(candidate));
}

std::unique_ptr<Effect> BacklashDiscovery::makeEffect(const DiscoveryData& data,
                                                      const std::vector<FittedCandidate>& accepted) const {
  std::vector<double> width(static_cast<std::size_t>(data.robot->dof()), 0.0);
  for (const FittedCandidate& a : accepted) width[static_cast<std::size_t>(a.candidate->joint)] += a.theta[0];
  return std::make_unique<BacklashEffect>(*data.robot, width, data.velocity_scale);
}

std::vector<NamedEstimate> BacklashDiscovery::describe(const FittedCandidate& fitted, const JointErrorModel& model) const {
  const std::string& joint = model.robot().joints[static_cast<std::size_t>(fitted.candidate->joint)].name;
  return {{joint + ".backlash_width_rad", fitted.theta[0], fitted.sigma[0]}};
}

}  // namespace jointcomp
