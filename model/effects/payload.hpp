// A payload the robot carries at its tool that the campaign or the job does not declare (a gripper, a
// tool changer, a spindle): its weight, m g at the centre of mass c (tool frame), adds
//   tau += -J_c^T (m g)        (J_c the linear rows of the point Jacobian at tool_pose * c)
// to the torque every joint carries, exactly as a declared payload (JointContext::payload_mass) does, and
// deflects the joints through their compliance. A load effect: only its weight; its inertia is not in the
// plant's mass matrix. Discovery fits m and the first moment m c, in which the torque is linear, and
// writes c = (m c) / m. Parameter file:
//   {"type": "payload", "mass_kg": m, "com_m": [x, y, z]}
// A negative mass is accepted (a correction: the links are lighter than their inertials say).
#pragma once

#include "model/effects/discovery_family.hpp"
#include "model/effects/effect.hpp"
#include "model/effects/gear_train.hpp"

namespace jointcomp {

class PayloadEffect : public Effect {
public:
  static constexpr const char* kType = "payload";
  // Throws ParameterError for a mass or centre that is not finite.
  PayloadEffect(const Robot& robot, double mass_kg, const Eigen::Vector3d& com_m);
  static std::unique_ptr<Effect> fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain& gears,
                                          const std::string& path);

  std::string type() const override { return kType; }
  EffectRole role() const override { return EffectRole::Load; }
  void addLoadTorque(const Robot& robot, const RobotWorkspace& ws, JointContext& ctx) const override;
  bool addLoadTorqueRate(const Robot& robot, const RobotWorkspace& ws, const JointContext& ctx, const JointVector& qd,
                         JointVector& rate) const override;
  // "payload.mass_kg", "payload.com_x_m", "payload.com_y_m", "payload.com_z_m"
  std::vector<std::string> parameterNames() const override;
  std::vector<double> parameters() const override;
  void setParameters(const std::vector<double>& values) override;
  nlohmann::json toJson() const override;
  std::unique_ptr<Effect> clone() const override { return std::make_unique<PayloadEffect>(*this); }

  double mass() const { return mass_; }
  const Eigen::Vector3d& centreOfMass() const { return com_; }

  // The joint torques of a mass at a point of the tool frame, at the pose of the last forward kinematics
  // in ws: -J_c^T (mass g), added to `torque`.
  static void addTorque(const Robot& robot, const RobotWorkspace& ws, double mass, const Eigen::Vector3d& com,
                        JointVector& torque);

private:
  double mass_;
  Eigen::Vector3d com_;
};

// Discovery: "payload", for the whole robot: an undeclared mass m at c (tool frame) loads every joint,
// tau = -J_c^T (m g), linear in m and in m c since J_c = J_o - [R c]x J_w; four blocks of load-torque
// columns (d tau / d(m, m c_x, m c_y, m c_z) at the commanded pose), moving the joints through their
// compliances. Written as one payload with c = (m c) / m.
class PayloadDiscovery : public DiscoveryFamily {
public:
  std::string name() const override { return "payload"; }
  void offer(const DiscoveryData& data, int joint, std::vector<DiscoveryCandidate>& candidates) const override;
  std::unique_ptr<Effect> makeEffect(const DiscoveryData& data,
                                     const std::vector<FittedCandidate>& accepted) const override;
  // The model's payload (every accepted payload candidate adds to it): m and c = (m c) / m, with the
  // first-order sigma of the ratio (the covariance of m and m c left out).
  std::vector<NamedEstimate> describe(const FittedCandidate& fitted, const JointErrorModel& model) const override;
};

}  // namespace jointcomp
