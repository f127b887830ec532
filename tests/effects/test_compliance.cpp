// Joint compliance: dq = -tau / K for a torque set by hand, and the quasi-static robot (compliance plus
// the loads, settled by fixed-point iteration) against the static balance K (command - q) = load(q) with
// the load recomputed independently from gravityTorques and the spring balancer's torque.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "effects_test_support.hpp"
#include "model/common/errors.hpp"
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

TEST(Compliance, SettlingFromAGuessOrInJointFramesFindsTheSameBalance) {
  // The start and the load evaluation change the way, not the fixed point: from the solution itself the first
  // iteration moves by less than the tolerance (joint-frame gravity is the kinematic one to rounding), from the
  // command as a given start the bits are those of the default, and a payload (which needs the tool's pose)
  // falls back to the kinematics.
  const JointErrorModel model = effects_test::rx170Model();
  const Robot& robot = model.robot();
  const EffectMask mask = model.loadsAnd({"compliance"});
  JointErrorWorkspace ws(robot);
  std::mt19937 rng(44u);
  for (int sample = 0; sample < 20; ++sample) {
    JointContext plain(robot.dof());
    plain.command = effects_test::randomConfiguration(robot, rng);
    const FixedPointReport from_command = settleStatically(model, mask, ws, plain);
    ASSERT_TRUE(from_command.converged);
    ASSERT_GT(from_command.iterations, 2) << "sample " << sample;

    JointContext at_solution = plain;
    const FixedPointReport settled =
        settleStatically(model, mask, ws, at_solution, {}, SettleStart::Given, SettleLoads::JointFrames);
    EXPECT_TRUE(settled.converged);
    EXPECT_EQ(settled.iterations, 1) << "sample " << sample << ", residual " << settled.residual;
    EXPECT_LT((at_solution.q - plain.q).cwiseAbs().maxCoeff(), 1e-12);

    JointContext nearby = plain;
    nearby.q = plain.q + JointVector::Constant(robot.dof(), 1e-6);
    ASSERT_TRUE(settleStatically(model, mask, ws, nearby, {}, SettleStart::Given, SettleLoads::JointFrames).converged);
    EXPECT_LT((nearby.q - plain.q).cwiseAbs().maxCoeff(), 1e-11) << "sample " << sample;

    JointContext given_command = plain;
    given_command.q = plain.command;
    const FixedPointReport same = settleStatically(model, mask, ws, given_command, {}, SettleStart::Given);
    EXPECT_EQ(same.iterations, from_command.iterations);
    EXPECT_EQ(given_command.q, plain.q);

    JointContext loaded = plain;
    loaded.payload_mass = 20.0;
    loaded.payload_com = Eigen::Vector3d(0.0, 0.0, 0.1);
    JointContext loaded_plain = loaded;
    ASSERT_TRUE(settleStatically(model, mask, ws, loaded_plain).converged);
    loaded.q = loaded.command;
    ASSERT_TRUE(settleStatically(model, mask, ws, loaded, {}, SettleStart::Given, SettleLoads::JointFrames).converged);
    EXPECT_EQ(loaded.q, loaded_plain.q);
    EXPECT_GT((loaded.q - plain.q).cwiseAbs().maxCoeff(), 1e-7);  // the payload did weigh
  }
}

TEST(Compliance, AGivenStartThatIsNotFiniteIsRefusedByName) {
  const JointErrorModel model = effects_test::rx170Model();
  JointErrorWorkspace ws(model.robot());
  JointContext ctx(model.robot().dof());
  ctx.command = JointVector::Zero(model.robot().dof());
  ctx.q = ctx.command;
  ctx.q[2] = std::numeric_limits<double>::quiet_NaN();
  try {
    settleStatically(model, model.allEffects(), ws, ctx, {}, SettleStart::Given);
    FAIL() << "a NaN start was accepted";
  } catch (const InvalidArgument& error) {
    EXPECT_NE(std::string(error.what()).find("q (the settling's start)"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace jointcomp
