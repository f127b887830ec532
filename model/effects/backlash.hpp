// Backlash (lost motion): the link lags the command by half the play on the side it was approached from,
//   dq_j = -b_j / 2 * s_j
// with b_j the width of the play (rad) and s_j the side. A robot at rest between moves (a measurement
// campaign) remembers it: s_j is the sign of the last move of that joint, however small or long ago
// (JointContext::approach, kept by LostMotionMemory), and 0 before the joint's first move (side not
// known: no error is claimed there). In continuous motion (a planned path) the side follows
// the velocity, s_j = tanh(v_j / v_s) with v_s a small velocity scale: the smooth sign keeps the error
// continuous, so that the plant, which puts every non-compliance joint-error effect into its
// transmission, does not hand its integrator a jump when a joint reverses; with v_s = 1e-3 rad/s it
// equals the sign for any real move. Parameter file:
//   {"type": "backlash", "width_rad": [n values], "velocity_scale_rad_per_s": 0.001}
// A negative width (the link leads) is accepted: discovery fits the sign.
#pragma once

#include <cmath>

#include "model/effects/discovery_family.hpp"
#include "model/effects/effect.hpp"
#include "model/effects/gear_train.hpp"
#include "model/effects/per_joint_effect.hpp"

namespace jointcomp {

// The side of each joint's lost motion as the last move of that joint set it: a move of any size beyond
// kStill (far below any encoder's resolution, so that rounding in a command file is no move) sets it to
// the move's sign, a joint that does not move keeps it however long it rests, and a joint not seen moving
// yet has side 0 (not known).
class LostMotionMemory {
public:
  static constexpr double kStill = 1e-9;  // rad (or rad/s: only the sign of a move counts)
  explicit LostMotionMemory(int dof) : side_(JointVector::Zero(dof)) {}
  // Records a move (the command's change, or the velocity of the move) and returns the sides after it.
  const JointVector& move(const JointVector& change) {
    for (int j = 0; j < side_.size(); ++j) {
      if (change[j] > kStill) side_[j] = 1.0;
      if (change[j] < -kStill) side_[j] = -1.0;
    }
    return side_;
  }
  const JointVector& sides() const { return side_; }

private:
  JointVector side_;
};

// The side of joint j's lost motion in `ctx`: the remembered side when the context has one, else the
// smooth sign of the velocity (continuous motion); 0 when neither is known.
double lostMotionSide(const JointContext& ctx, int j, double velocity_scale);

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
  // The factor of b_j in dq_j: -s_j / 2.
  static double feature(double side) { return -0.5 * side; }
};

// Discovery: "backlash", one column per joint, -s_j / 2 with s_j remembered along the command sequence.
class BacklashDiscovery : public PerJointFeatureDiscovery {
public:
  BacklashDiscovery() : PerJointFeatureDiscovery("backlash", "backlash_width_rad", false) {}
  // Physical: a lost motion lags the motion (width not negative) and turns the joint by at most
  // kMaxPlausibleJointError over the fitted rows.
  std::string physicalProblem(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                              const Eigen::VectorXd& theta, const JointVector& compliance) const override;

protected:
  double feature(const DiscoveryData& data, int row, int joint) const override;
  std::unique_ptr<Effect> effectOf(const DiscoveryData& data, const std::vector<double>& width) const override;
};

}  // namespace jointcomp
