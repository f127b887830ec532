// Backlash (lost motion): the link lags the command by half the play in the direction it was approached,
//   dq_j = -b_j / 2 * tanh(v_j / v_s)
// with b_j the width of the play (rad), v_j the joint's velocity (JointContext::velocity, the direction
// of approach: campaigns set it from the command sequence) and v_s a small velocity scale. The smooth
// sign (tanh instead of sign) keeps the error continuous in the velocity, so that the plant, which puts
// every non-compliance joint-error effect into its transmission, does not hand its integrator a jump
// when a joint reverses; with v_s = 1e-3 rad/s it equals the sign for any real move. A joint at rest
// (v = 0) gets no error: the side it rests on is not known from the context alone. Parameter file:
//   {"type": "backlash", "width_rad": [n values], "velocity_scale_rad_per_s": 0.001}
// A negative width (the link leads) is accepted: discovery fits the sign.
#pragma once

#include <cmath>

#include "model/effects/discovery_family.hpp"
#include "model/effects/effect.hpp"
#include "model/effects/gear_train.hpp"
#include "model/effects/per_joint_effect.hpp"

namespace jointcomp {

class BacklashEffect : public PerJointEffect {
public:
  static constexpr const char* kType = "backlash";
  static constexpr double kDefaultVelocityScale = 1e-3;  // rad/s
  // Throws ParameterError for the wrong number of widths, a width that is not finite or a scale <= 0.
  BacklashEffect(const Robot& robot, const std::vector<double>& width_rad,
                 double velocity_scale = kDefaultVelocityScale);
  static std::unique_ptr<Effect> fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain& gears,
                                          const std::string& path);

  // The file format: the fields (and scalars) the parameter file holds.
  static const std::vector<Scalar>& scalarLayout();  // velocity_scale_rad_per_s
  static const std::vector<Field>& layout();         // "<joint>.backlash_width_rad"
  static std::unique_ptr<Effect> fromValues(const Robot& robot, const std::vector<double>& values,
                                            const std::vector<double>& scalars);

  std::string type() const override { return kType; }
  EffectRole role() const override { return EffectRole::JointError; }
  void addJointError(const Robot& robot, const JointContext& ctx, JointVector& dq) const override;
  std::unique_ptr<Effect> clone() const override { return std::make_unique<BacklashEffect>(*this); }

  double velocityScale() const { return scalar(0); }
  // The factor of b_j in dq_j: -tanh(v / v_s) / 2.
  static double feature(double velocity, double velocity_scale) { return -0.5 * std::tanh(velocity / velocity_scale); }
};

// Discovery: "backlash", one column per joint, -tanh(v_j / v_s) / 2 with v_j from the command sequence.
class BacklashDiscovery : public PerJointFeatureDiscovery {
public:
  BacklashDiscovery() : PerJointFeatureDiscovery("backlash", "backlash_width_rad", false) {}

protected:
  double feature(const DiscoveryData& data, int row, int joint) const override;
  std::unique_ptr<Effect> effectOf(const DiscoveryData& data, const std::vector<double>& width) const override;
};

}  // namespace jointcomp
