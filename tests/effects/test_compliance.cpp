// Joint compliance: dq = -tau / K for a torque set by hand, and the quasi-static robot (compliance plus
// the loads, settled by fixed-point iteration) against the static balance K (command - q) = load(q) with
// the load recomputed independently from gravityTorques and the spring balancer's torque.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "effects_test_support.hpp"
#include "model/effects/compliance.hpp"
#include "model/effects/spring_balancer.hpp"
#include "model/robot/dynamics.hpp"

namespace jointcomp {
namespace {

std::vector<double> fileStiffness() {
  const nlohmann::json file = effects_test::rx170Json();
  for (const auto& effect : file.at("effects")) {
    if (effect.at("type") == "compliance") return effect.at("stiffness_nm_per_rad").get<std::vector<double>>();
  }
  return {};
}

TEST(Compliance, StiffnessesAreThoseOfTheFile) {
  const JointErrorModel model = effects_test::rx170Model();
  const int index = model.findEffect(ComplianceEffect::kType);
  ASSERT_GE(index, 0);
  const std::vector<double> expected = fileStiffness();
  ASSERT_EQ(expected.size(), 6u);
  EXPECT_EQ(model.effect(index).parameters(), expected);
  // The paper's Table I.
  EXPECT_EQ(expected[1], 0.85e6);
}

TEST(Compliance, UnitTorqueTimesStiffnessGivesMinusOneRadian) {
  const JointErrorModel model = effects_test::rx170Model();
  const Effect& compliance = model.effect(model.findEffect(ComplianceEffect::kType));
  const std::vector<double> k = fileStiffness();
  const Robot& robot = model.robot();
  for (int j = 0; j < robot.dof(); ++j) {
    JointContext ctx(robot.dof());
    ctx.load_torque[j] = k[j] * 1e-3;  // a torque that twists joint j by 1 mrad
    JointVector dq = JointVector::Zero(robot.dof());
    compliance.addJointError(robot, ctx, dq);
    for (int i = 0; i < robot.dof(); ++i) {
      EXPECT_NEAR(dq[i], i == j ? -1e-3 : 0.0, 1e-18) << "torque on joint " << j << ", error of joint " << i;
    }
  }
}

TEST(Compliance, ErrorsAddUp) {
  // addJointError adds to what is there; it does not overwrite.
  const JointErrorModel model = effects_test::rx170Model();
  const Effect& compliance = model.effect(model.findEffect(ComplianceEffect::kType));
  const Robot& robot = model.robot();
  JointContext ctx(robot.dof());
  ctx.load_torque = JointVector::Constant(robot.dof(), 100.0);
  JointVector once = JointVector::Zero(robot.dof());
  compliance.addJointError(robot, ctx, once);
  JointVector twice = once;
  compliance.addJointError(robot, ctx, twice);
  EXPECT_LT((twice - 2.0 * once).cwiseAbs().maxCoeff(), 1e-18);
  EXPECT_GT(once.cwiseAbs().minCoeff(), 0.0);
}

TEST(Compliance, SettledRobotIsInStaticBalance) {
  const JointErrorModel model = effects_test::rx170Model();
  const Robot& robot = model.robot();
  const EffectMask mask = model.loadsAnd({"compliance"});
  const auto& spring = dynamic_cast<const SpringBalancerEffect&>(model.effect(model.findEffect("spring_balancer")));
  const std::vector<double> k = fileStiffness();
  JointErrorWorkspace ws(robot);
  RobotWorkspace check_ws(robot);
  std::mt19937 rng(2012u);
  double largest_deflection = 0.0;
  for (int sample = 0; sample < 50; ++sample) {
    JointContext ctx(robot.dof());
    ctx.command = effects_test::randomConfiguration(robot, rng);
    const FixedPointReport report = settleStatically(model, mask, ws, ctx);
    ASSERT_TRUE(report.converged) << "sample " << sample << ", residual " << report.residual;
    // The load at the settled pose, recomputed: gravity plus the balancer on its joint.
    JointVector load;
    gravityTorques(robot, check_ws, ctx.q, load);
    load[spring.joint()] += spring.torque(ctx.q[spring.joint()]);
    const double scale = load.cwiseAbs().maxCoeff();
    for (int j = 0; j < robot.dof(); ++j) {
      const double held = k[j] * (ctx.command[j] - ctx.q[j]);
      EXPECT_NEAR(held, load[j], 1e-9 * scale) << "sample " << sample << ", joint " << j;
    }
    largest_deflection = std::max(largest_deflection, (ctx.command - ctx.q).cwiseAbs().maxCoeff());
  }
  // The balance is not trivially met by q = command: the joints did deflect.
  EXPECT_GT(largest_deflection, 1e-4);
}

TEST(Compliance, WithoutLoadEffectsTheBalanceIsAgainstGravityAlone) {
  // Only the compliance bit selected: the spring does not take part.
  const JointErrorModel model = effects_test::rx170Model();
  const Robot& robot = model.robot();
  const EffectMask mask = EffectMask(1) << model.findEffect(ComplianceEffect::kType);
  const std::vector<double> k = fileStiffness();
  JointErrorWorkspace ws(robot);
  RobotWorkspace check_ws(robot);
  std::mt19937 rng(99u);
  for (int sample = 0; sample < 20; ++sample) {
    JointContext ctx(robot.dof());
    ctx.command = effects_test::randomConfiguration(robot, rng);
    ASSERT_TRUE(settleStatically(model, mask, ws, ctx).converged);
    JointVector gravity;
    gravityTorques(robot, check_ws, ctx.q, gravity);
    const double scale = gravity.cwiseAbs().maxCoeff();
    for (int j = 0; j < robot.dof(); ++j) {
      EXPECT_NEAR(k[j] * (ctx.command[j] - ctx.q[j]), gravity[j], 1e-9 * scale) << "joint " << j;
    }
  }
}

TEST(Compliance, EmptyMaskLeavesTheRobotWhereItIsCommanded) {
  const JointErrorModel model = effects_test::rx170Model();
  const Robot& robot = model.robot();
  JointErrorWorkspace ws(robot);
  std::mt19937 rng(3u);
  JointContext ctx(robot.dof());
  ctx.command = effects_test::randomConfiguration(robot, rng);
  const FixedPointReport report = settleStatically(model, 0, ws, ctx);
  EXPECT_TRUE(report.converged);
  EXPECT_EQ(ctx.q, ctx.command);
}

}  // namespace
}  // namespace jointcomp
