// Load-dependent hysteresis (friction lost motion of the transmission): the link lags the command, in the
// direction it was approached, by half a lost motion that grows with the torque the joint carries,
//   dq_j = -h_j / 2 * |tau_j| * tanh(v_j / v_s)
// with h_j the width of the loop per N m (rad / (N m)), tau_j the joint's load torque
// (JointContext::load_torque) and s_j the side of the lost motion, remembered at rest and tanh(v_j / v_s)
// in continuous motion exactly as for backlash (backlash.hpp), with the same small velocity scale v_s.
//
// Why this model: in a gear transmission under load (harmonic drives in particular) the teeth, the wave
// generator and the flexspline slide under a normal force proportional to the transmitted torque, so the
// friction that holds the link when it stops is a fraction of |tau| (Coulomb: mu N). Approached from
// below, the link stops short by that friction over the joint stiffness; approached from above it stops
// beyond: the torque-deflection curve has a loop whose width is proportional to the load (the "hysteresis
// loss" of gear catalogues, specified as a fraction of rated torque), and it flips with the direction of
// motion. Backlash (backlash.hpp) is the part of the lost motion that does not depend on the load (play
// between teeth): b/2 for every pose; hysteresis is zero for an unloaded joint and largest where gravity
// loads it most, so the two are told apart by how the lag varies with the pose. The model is linear in h_j,
// which discovery fits; its only memory is the side of the last move (no Dahl or Bouc-Wen internal state).
// Parameter file:
//   {"type": "hysteresis", "width_rad_per_nm": [n values], "velocity_scale_rad_per_s": 0.001}
// A negative width (the link leads) is accepted: discovery fits the sign.
#pragma once

#include <cmath>

#include "model/effects/discovery_family.hpp"
#include "model/effects/effect.hpp"
#include "model/effects/gear_train.hpp"
#include "model/effects/per_joint_effect.hpp"

namespace jointcomp {

class HysteresisEffect : public PerJointEffect {
public:
  static constexpr const char* kType = "hysteresis";
  static constexpr double kDefaultVelocityScale = 1e-3;  // rad/s, as backlash
  // Throws ParameterError for the wrong number of widths, a width that is not finite or a scale <= 0.
  HysteresisEffect(const Robot& robot, const std::vector<double>& width_rad_per_nm,
                   double velocity_scale = kDefaultVelocityScale);
  static std::unique_ptr<Effect> fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain& gears,
                                          const std::string& path);

  // The file format: the fields (and scalars) the parameter file holds.
  static const std::vector<Scalar>& scalarLayout();  // velocity_scale_rad_per_s
  static const std::vector<Field>& layout();         // "<joint>.hysteresis_width_rad_per_nm"
  static std::unique_ptr<Effect> fromValues(const Robot& robot, const std::vector<double>& values,
                                            const std::vector<double>& scalars);

  std::string type() const override { return kType; }
  EffectRole role() const override { return EffectRole::JointError; }
  void addJointError(const Robot& robot, const JointContext& ctx, JointVector& dq) const override;
  std::unique_ptr<Effect> clone() const override { return std::make_unique<HysteresisEffect>(*this); }

  double velocityScale() const { return scalar(0); }
  // The factor of h_j in dq_j: -|tau| s / 2.
  static double feature(double side, double torque) { return -0.5 * std::abs(torque) * side; }
};

// Discovery: "hysteresis", one column per joint, -|tau_j| tanh(v_j / v_s) / 2 (needs the load torque).
class HysteresisDiscovery : public PerJointFeatureDiscovery {
public:
  HysteresisDiscovery() : PerJointFeatureDiscovery("hysteresis", "hysteresis_width_rad_per_nm", true) {}
  // Physical: a lost motion lags the motion (width not negative) and turns the joint by at most
  // kMaxPlausibleJointError over the fitted rows.
  std::string physicalProblem(const DiscoveryData& data, const DiscoveryCandidate& candidate,
                              const Eigen::VectorXd& theta, const JointVector& compliance) const override;

protected:
  double feature(const DiscoveryData& data, int row, int joint) const override;
  std::unique_ptr<Effect> effectOf(const DiscoveryData& data, const std::vector<double>& width) const override;
};

}  // namespace jointcomp
