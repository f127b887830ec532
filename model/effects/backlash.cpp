#include "model/effects/backlash.hpp"

#include <cmath>
#include <cstdio>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"

namespace jointcomp {

const std::vector<PerJointEffect::Field>& BacklashEffect::layout() {
  static const std::vector<Field> fields = {{"width_rad", "backlash_width_rad"}};
  return fields;
}

const std::vector<PerJointEffect::Scalar>& BacklashEffect::scalarLayout() {
  static const std::vector<Scalar> scalars = {{"velocity_scale_rad_per_s", kDefaultVelocityScale, Check::Positive}};
  return scalars;
}

BacklashEffect::BacklashEffect(const Robot& robot, const std::vector<double>& width, double velocity_scale)
    : PerJointEffect(robot, layout(), scalarLayout()) {
  setScalars({velocity_scale});
  setParameters(width);
}

std::unique_ptr<Effect> BacklashEffect::fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain&,
                                                 const std::string& path) {
  return readAs<BacklashEffect>(json, robot, path);
}

std::unique_ptr<Effect> BacklashEffect::fromValues(const Robot& robot, const std::vector<double>& values,
                                                   const std::vector<double>& scalars) {
  return std::make_unique<BacklashEffect>(robot, values, scalars[0]);
}

double lostMotionSide(const JointContext& ctx, int j, double velocity_scale) {
  if (ctx.approach.size() > j) return ctx.approach[j];
  if (ctx.velocity.size() > j) return std::tanh(ctx.velocity[j] / velocity_scale);
  return 0.0;
}

void BacklashEffect::addJointError(const Robot&, const JointContext& ctx, JointVector& dq) const {
  const std::vector<double>& width = field(0);
  for (std::size_t i = 0; i < width.size(); ++i) {
    const int j = static_cast<int>(i);
    dq[j] += width[i] * feature(lostMotionSide(ctx, j, scalar(0)));
  }
}

double BacklashDiscovery::feature(const DiscoveryData& data, int row, int joint) const {
  return BacklashEffect::feature(data.approach[row][joint]);
}

std::unique_ptr<Effect> BacklashDiscovery::effectOf(const DiscoveryData& data, const std::vector<double>& width) const {
  return std::make_unique<BacklashEffect>(*data.robot, width, data.velocity_scale);
}

std::string BacklashDiscovery::physicalProblem(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                                               const Eigen::VectorXd& theta, const JointVector&) const {
  const int j = candidate.joint;
  if (j < 0 || theta.size() != 1) return {};
  const double width = theta[0];
  const double turn = std::abs(width) * 0.5;  // rad, the most it moves the joint over the fitted rows
  char text[240];
  if (width < 0.0) {
    std::snprintf(text, sizeof(text),
                  "not physical: %s's backlash width %.3g rad is negative (the link would lead the motion)",
                  jointNameOf(data, j).c_str(), width);
  } else if (turn > kMaxPlausibleJointError) {
    std::snprintf(
        text, sizeof(text),
        "not physical: %s's backlash width %.3g rad turns the joint by %.3g rad, beyond the plausible %.3g rad",
        jointNameOf(data, j).c_str(), width, turn, kMaxPlausibleJointError);
  } else {
    return {};
  }
  return text;
}

}  // namespace jointcomp
