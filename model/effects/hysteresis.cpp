#include "model/effects/hysteresis.hpp"

#include <cmath>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"
#include "model/effects/backlash.hpp"

namespace jointcomp {

const std::vector<PerJointEffect::Field>& HysteresisEffect::layout() {
  static const std::vector<Field> fields = {{"width_rad_per_nm", "hysteresis_width_rad_per_nm"}};
  return fields;
}

const std::vector<PerJointEffect::Scalar>& HysteresisEffect::scalarLayout() {
  static const std::vector<Scalar> scalars = {{"velocity_scale_rad_per_s", kDefaultVelocityScale, Check::Positive}};
  return scalars;
}

HysteresisEffect::HysteresisEffect(const Robot& robot, const std::vector<double>& width, double velocity_scale)
    : PerJointEffect(robot, layout(), scalarLayout()) {
  setScalars({velocity_scale});
  setParameters(width);
}

std::unique_ptr<Effect> HysteresisEffect::fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain&,
                                                   const std::string& path) {
  return readAs<HysteresisEffect>(json, robot, path);
}

std::unique_ptr<Effect> HysteresisEffect::fromValues(const Robot& robot, const std::vector<double>& values,
                                                     const std::vector<double>& scalars) {
  return std::make_unique<HysteresisEffect>(robot, values, scalars[0]);
}

void HysteresisEffect::addJointError(const Robot&, const JointContext& ctx, JointVector& dq) const {
  if (ctx.load_torque.size() != dq.size()) return;  // no load known
  const std::vector<double>& width = field(0);
  for (std::size_t i = 0; i < width.size(); ++i) {
    const int j = static_cast<int>(i);
    dq[j] += width[i] * feature(lostMotionSide(ctx, j, scalar(0)), ctx.load_torque[j]);
  }
}

double HysteresisDiscovery::feature(const DiscoveryData& data, int row, int joint) const {
  return HysteresisEffect::feature(data.approach[row][joint], data.load_torque[row][joint]);
}

std::unique_ptr<Effect> HysteresisDiscovery::effectOf(const DiscoveryData& data,
                                                      const std::vector<double>& width) const {
  return std::make_unique<HysteresisEffect>(*data.robot, width, data.velocity_scale);
}

std::string HysteresisDiscovery::physicalProblem(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                                                 const Eigen::VectorXd& theta, const JointVector&) const {
  const int j = candidate.joint;
  if (j < 0 || theta.size() != 1) return {};
  const double width = theta[0];
  const double turn =
      std::abs(width) * 0.5 * largestTorque(data, j);  // rad, the most it moves the joint over the fitted rows
  char text[240];
  if (width < 0.0) {
    std::snprintf(text, sizeof(text),
                  "not physical: %s's hysteresis width %.3g rad/(N m) is negative (the link would lead the motion)",
                  jointNameOf(data, j).c_str(), width);
  } else if (turn > kMaxPlausibleJointError) {
    std::snprintf(
        text, sizeof(text),
        "not physical: %s's hysteresis width %.3g rad/(N m) turns the joint by %.3g rad, beyond the plausible %.3g rad",
        jointNameOf(data, j).c_str(), width, turn, kMaxPlausibleJointError);
  } else {
    return {};
  }
  return text;
}

}  // namespace jointcomp
