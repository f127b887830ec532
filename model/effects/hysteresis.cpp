#include "model/effects/hysteresis.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/common/json_fields.hpp"

namespace jointcomp {

const std::vector<PerJointEffect::Field>& HysteresisEffect::layout() {
  static const std::vector<Field> fields = {{"width_rad_per_nm", "hysteresis_width_rad_per_nm"}};
  return fields;
}

HysteresisEffect::HysteresisEffect(const Robot& robot, std::vector<double> width, double velocity_scale)
    : PerJointEffect(robot, layout()), velocity_scale_(velocity_scale) {
  if (!(std::isfinite(velocity_scale) && velocity_scale > 0.0)) {
    throw ParameterError("hysteresis: velocity_scale_rad_per_s must be finite and positive");
  }
  setParameters(width);
}

std::unique_ptr<Effect> HysteresisEffect::fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain&,
                                          const std::string& path) {
  JsonFields fields(json, path);
  fields.text("type");
  const std::vector<double> width = readFields(fields, layout(), robot.dof());
  const double scale = fields.numberOr("velocity_scale_rad_per_s", kDefaultVelocityScale);
  const std::string note = fields.textOr("estimate", "");
  fields.rejectUnknownKeys();
  if (!(scale > 0.0)) throw ParameterError(path + ".velocity_scale_rad_per_s: must be positive");
  auto effect = std::make_unique<HysteresisEffect>(robot, width, scale);
  effect->estimate_note = note;
  return effect;
}

void HysteresisEffect::writeExtraJson(nlohmann::json& json) const { json["velocity_scale_rad_per_s"] = velocity_scale_; }

void HysteresisEffect::addJointError(const Robot&, const JointContext& ctx, JointVector& dq) const {
  if (ctx.velocity.size() != dq.size() || ctx.load_torque.size() != dq.size()) return;  // no motion (or load) known
  const std::vector<double>& width = field(0);
  for (std::size_t i = 0; i < width.size(); ++i) {
    const int j = static_cast<int>(i);
    dq[j] += width[i] * feature(ctx.velocity[j], ctx.load_torque[j], velocity_scale_);
  }
}

void HysteresisDiscovery::offer(const DiscoveryData& data, int joint, std::vector<DiscoveryCandidate>& candidates) const {
  if (joint < 0 || !data.torque_known) return;
  DiscoveryCandidate candidate;
  candidate.type = name();
  candidate.joint = joint;
  candidate.columns = featureColumn(data, [&](int i) {
    return HysteresisEffect::feature(data.velocity[i][joint], data.load_torque[i][joint], data.velocity_scale);
  });
  candidates.push_back(std::move(candidate));
}

std::unique_ptr<Effect> HysteresisDiscovery::makeEffect(const DiscoveryData& data,
                                                        const std::vector<FittedCandidate>& accepted) const {
  std::vector<double> width(static_cast<std::size_t>(data.robot->dof()), 0.0);
  for (const FittedCandidate& a : accepted) width[static_cast<std::size_t>(a.candidate->joint)] += a.theta[0];
  return std::make_unique<HysteresisEffect>(*data.robot, width, data.velocity_scale);
}

std::vector<NamedEstimate> HysteresisDiscovery::describe(const FittedCandidate& fitted, const JointErrorModel& model) const {
  const std::string& joint = model.robot().joints[static_cast<std::size_t>(fitted.candidate->joint)].name;
  return {{joint + ".hysteresis_width_rad_per_nm", fitted.theta[0], fitted.sigma[0]}};
}

}  // namespace jointcomp
