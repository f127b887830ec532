// Lost motion has memory: the side of a joint's play is the one its last move set, however small the move
// or long ago, and a joint at rest keeps it. The campaigns here are built by hand so that the side is
// known independently of the library's memory: joint 2 moves only every few rows, or by steps of a
// micro-radian, while the other joints move at random. The truth's link angles come from the settled
// model given those hand-tracked sides; discovery, which sees only the command sequence, must find the
// backlash with its true width and bring the held-out error to the noise floor.
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "model/common/random.hpp"
#include "model/effects/backlash.hpp"
#include "model/effects/hysteresis.hpp"
#include "model/experiment/campaign_simulation.hpp"
#include "model/identify/discovery.hpp"
#include "model/robot/kinematics.hpp"
#include "tests/identify/identify_test_support.hpp"

namespace jointcomp {
namespace {

using namespace identify_test;

constexpr int kJoint = 1;                   // joint 2 of the RX170 carries the play
constexpr double kWidth = 0.012 * kDegree;  // rad
constexpr double kTrackerSigma = 10e-6;     // m per axis

enum class Motion { EveryFewRows, FineSteps };

// Random poses for the other joints (the simulator's well-conditioned draws); joint 2 moves only every
// fourth row (EveryFewRows: by a random amount) or on every row by +-1 micro-radian in a random direction
// around its drawn value (FineSteps). Each row's side of joint 2's play is tracked here by hand.
MeasurementCampaign handBuiltCampaign(Motion motion, int count, std::uint64_t seed, double width = kWidth) {
  CampaignSimulationSpec spec;
  spec.protocol = CampaignProtocol::RandomPoses;
  spec.seed = seed;
  spec.random.count = count;
  spec.noise = false;
  MeasurementCampaign campaign = simulateCampaign(rx170Model(), spec);

  JointErrorModel truth = rx170Model();
  std::vector<double> widths(6, 0.0);
  widths[kJoint] = width;
  truth.addEffect(std::make_unique<BacklashEffect>(truth.robot(), widths));
  JointErrorWorkspace ws(truth.robot());
  JointContext ctx(truth.robot().dof());
  DeterministicRandom random(seed * 7 + 3);
  double held = campaign.command[0][kJoint];
  double side = 0.0;  // joint 2 has not moved before the first row: side unknown, no error
  for (std::size_t k = 0; k < campaign.size(); ++k) {
    JointVector command = campaign.command[k];
    if (k > 0) {
      double next = held;
      if (motion == Motion::EveryFewRows && k % 4 == 0) next = command[kJoint];
      if (motion == Motion::FineSteps) next = held + (random.uniform() < 0.5 ? -1e-6 : 1e-6);
      if (next > held) side = 1.0;
      if (next < held) side = -1.0;
      held = next;
    }
    command[kJoint] = held;
    campaign.command[k] = command;
    ctx.command = command;
    ctx.velocity.setZero();
    ctx.approach = JointVector::Zero(6);
    ctx.approach[kJoint] = side;  // the truth's side for joint 2; the other joints carry no play
    ctx.payload_com = campaign.target_in_flange;
    const FixedPointReport report = settleStatically(truth, truth.allEffects(), ws, ctx);
    EXPECT_TRUE(report.converged);
    forwardKinematics(truth.robot(), ws.robot, ctx.q);
    const Eigen::Vector3d noise(random.normal(), random.normal(), random.normal());
    campaign.position[k] = ws.robot.tool_pose * campaign.target_in_flange + kTrackerSigma * noise;
  }
  campaign.position_noise = kTrackerSigma;
  return campaign;
}

double fittedWidth(const DiscoveryResult& r) {
  for (const DiscoveryStep& s : r.steps) {
    if (s.type == "backlash" && s.joint == kJoint && !s.parameters.empty()) return s.parameters[0].value;
  }
  return std::nan("");
}

DiscoveryResult discoverBacklash(Motion motion) {
  const MeasurementCampaign fit = handBuiltCampaign(motion, 240, 41);
  const MeasurementCampaign held = handBuiltCampaign(motion, 120, 1041);
  DiscoveryOptions options;
  options.types = {"backlash", "offset"};
  options.max_steps = 3;
  return discoverEffects(rx170Model(), {fit}, {held}, options);
}

TEST(LostMotionMemory, KeepsTheSideOfTheLastMoveOfEachJoint) {
  LostMotionMemory memory(3);
  EXPECT_EQ(memory.sides(), JointVector::Zero(3));  // nothing moved yet: not known
  JointVector change(3);
  change << 0.2, -1e-7, 0.0;
  EXPECT_EQ(memory.move(change), (JointVector(3) << 1.0, -1.0, 0.0).finished());
  change << 0.0, 0.0, 1e-12;  // rounding in a command file is no move
  EXPECT_EQ(memory.move(change), (JointVector(3) << 1.0, -1.0, 0.0).finished());
  change << -3e-9, 0.0, 0.0;  // the smallest real move sets the side
  EXPECT_EQ(memory.move(change), (JointVector(3) << -1.0, -1.0, 0.0).finished());
}

TEST(LostMotionMemory, EffectsTakeTheRememberedSideOverTheVelocity) {
  JointErrorModel model = rx170Model();
  const std::vector<double> widths = {0.0, 2e-4, 0.0, 0.0, 0.0, 0.0};
  const BacklashEffect backlash(model.robot(), widths);
  const HysteresisEffect hysteresis(model.robot(), widths);
  JointContext ctx(6);
  ctx.load_torque[1] = -300.0;
  JointVector dq = JointVector::Zero(6);
  // At rest with a remembered side: the full half play, whatever the (zero) velocity says.
  ctx.approach = JointVector::Zero(6);
  ctx.approach[1] = -1.0;
  backlash.addJointError(model.robot(), ctx, dq);
  EXPECT_DOUBLE_EQ(dq[1], 1e-4);
  dq.setZero();
  hysteresis.addJointError(model.robot(), ctx, dq);
  EXPECT_DOUBLE_EQ(dq[1], 0.5 * 2e-4 * 300.0);
  // Continuous motion (no remembered side): the smooth sign of the velocity.
  ctx.approach.resize(0);
  ctx.velocity[1] = 0.5e-3;  // half the velocity scale
  dq.setZero();
  backlash.addJointError(model.robot(), ctx, dq);
  EXPECT_NEAR(dq[1], -1e-4 * std::tanh(0.5), 1e-18);
}

TEST(LostMotionMemory, DiscoveryFindsThePlayOfAJointThatMovesOnlyEveryFewRows) {
  const DiscoveryResult r = discoverBacklash(Motion::EveryFewRows);
  ASSERT_FALSE(r.steps.empty());
  EXPECT_EQ(r.steps[0].type, "backlash");
  EXPECT_EQ(r.steps[0].joint, kJoint);
  EXPECT_NEAR(fittedWidth(r), kWidth, 0.1 * kWidth);
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
}

TEST(LostMotionMemory, DiscoveryFindsThePlayUnderMicroRadianSteps) {
  const DiscoveryResult r = discoverBacklash(Motion::FineSteps);
  ASSERT_FALSE(r.steps.empty());
  EXPECT_EQ(r.steps[0].type, "backlash");
  EXPECT_EQ(r.steps[0].joint, kJoint);
  EXPECT_NEAR(fittedWidth(r), kWidth, 0.1 * kWidth);
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
}

}  // namespace
}  // namespace jointcomp
