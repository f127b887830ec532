// The spring balancer against identities: its torque is the derivative of its energy (finite
// differences), its length follows from the two anchor points placed in the plane (an independent 2-D
// construction), its energy is that of a preloaded linear spring of that length, and on the RX170 it
// holds joint 2 up against gravity.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "effects_test_support.hpp"
#include "model/effects/spring_balancer.hpp"
#include "model/robot/dynamics.hpp"

namespace jointcomp {
namespace {

using effects_test::kPi;

// Spring length built from the anchor points: A fixed at distance a on the link before the joint (along
// x), B at distance b on the moving link, at angle angle_at_zero + q from A about the joint axis.
double lengthFromAnchors(const SpringBalancerGeometry& g, double q) {
  const Eigen::Vector2d a(g.anchor_distance_before_m, 0.0);
  const double angle = g.angle_at_zero_rad + q;
  const Eigen::Vector2d b = g.anchor_distance_after_m * Eigen::Vector2d(std::cos(angle), std::sin(angle));
  return (b - a).norm();
}

// Energy of a preloaded linear spring of that length: integral of F = P + k (L - L0) dL from L0 plus
// the constant P L0 (which does not matter for the torque).
double energyFromAnchors(const SpringBalancerGeometry& g, double q) {
  const double length = lengthFromAnchors(g, q);
  const double stretch = length - g.free_length_m;
  return g.preload_n * length + 0.5 * g.stiffness_n_per_m * stretch * stretch;
}

// Fourth-order central difference of f at x.
template <class F>
double derivative(const F& f, double x, double h) {
  return (8.0 * (f(x + h) - f(x - h)) - (f(x + 2.0 * h) - f(x - 2.0 * h))) / (12.0 * h);
}

// Energy scale of a geometry, to size tolerances.
double energyScale(const SpringBalancerGeometry& g) {
  const double reach = g.anchor_distance_before_m + g.anchor_distance_after_m;
  return g.stiffness_n_per_m * reach * reach + std::abs(g.preload_n) * reach + 1.0;
}

std::vector<SpringBalancerGeometry> geometries() {
  std::vector<SpringBalancerGeometry> result;
  // The RX170 balancer of the parameter file.
  const nlohmann::json file = effects_test::rx170Json();
  for (const auto& effect : file.at("effects")) {
    if (effect.at("type") != "spring_balancer") continue;
    SpringBalancerGeometry g;
    g.anchor_distance_before_m = effect.at("anchor_distance_before_m").get<double>();
    g.anchor_distance_after_m = effect.at("anchor_distance_after_m").get<double>();
    g.angle_at_zero_rad = effect.at("angle_at_zero_rad").get<double>();
    g.stiffness_n_per_m = effect.at("stiffness_n_per_m").get<double>();
    g.free_length_m = effect.at("free_length_m").get<double>();
    g.preload_n = effect.at("preload_n").get<double>();
    result.push_back(g);
  }
  // Random ones with preload, an offset angle and anchors of different lengths (never coinciding).
  std::mt19937 rng(17u);
  std::uniform_real_distribution<double> distance(0.05, 0.5);
  std::uniform_real_distribution<double> angle(-kPi, kPi);
  std::uniform_real_distribution<double> stiffness(1e3, 5e4);
  std::uniform_real_distribution<double> preload(-2000.0, 2000.0);
  for (int i = 0; i < 20; ++i) {
    SpringBalancerGeometry g;
    g.anchor_distance_before_m = distance(rng);
    g.anchor_distance_after_m = g.anchor_distance_before_m * (i % 2 == 0 ? 0.4 : 1.7);
    g.angle_at_zero_rad = angle(rng);
    g.stiffness_n_per_m = stiffness(rng);
    g.free_length_m = 0.5 * distance(rng);
    g.preload_n = preload(rng);
    result.push_back(g);
  }
  return result;
}

TEST(SpringBalancer, TheFileHasOneOnJoint2) {
  const JointErrorModel model = effects_test::rx170Model();
  const int index = model.findEffect(SpringBalancerEffect::kType);
  ASSERT_GE(index, 0);
  const auto& spring = dynamic_cast<const SpringBalancerEffect&>(model.effect(index));
  EXPECT_EQ(spring.joint(), effects_test::jointByName(model.robot(), "joint_2"));
  EXPECT_EQ(spring.role(), EffectRole::Load);
  ASSERT_EQ(geometries().size(), 21u);
}

TEST(SpringBalancer, LengthIsTheDistanceBetweenTheAnchorPoints) {
  const Robot& robot = *effects_test::rx170();
  for (const SpringBalancerGeometry& g : geometries()) {
    const SpringBalancerEffect spring(robot, 1, g);
    for (double q = -3.0; q <= 3.0; q += 0.125) {
      EXPECT_NEAR(spring.springLength(q), lengthFromAnchors(g, q), 1e-14) << "q = " << q;
    }
  }
}

TEST(SpringBalancer, EnergyIsThatOfAPreloadedLinearSpring) {
  const Robot& robot = *effects_test::rx170();
  for (const SpringBalancerGeometry& g : geometries()) {
    const SpringBalancerEffect spring(robot, 1, g);
    for (double q = -3.0; q <= 3.0; q += 0.125) {
      // Energies may differ by a constant only; this one is the same up to rounding.
      EXPECT_NEAR(spring.potentialEnergy(q), energyFromAnchors(g, q), 1e-12 * energyScale(g)) << "q = " << q;
    }
  }
}

TEST(SpringBalancer, TorqueIsTheDerivativeOfTheEnergy) {
  const Robot& robot = *effects_test::rx170();
  for (const SpringBalancerGeometry& g : geometries()) {
    const SpringBalancerEffect spring(robot, 1, g);
    const auto energy = [&spring](double x) { return spring.potentialEnergy(x); };
    for (double q = -3.0; q <= 3.0; q += 0.1) {
      const double fd = derivative(energy, q, 1e-3);
      EXPECT_NEAR(spring.torque(q), fd, 1e-9 * energyScale(g)) << "q = " << q;
    }
  }
}

TEST(SpringBalancer, TorqueIsTheDerivativeOfTheIndependentEnergy) {
  // The same identity against the energy written from the anchor points: a wrong length or a wrong sign
  // in both the library's energy and its torque cannot hide here.
  const Robot& robot = *effects_test::rx170();
  for (const SpringBalancerGeometry& g : geometries()) {
    const SpringBalancerEffect spring(robot, 1, g);
    const auto energy = [&g](double x) { return energyFromAnchors(g, x); };
    for (double q = -3.0; q <= 3.0; q += 0.1) {
      EXPECT_NEAR(spring.torque(q), derivative(energy, q, 1e-3), 1e-9 * energyScale(g)) << "q = " << q;
    }
  }
}

TEST(SpringBalancer, AddsItsTorqueToItsJointOnly) {
  const JointErrorModel model = effects_test::rx170Model();
  const auto& spring = dynamic_cast<const SpringBalancerEffect&>(model.effect(model.findEffect("spring_balancer")));
  const Robot& robot = model.robot();
  RobotWorkspace ws(robot);
  std::mt19937 rng(5u);
  for (int sample = 0; sample < 20; ++sample) {
    JointContext ctx(robot.dof());
    ctx.q = effects_test::randomConfiguration(robot, rng);
    ctx.load_torque = JointVector::Constant(robot.dof(), 7.0);
    spring.addLoadTorque(robot, ws, ctx);
    for (int j = 0; j < robot.dof(); ++j) {
      const double expected = 7.0 + (j == spring.joint() ? spring.torque(ctx.q[j]) : 0.0);
      EXPECT_EQ(ctx.load_torque[j], expected) << "joint " << j;
    }
  }
}

TEST(SpringBalancer, HoldsTheRx170ArmUpAgainstGravity) {
  // With the arm stretched (q3 = 0) and leaning either way, the spring torque opposes the gravity torque
  // of joint 2 and carries a large part of it, less than all (the file says about three quarters).
  const JointErrorModel model = effects_test::rx170Model();
  const Robot& robot = model.robot();
  const auto& spring = dynamic_cast<const SpringBalancerEffect&>(model.effect(model.findEffect("spring_balancer")));
  RobotWorkspace ws(robot);
  for (double q2 : {-1.2, -0.8, -0.4, 0.4, 0.8, 1.2}) {
    JointVector q = JointVector::Zero(robot.dof());
    q[1] = q2;
    JointVector gravity;
    gravityTorques(robot, ws, q, gravity);
    const double carried = -spring.torque(q2) / gravity[1];
    EXPECT_GT(carried, 0.5) << "q2 = " << q2 << ", gravity " << gravity[1] << " N m";
    EXPECT_LT(carried, 0.9) << "q2 = " << q2 << ", gravity " << gravity[1] << " N m";
  }
}

}  // namespace
}  // namespace jointcomp
