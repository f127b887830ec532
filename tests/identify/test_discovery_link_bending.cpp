// Link bending (model/effects/link_bending.hpp): a long link between parallel joints whose far end sags
// sideways under the shear it carries. Checked against an independent derivation (the shear from the
// potential energy's finite differences, the far end's move from forward kinematics: it translates,
// it does not turn), its levers against the UR10's published DH lengths, its parameter file (round trip,
// refusals naming the joint), the compensator reaching the planned pose on a robot that bends, and
// discovery: on a simulated RX170 whose upper arm bends (seeded poses and tracker noise) it names the
// link and its deflection; on one that does not, it accepts nothing.
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/compensation/compensator.hpp"
#include "model/effects/link_bending.hpp"
#include "model/effects/registry.hpp"
#include "model/identify/discovery.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/kinematics.hpp"
#include "model/robot/load_urdf.hpp"
#include "tests/identify/identify_test_support.hpp"

namespace jointcomp {
namespace {

using namespace identify_test;

constexpr double kDeflection = 3e-7;  // m/N: a 0.65 m arm with E I about 3e5 N m^2, 0.15 mm under 500 N

JointErrorModel withBending(JointErrorModel model, int joint, double deflection) {
  std::vector<double> s(static_cast<std::size_t>(model.robot().dof()), 0.0);
  s[static_cast<std::size_t>(joint)] = deflection;
  model.addEffect(std::make_unique<LinkBendingEffect>(model.robot(), s));
  return model;
}

// Gravity's potential energy of the moving bodies at q (J).
double potential(const Robot& robot, const JointVector& q) {
  RobotWorkspace ws(robot);
  forwardKinematics(robot, ws, q);
  double v = 0.0;
  for (int k = 0; k < robot.dof(); ++k)
    v -= robot.joints[static_cast<std::size_t>(k)].body.mass * robot.gravity.dot(ws.com[k]);
  return v;
}

TEST(LinkBending, LeversAreTheUr10sPublishedLinkLengths) {
  const Robot ur10 = loadRobotFromUrdfFile(std::string(JOINTCOMP_DATA_DIR) + "/robots/ur10.urdf");
  const std::vector<double> lever = parallelLinkLevers(ur10);
  // Universal Robots' DH: a2 = -0.612, a3 = -0.5723 between the three parallel joints; the wrist's next
  // axes are perpendicular, the base's too.
  ASSERT_EQ(lever.size(), 6u);
  EXPECT_NEAR(lever[1], 0.612, 1e-6);
  EXPECT_NEAR(lever[2], 0.5723, 1e-6);
  for (std::size_t j : {0u, 3u, 4u, 5u}) EXPECT_EQ(lever[j], 0.0) << "joint " << j + 1;
}

TEST(LinkBending, FarEndTranslatesByTheShearTimesTheDeflection) {
  const JointErrorModel model = withBending(rx170Model(), 1, kDeflection);
  const Robot& robot = model.robot();
  const double lever = parallelLinkLevers(robot)[1];
  ASSERT_GT(lever, 0.3);
  JointErrorWorkspace ws(robot);
  RobotWorkspace before(robot), after(robot);
  const int bending = model.findEffect(LinkBendingEffect::kType);
  const MeasurementCampaign poses = randomCampaign(rx170Model(), 8, 5);
  for (const JointVector& q : poses.command) {
    JointContext ctx(6);
    ctx.q = q;
    ctx.command = q;
    computeLoadTorque(model, 0, ws, ctx);  // gravity only
    // Independent: the joints' gravity torques as the potential energy's slope (central differences).
    JointVector tau(6);
    for (int j = 0; j < 6; ++j) {
      JointVector plus = q, minus = q;
      plus[j] += 1e-6;
      minus[j] -= 1e-6;
      tau[j] = (potential(robot, plus) - potential(robot, minus)) / 2e-6;
    }
    EXPECT_NEAR(ctx.load_torque[1], tau[1], 1e-5 * (1.0 + std::abs(tau[1])));
    JointVector dq = JointVector::Zero(6);
    model.effect(bending).addJointError(robot, ctx, dq);
    for (int j : {0, 3, 4, 5}) EXPECT_EQ(dq[j], 0.0);
    forwardKinematics(robot, before, q);
    forwardKinematics(robot, after, JointVector(q + dq));
    // The distal arm keeps its orientation and moves sideways by s (tau_2 - tau_3) / L, perpendicular to
    // the joint axis and to the link, down the way gravity pulls.
    const Eigen::Vector3d move = after.tool_pose.translation() - before.tool_pose.translation();
    const double shear = (tau[1] - tau[2]) / lever;
    const Eigen::Matrix3d turn = after.tool_pose.linear() * before.tool_pose.linear().transpose();
    EXPECT_LT(Eigen::AngleAxisd(turn).angle(), 1e-12);
    EXPECT_NEAR(move.norm(), kDeflection * std::abs(shear), 1e-3 * kDeflection * std::abs(shear) + 1e-12);
    const Eigen::Vector3d link = before.origin[2] - before.origin[1];
    EXPECT_LT(std::abs(move.dot(before.axis[1])), 1e-12);
    EXPECT_LT(std::abs(move.dot(link.normalized())), 1e-3 * move.norm() + 1e-12);
    if (std::abs(shear) > 50.0) {
      EXPECT_GT(move.dot(robot.gravity.normalized()), 0.0) << "sags upward";
    }
  }
}

TEST(LinkBending, ParameterFileRoundTripAndRefusals) {
  const JointErrorModel model = withBending(rx170Model(), 1, kDeflection);
  const std::string text = parametersToJson(model);
  const JointErrorModel back = parseParameters(text, "bending.json", model.sharedRobot());
  const int index = back.findEffect(LinkBendingEffect::kType);
  ASSERT_GE(index, 0);
  EXPECT_EQ(back.effect(index).parameters()[1], kDeflection);
  EXPECT_EQ(parametersToJson(back), text);

  const Robot& robot = model.robot();
  const nlohmann::json wrist = {{"type", "link_bending"}, {"deflection_m_per_n", {0, 0, 0, 1e-7, 0, 0}}};
  try {
    createEffect(wrist, robot, model.gears(), "p.json: effects[3]");
    ADD_FAILURE() << "a bending wrist joint was accepted";
  } catch (const ParameterError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr(robot.joints[3].name + ".link_bending_deflection_m_per_n"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("not parallel"));
  }
  EXPECT_THROW(createEffect({{"type", "link_bending"}, {"deflection_m_per_n", {0, 1e-7}}}, robot, model.gears(), "p"),
               ParameterError);
  EXPECT_THROW(LinkBendingEffect(robot, {0, std::nan(""), 0, 0, 0, 0}), ParameterError);
}

TEST(LinkBending, CompensatorReachesThePlannedPoseOnABendingRobot) {
  const JointErrorModel truth = withBending(rx170Model(), 1, 5.0 * kDeflection);
  Compensator compensator(truth, truth.allEffects());
  JointErrorWorkspace ws(truth.robot());
  const JointErrorModel straight = rx170Model();
  const MeasurementCampaign poses = randomCampaign(truth, 20, 9);
  double moved = 0.0;
  for (const JointVector& planned_q : poses.command) {
    JointContext planned(6);
    planned.q = planned_q;
    JointVector reference(6);
    compensator.compensate(planned, reference);
    JointContext actual(6);
    actual.command = reference;
    ASSERT_TRUE(settleStatically(truth, truth.allEffects(), ws, actual).converged);
    EXPECT_LT((actual.q - planned_q).cwiseAbs().maxCoeff(), 1e-9);
    // The bending is in the correction: joint 3's reference moves against joint 2's.
    JointContext plain = actual;
    plain.command = planned_q;
    settleStatically(straight, straight.allEffects(), ws, plain);
    moved = std::max(moved, std::abs((reference - planned_q)[2] - (planned_q - plain.q)[2]));
  }
  EXPECT_GT(moved, 1e-5);
}

DiscoveryResult discover(const JointErrorModel& truth, std::uint64_t seed) {
  DiscoveryOptions options;
  options.max_harmonic_order = 3;
  options.max_steps = 4;
  return discoverEffects(rx170Model(), {randomCampaign(truth, 240, seed)}, {randomCampaign(truth, 120, seed + 1000)},
                         options);
}

TEST(LinkBending, DiscoveryNamesTheLinkAndItsDeflection) {
  for (std::uint64_t seed : {71u, 72u}) {
    const DiscoveryResult r = discover(withBending(rx170Model(), 1, kDeflection), seed);
    ASSERT_FALSE(r.steps.empty()) << "seed " << seed << ": " << r.stop_reason;
    EXPECT_EQ(r.steps[0].type, "link_bending") << "seed " << seed;
    EXPECT_EQ(r.steps[0].joint, 1);
    const DiscoveredParameter* s = nullptr;
    for (const DiscoveredParameter& p : r.steps[0].parameters) {
      if (p.name == r.model.robot().joints[1].name + ".link_bending_deflection_m_per_n") s = &p;
    }
    ASSERT_NE(s, nullptr);
    EXPECT_GT(s->sigma, 0.0);
    EXPECT_NEAR(s->value, kDeflection, 4.0 * s->sigma + 0.1 * kDeflection) << "seed " << seed;
    EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor) << "seed " << seed;
    EXPECT_GE(r.model.findEffect(LinkBendingEffect::kType), 0);
  }
}

TEST(LinkBending, DiscoveryAcceptsNoBendingOnARobotThatDoesNotBend) {
  for (std::uint64_t seed : {73u, 74u}) {
    const DiscoveryResult r = discover(rx170Model(), seed);
    for (const DiscoveryStep& s : r.steps) EXPECT_NE(s.type, "link_bending") << "seed " << seed;
    EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
  }
}

}  // namespace
}  // namespace jointcomp
