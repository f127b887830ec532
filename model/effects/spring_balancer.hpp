// A gravity compensator: a linear spring between a point fixed on the link before a joint (anchor A, at
// distance a from the joint axis) and a point on the link it moves (anchor B, at distance b). In the
// plane normal to the axis the angle between the two anchors is angle_at_zero + q, so the spring length
// is L(q)^2 = a^2 + b^2 - 2ab cos(angle_at_zero + q), its force F = preload + k (L - free_length), its
// energy V = preload L + k/2 (L - free_length)^2, and it adds dV/dq to the torque the joint carries
// (negative where it holds the arm up). The Staubli RX joint 2 has one (Olabi et al. 2012).
#pragma once

#include "model/effects/effect.hpp"

namespace jointcomp {

struct SpringBalancerGeometry {
  double anchor_distance_before_m = 0.0;  // a
  double anchor_distance_after_m = 0.0;   // b
  double angle_at_zero_rad = 0.0;
  double stiffness_n_per_m = 0.0;  // k
  double free_length_m = 0.0;
  double preload_n = 0.0;
};

class SpringBalancerEffect : public Effect {
public:
  static constexpr const char* kType = "spring_balancer";
  SpringBalancerEffect(const Robot& robot, int joint, SpringBalancerGeometry geometry);
  static std::unique_ptr<Effect> fromJson(const nlohmann::json& json, const Robot& robot, const std::string& path);

  std::string type() const override { return kType; }
  EffectRole role() const override { return EffectRole::Load; }
  void addLoadTorque(const Robot& robot, const RobotWorkspace& ws, JointContext& ctx) const override;
  bool loadTorqueReadsKinematics() const override { return false; }  // a function of its joint's angle
  bool addLoadTorqueRate(const Robot& robot, const RobotWorkspace& ws, const JointContext& ctx, const JointVector& qd,
                         JointVector& rate) const override;
  std::vector<std::string> parameterNames() const override;
  std::vector<double> parameters() const override;
  void setParameters(const std::vector<double>& values) override;
  nlohmann::json toJson() const override;
  std::unique_ptr<Effect> clone() const override { return std::make_unique<SpringBalancerEffect>(*this); }

  int joint() const { return joint_; }
  double springLength(double q) const;
  double potentialEnergy(double q) const;
  double loadPotentialEnergy(const Robot&, const JointContext& ctx) const override {
    return potentialEnergy(ctx.q[joint_]);
  }
  // dV/dq: what the spring adds to the torque the joint carries.
  double torque(double q) const;
  // d(torque)/dq.
  double torqueSlope(double q) const;

private:
  int joint_;
  std::string joint_name_;
  SpringBalancerGeometry geometry_;
};

}  // namespace jointcomp
