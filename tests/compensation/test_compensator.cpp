// Offline compensation against its purpose: when the model is the truth and nothing is noisy, the
// references it computes bring the quasi-static robot (settled with every effect) exactly onto the planned
// joints and the planned tool path. Also: the fixed point is reached in a few iterations, compliance alone
// needs one pass and equals the closed form Q_theo + load / K, an empty mask changes nothing, and bad
// inputs are rejected.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/compensation/compensator.hpp"
#include "model/compensation/feed_rate.hpp"
#include "model/compensation/joint_trajectory.hpp"
#include "model/compensation/path.hpp"
#include "model/effects/compliance.hpp"
#include "model/effects/payload.hpp"
#include "model/effects/periodic_table.hpp"
#include "model/effects/spring_balancer.hpp"
#include "model/experiment/spiral_experiment.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/kinematics.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

constexpr double kDegree = 3.14159265358979323846 / 180.0;

std::shared_ptr<const Robot> rx170() {
  static const std::shared_ptr<const Robot> robot =
      std::make_shared<const Robot>(loadRobotFromUrdfFile(std::string(JOINTCOMP_DATA_DIR) + "/robots/rx170.urdf"));
  return robot;
}

JointErrorModel rx170Model() {
  return loadParameterFile(std::string(JOINTCOMP_DATA_DIR) + "/params/rx170.json", rx170());
}

// A straight tool move in front of the robot at the height of the paper's test, tool pointing down,
// planned at the paper's speed and acceleration: about 1500 points.
const JointTrajectory& plannedLine() {
  static const JointTrajectory trajectory = [] {
    const Robot& robot = *rx170();
    const Path line = straightLine(Eigen::Vector3d(1.10, -0.08, 0.20), Eigen::Vector3d(1.28, 0.06, 0.26));
    const std::vector<FeedRateSample> samples = planFeedRate(line, FeedRateSpec{});
    JointVector seed = JointVector::Zero(robot.dof());
    seed[1] = 60 * kDegree;
    seed[2] = 60 * kDegree;
    seed[4] = 60 * kDegree;
    return planJointTrajectory(robot, samples, toolPointingDown(), seed);
  }();
  return trajectory;
}

Eigen::Vector3d toolPosition(const Robot& robot, RobotWorkspace& ws, const JointVector& q) {
  forwardKinematics(robot, ws, q);
  return ws.tool_pose.translation();
}

struct Settled {
  double max_joint_error = 0.0;  // rad, |q - planned|
  double max_tool_error = 0.0;   // m, |tool - planned tool point|
};

// Where the truth puts the links for each reference, against the plan.
Settled settleAll(const JointErrorModel& truth, EffectMask mask, const JointTrajectory& plan,
                  const std::vector<JointVector>& references) {
  const Robot& robot = truth.robot();
  JointErrorWorkspace ws(robot);
  RobotWorkspace fk(robot);
  JointContext ctx(robot.dof());
  Settled result;
  for (std::size_t k = 0; k < references.size(); ++k) {
    ctx.command = references[k];
    ctx.velocity = plan.qd[k];
    ctx.time = plan.time[k];
    const FixedPointReport report = settleStatically(truth, mask, ws, ctx);
    EXPECT_TRUE(report.converged) << "point " << k;
    result.max_joint_error = std::max(result.max_joint_error, (ctx.q - plan.q[k]).cwiseAbs().maxCoeff());
    result.max_tool_error =
        std::max(result.max_tool_error, (toolPosition(robot, fk, ctx.q) - plan.tool_position[k]).norm());
  }
  return result;
}

// The plain fixed point Q_ref <- Q_theo - dQ(Q_theo, Q_ref) from Q_ref = Q_theo, written with the model's
// generic calls (libm's sines, no Newton step, no anchors), until an iteration moves it by no more than
// `tolerance` (1e-12: the compensator before its Newton steps, to the bit; 0: until it stops moving, the
// point the compensator must land on).
// `loads`: a payload and a tool wrench to hold (the context's other fields are not read).
JointVector plainFixedPoint(const JointErrorModel& model, EffectMask mask, const JointVector& planned,
                            double tolerance = 0.0, const JointContext* loads = nullptr) {
  JointErrorWorkspace ws(model.robot());
  JointContext ctx(model.robot().dof());
  if (loads) {
    ctx.payload_mass = loads->payload_mass;
    ctx.payload_com = loads->payload_com;
    ctx.tool_wrench = loads->tool_wrench;
  }
  ctx.q = planned;
  computeLoadTorque(model, mask, ws, ctx);
  ctx.command = ctx.q;
  for (int iteration = 0; iteration < 40; ++iteration) {
    updateMotorAngles(model, ctx);
    JointVector dq = JointVector::Zero(model.robot().dof());
    addSelectedJointErrors(model, mask, ctx, dq);
    const JointVector next = ctx.q - dq;
    const double change = (next - ctx.command).cwiseAbs().maxCoeff();
    ctx.command = next;
    if (change <= tolerance) break;
  }
  return ctx.command;
}

// Joint values spread over the middle 80 % of each joint's range.
JointVector randomPose(const Robot& robot, std::mt19937& rng) {
  JointVector q(robot.dof());
  for (int j = 0; j < robot.dof(); ++j) {
    const Joint& joint = robot.joints[static_cast<std::size_t>(j)];
    const double margin = 0.1 * (joint.upper - joint.lower);
    q[j] = std::uniform_real_distribution<double>(joint.lower + margin, joint.upper - margin)(rng);
  }
  return q;
}

// A command-dependent error that does not know its slope (Effect::addMotorSlope's false): the compensator
// takes plain fixed-point steps for it.
class SlopelessRipple : public Effect {
public:
  std::string type() const override { return "slopeless_ripple"; }
  EffectRole role() const override { return EffectRole::JointError; }
  bool dependsOnCommand() const override { return true; }
  void addJointError(const Robot&, const JointContext& ctx, JointVector& dq) const override {
    dq[1] += 3e-5 * std::sin(ctx.motor[1] / 3.0 + 0.3);
  }
  std::vector<std::string> parameterNames() const override { return {}; }
  std::vector<double> parameters() const override { return {}; }
  void setParameters(const std::vector<double>&) override {}
  nlohmann::json toJson() const override { return nlohmann::json::object(); }
  std::unique_ptr<Effect> clone() const override { return std::make_unique<SlopelessRipple>(*this); }
};

TEST(Compensator, ThePlanIsLongEnoughToMean) {
  ASSERT_GT(plannedLine().size(), 1000u);
  // The plan itself reaches its tool points (so that the errors below are the compensation's).
  const Robot& robot = *rx170();
  RobotWorkspace fk(robot);
  for (std::size_t k = 0; k < plannedLine().size(); k += 50) {
    EXPECT_LT((toolPosition(robot, fk, plannedLine().q[k]) - plannedLine().tool_position[k]).norm(), 1e-9);
  }
}

TEST(Compensator, WithTheTrueModelTheRobotFollowsThePlanExactly) {
  const JointErrorModel nominal = rx170Model();
  const JointErrorModel truth = nominal;  // no perturbation: the model is the truth
  const JointTrajectory& plan = plannedLine();
  std::vector<JointVector> references;
  const TrajectoryCompensationReport report =
      compensateTrajectory(nominal, nominal.allEffects(), plan.q, plan.qd, references);
  ASSERT_EQ(references.size(), plan.size());
  std::cout << "[ compensator ] all effects: at most " << report.max_iterations << " iterations, residual "
            << report.max_residual << " rad, largest correction " << report.max_correction / kDegree << " deg\n";
  RecordProperty("max_iterations_all_effects", report.max_iterations);
  EXPECT_LE(report.max_residual, 1e-12);
  EXPECT_LE(report.max_iterations, 6);
  EXPECT_GT(report.max_correction, 0.005 * kDegree);  // the compensation does something

  const Settled compensated = settleAll(truth, truth.allEffects(), plan, references);
  std::cout << "[ compensator ] settled: joints within " << compensated.max_joint_error << " rad, tool within "
            << compensated.max_tool_error * 1e6 << " um\n";
  EXPECT_LT(compensated.max_joint_error, 1e-10);
  EXPECT_LT(compensated.max_tool_error, 1e-6);

  // Without compensation the same robot misses by far more: the test above can fail.
  const Settled uncompensated = settleAll(truth, truth.allEffects(), plan, plan.q);
  EXPECT_GT(uncompensated.max_joint_error, 1e-4);
  EXPECT_GT(uncompensated.max_tool_error, 1e-4);
}

TEST(Compensator, ConvergesToTheToleranceInAFewIterations) {
  const JointErrorModel model = rx170Model();
  const EffectMask mask = model.allEffects();
  Compensator compensator(model, mask);
  const JointTrajectory& plan = plannedLine();
  JointErrorWorkspace ws(model.robot());
  std::map<int, int> histogram;
  JointContext ctx(model.robot().dof());
  JointVector reference;
  for (std::size_t k = 0; k < plan.size(); ++k) {
    ctx.q = plan.q[k];
    ctx.velocity = plan.qd[k];
    const FixedPointReport report = compensator.compensate(ctx, reference);
    ASSERT_TRUE(report.converged) << "point " << k;
    EXPECT_LE(report.residual, 1e-12) << "point " << k;
    ++histogram[report.iterations];
    // The fixed point itself: Q_ref = Q_theo - dQ(Q_theo, Q_ref), re-evaluated from scratch.
    JointContext check(model.robot().dof());
    check.q = plan.q[k];
    check.velocity = plan.qd[k];
    check.command = reference;
    computeLoadTorque(model, mask, ws, check);
    updateMotorAngles(model, check);
    JointVector dq = JointVector::Zero(model.robot().dof());
    addSelectedJointErrors(model, mask, check, dq);
    EXPECT_LT((plan.q[k] - dq - reference).cwiseAbs().maxCoeff(), 1e-13) << "point " << k;
    // ctx comes back with the result.
    EXPECT_EQ(ctx.command, reference);
  }
  std::string counts;
  for (const auto& [iterations, points] : histogram) {
    counts += " " + std::to_string(iterations) + " iterations: " + std::to_string(points) + " points;";
  }
  std::cout << "[ compensator ]" << counts << "\n";
  RecordProperty("iteration_histogram", counts);
  EXPECT_LE(histogram.rbegin()->first, 6);
  EXPECT_GT(histogram.begin()->first, 1);  // the transmission error does make it iterate
}

TEST(Compensator, ComplianceAloneNeedsOnePassAndIsTheClosedForm) {
  const JointErrorModel model = rx170Model();
  const Robot& robot = model.robot();
  const EffectMask mask = model.loadsAnd({"compliance"});
  const std::vector<double> k = model.effect(model.findEffect(ComplianceEffect::kType)).parameters();
  const auto& spring = dynamic_cast<const SpringBalancerEffect&>(model.effect(model.findEffect("spring_balancer")));
  Compensator compensator(model, mask);
  const JointTrajectory& plan = plannedLine();
  RobotWorkspace dyn(robot);
  JointContext ctx(robot.dof());
  JointVector reference;
  for (std::size_t p = 0; p < plan.size(); p += 7) {
    ctx.q = plan.q[p];
    const FixedPointReport report = compensator.compensate(ctx, reference);
    EXPECT_TRUE(report.converged);
    EXPECT_EQ(report.iterations, 1) << "point " << p;
    // Q_ref = Q_theo + load(Q_theo) / K with the load recomputed: gravity plus the balancer.
    JointVector load;
    gravityTorques(robot, dyn, plan.q[p], load);
    load[spring.joint()] += spring.torque(plan.q[p][spring.joint()]);
    for (int j = 0; j < robot.dof(); ++j) {
      EXPECT_NEAR(reference[j], plan.q[p][j] + load[j] / k[j], 1e-14) << "point " << p << ", joint " << j;
    }
  }
  std::vector<JointVector> references;
  const TrajectoryCompensationReport trajectory = compensateTrajectory(model, mask, plan.q, plan.qd, references);
  EXPECT_EQ(trajectory.max_iterations, 1);
  // A robot with compliance and loads only then follows the plan.
  const Settled settled = settleAll(model, mask, plan, references);
  EXPECT_LT(settled.max_joint_error, 1e-10);
  EXPECT_LT(settled.max_tool_error, 1e-6);
}

TEST(Compensator, EmptyMaskReturnsThePlan) {
  const JointErrorModel model = rx170Model();
  const JointTrajectory& plan = plannedLine();
  std::vector<JointVector> references;
  const TrajectoryCompensationReport report = compensateTrajectory(model, 0, plan.q, plan.qd, references);
  ASSERT_EQ(references.size(), plan.size());
  for (std::size_t k = 0; k < plan.size(); ++k) ASSERT_EQ(references[k], plan.q[k]) << "point " << k;
  EXPECT_EQ(report.max_correction, 0.0);
  EXPECT_EQ(report.max_iterations, 1);
}

TEST(Compensator, LoadsAloneCorrectNothing) {
  // The spring balancer is a load: without an error effect to turn loads into joint errors, nothing moves.
  const JointErrorModel model = rx170Model();
  const JointTrajectory& plan = plannedLine();
  std::vector<JointVector> references;
  const EffectMask loads = model.loadsAnd({});
  ASSERT_NE(loads, 0u);
  compensateTrajectory(model, loads, plan.q, plan.qd, references);
  for (std::size_t k = 0; k < plan.size(); k += 11) EXPECT_EQ(references[k], plan.q[k]);
}

TEST(Compensator, RejectsNanPlannedJoints) {
  const JointErrorModel model = rx170Model();
  Compensator compensator(model, model.allEffects());
  JointContext ctx(model.robot().dof());
  ctx.q = plannedLine().q[10];
  ctx.q[3] = std::numeric_limits<double>::quiet_NaN();
  JointVector reference;
  EXPECT_THROW(compensator.compensate(ctx, reference), InvalidArgument);
  ctx.q = plannedLine().q[10];
  ctx.q[0] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(compensator.compensate(ctx, reference), InvalidArgument);

  std::vector<JointVector> planned(plannedLine().q.begin(), plannedLine().q.begin() + 20);
  planned[13][1] = std::numeric_limits<double>::quiet_NaN();
  std::vector<JointVector> references;
  EXPECT_THROW(compensateTrajectory(model, model.allEffects(), planned, {}, references), InvalidArgument);
}

TEST(Compensator, RejectsMismatchedSizes) {
  const JointErrorModel model = rx170Model();
  const JointTrajectory& plan = plannedLine();
  const std::vector<JointVector> planned(plan.q.begin(), plan.q.begin() + 20);
  const std::vector<JointVector> velocities(plan.qd.begin(), plan.qd.begin() + 19);
  std::vector<JointVector> references;
  try {
    compensateTrajectory(model, model.allEffects(), planned, velocities, references);
    FAIL() << "20 positions with 19 velocities were accepted";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("20"));
    EXPECT_THAT(error.what(), HasSubstr("19"));
  }
  // A point with the wrong number of joints.
  std::vector<JointVector> wrong_dof = planned;
  wrong_dof[4] = JointVector::Zero(5);
  EXPECT_THROW(compensateTrajectory(model, model.allEffects(), wrong_dof, {}, references), InvalidArgument);
}

TEST(Compensator, RejectsBadOptionsAndReportsNonConvergence) {
  const JointErrorModel model = rx170Model();
  FixedPointOptions zero_tolerance;
  zero_tolerance.tolerance = 0.0;
  EXPECT_THROW(Compensator(model, model.allEffects(), zero_tolerance), InvalidArgument);
  FixedPointOptions no_iterations;
  no_iterations.max_iterations = 0;
  EXPECT_THROW(Compensator(model, model.allEffects(), no_iterations), InvalidArgument);
  // One iteration cannot reach 1e-12 with the transmission error: the point is named.
  FixedPointOptions one;
  one.max_iterations = 1;
  const std::vector<JointVector> planned(plannedLine().q.begin(), plannedLine().q.begin() + 3);
  std::vector<JointVector> references;
  try {
    compensateTrajectory(model, model.allEffects(), planned, {}, references, one);
    FAIL() << "one iteration reported convergence";
  } catch (const SolverError& error) {
    EXPECT_THAT(error.what(), HasSubstr("point 0"));
  }
}

// A reference beyond a joint's limits cannot be commanded: a payload of 1e6 kg bends the model's joints so
// far that the fixed point converges outside them, and that is an error naming the joint, not an answer.
TEST(Compensator, AReferenceBeyondTheJointLimitsIsAnError) {
  const JointErrorModel model = rx170Model();
  Compensator compensator(model, model.allEffects());
  JointContext ctx(6);
  ctx.q = plannedLine().q.front();
  JointVector reference;
  ASSERT_TRUE(compensator.compensate(ctx, reference).converged);  // the plan itself is fine
  for (int j = 0; j < 6; ++j) {
    EXPECT_GE(reference[j], model.robot().joints[j].lower);
    EXPECT_LE(reference[j], model.robot().joints[j].upper);
  }
  ctx.payload_mass = 1e6;
  try {
    compensator.compensate(ctx, reference);
    ADD_FAILURE() << "a reference beyond the limits was returned";
  } catch (const UnreachableError& error) {
    EXPECT_THAT(error.what(), HasSubstr("outside its limits"));
    EXPECT_THAT(error.what(), HasSubstr("joint_"));
  }
  // The same check on its own: a reference just past a limit is refused, one at the limit is not.
  JointVector at_limit = plannedLine().q.front();
  at_limit[1] = model.robot().joints[1].upper;
  EXPECT_NO_THROW(requireWithinLimits(model.robot(), at_limit));
  at_limit[1] = std::nextafter(at_limit[1], 10.0);
  EXPECT_THROW(requireWithinLimits(model.robot(), at_limit), UnreachableError);
}

// The Newton iteration, cold (compensate) and from the previous point's correction (compensateFrom),
// and compensateTrajectory land on the plain fixed point to rounding, along the line, along the paper's
// spiral and at random poses. Cold, the higher-order first step meets the tolerance at the second evaluation
// of the error (Newton alone took three); from the previous correction Newton does, and never needs more.
TEST(Compensator, NewtonStepsLandOnThePlainFixedPoint) {
  const JointErrorModel model = rx170Model();
  const EffectMask mask = model.allEffects();
  const SpiralExperimentSpec paper;
  const JointTrajectory spiral = planSpiralTrajectory(*rx170(), paper.spiral, paper.feed_rate);
  ASSERT_GT(spiral.size(), 5000u);
  double largest = 0.0, from_former = 0.0;
  for (const JointTrajectory* plan : {&plannedLine(), &spiral}) {
    Compensator cold(model, mask), along(model, mask);
    JointContext cold_ctx(6), along_ctx(6);
    JointVector cold_reference, along_reference, correction;
    std::vector<JointVector> trajectory_references;
    compensateTrajectory(model, mask, plan->q, plan->qd, trajectory_references);
    int cold_evaluations = 0, along_evaluations = 0, along_most = 0, cold_most = 0;
    for (std::size_t k = 0; k < plan->size(); ++k) {
      const JointVector plain = plainFixedPoint(model, mask, plan->q[k]);
      from_former =
          std::max(from_former, (plainFixedPoint(model, mask, plan->q[k], 1e-12) - plain).cwiseAbs().maxCoeff());
      cold_ctx.q = along_ctx.q = plan->q[k];
      cold_ctx.velocity = along_ctx.velocity = plan->qd[k];
      const FixedPointReport cold_report = cold.compensate(cold_ctx, cold_reference);
      const FixedPointReport along_report = k == 0 ? along.compensate(along_ctx, along_reference)
                                                   : along.compensateFrom(along_ctx, correction, along_reference);
      ASSERT_TRUE(cold_report.converged && along_report.converged) << "point " << k;
      correction = plan->q[k] - along_reference;
      cold_evaluations += cold_report.iterations;
      along_evaluations += along_report.iterations;
      if (k > 0) along_most = std::max(along_most, along_report.iterations);
      cold_most = std::max(cold_most, cold_report.iterations);
      for (const JointVector* reference : {&cold_reference, &along_reference, &trajectory_references[k]}) {
        largest = std::max(largest, (*reference - plain).cwiseAbs().maxCoeff());
      }
    }
    const char* name = plan == &spiral ? "spiral" : "line";
    std::cout << "[ compensator ] " << name << ": evaluations per point "
              << static_cast<double>(cold_evaluations) / plan->size() << " cold, "
              << static_cast<double>(along_evaluations) / plan->size() << " from the previous correction\n";
    EXPECT_LE(along_most, 2) << name;
    EXPECT_LE(cold_most, 2) << name;
    EXPECT_LE(along_evaluations, cold_evaluations) << name;
  }
  std::mt19937 rng(31u);
  Compensator compensator(model, mask);
  JointContext ctx(6);
  JointVector reference;
  for (int sample = 0; sample < 300; ++sample) {
    const JointVector pose = randomPose(model.robot(), rng);
    ctx.q = pose;
    ctx.velocity.setZero();
    ASSERT_TRUE(compensator.compensate(ctx, reference).converged) << "sample " << sample;
    largest = std::max(largest, (reference - plainFixedPoint(model, mask, pose)).cwiseAbs().maxCoeff());
  }
  std::cout << "[ compensator ] Newton against the plain fixed point: within " << largest
            << " rad (the former plain iteration to 1e-12: within " << from_former << " rad)\n";
  // Both stop when the map moves by <= 1e-12 rad and contract it by about 1e-2: well inside 1e-12 of it.
  EXPECT_LT(largest, 1e-13);
}

// The compensator takes gravity from the joints' sines alone (gravityTorquesInJointFrames) unless a load needs
// the tool's pose: a payload or a wrench in the context, or a load effect that reads the kinematics (a
// payload effect). Each way it lands on the plain fixed point with the forward kinematics' loads, and the
// loads change the answer (so the comparison sees them).
TEST(Compensator, LoadsThatNeedTheToolsPoseLandOnThePlainFixedPoint) {
  const JointErrorModel bare = rx170Model();
  JointErrorModel with_payload_effect = bare;
  with_payload_effect.addEffect(std::make_unique<PayloadEffect>(bare.robot(), 20.0, Eigen::Vector3d(0.05, -0.02, 0.1)));
  JointContext loads(6);
  loads.payload_mass = 12.0;
  loads.payload_com = Eigen::Vector3d(0.0, 0.03, 0.08);
  loads.tool_wrench << 30.0, -20.0, 50.0, 4.0, -3.0, 2.0;
  std::mt19937 rng(37u);
  double largest = 0.0, smallest_load_effect = std::numeric_limits<double>::infinity();
  for (int sample = 0; sample < 50; ++sample) {
    const JointVector pose = randomPose(bare.robot(), rng);
    for (int way = 0; way < 3; ++way) {
      const JointErrorModel& model = way == 2 ? with_payload_effect : bare;
      const EffectMask mask = model.allEffects();
      Compensator compensator(model, mask);
      JointContext ctx(6);
      if (way == 1) {
        ctx.payload_mass = loads.payload_mass;
        ctx.payload_com = loads.payload_com;
        ctx.tool_wrench = loads.tool_wrench;
      }
      ctx.q = pose;
      JointVector reference;
      ASSERT_TRUE(compensator.compensate(ctx, reference).converged) << "sample " << sample << " way " << way;
      const JointVector plain = plainFixedPoint(model, mask, pose, 0.0, way == 1 ? &loads : nullptr);
      largest = std::max(largest, (reference - plain).cwiseAbs().maxCoeff());
      if (way > 0) {
        smallest_load_effect =
            std::min(smallest_load_effect, (plain - plainFixedPoint(bare, bare.allEffects(), pose)).norm());
      }
    }
  }
  EXPECT_LT(largest, 1e-13);
  EXPECT_GT(smallest_load_effect, 1e-6);  // rad: the payload and wrench move the reference
}

// A guess far from the answer costs iterations, not accuracy; a guess that is not a number is an error.
TEST(Compensator, AnyFiniteGuessGivesTheSameReference) {
  const JointErrorModel model = rx170Model();
  const EffectMask mask = model.allEffects();
  Compensator compensator(model, mask);
  JointContext ctx(6);
  ctx.q = plannedLine().q[100];
  JointVector reference, from_guess;
  ASSERT_TRUE(compensator.compensate(ctx, reference).converged);
  for (const double offset : {0.0, 1e-6, 1e-3, 0.05}) {
    JointVector guess = ctx.q - reference;
    guess.array() += offset;
    const FixedPointReport report = compensator.compensateFrom(ctx, guess, from_guess);
    ASSERT_TRUE(report.converged) << "offset " << offset;
    EXPECT_LE(report.residual, 1e-12);
    EXPECT_LT((from_guess - reference).cwiseAbs().maxCoeff(), 1e-13) << "offset " << offset;
  }
  // compensate() does not remember the calls between: the same point gives the same bits again.
  JointVector again;
  ASSERT_TRUE(compensator.compensate(ctx, again).converged);
  EXPECT_EQ(again, reference);
  JointVector guess = JointVector::Zero(6);
  guess[2] = std::numeric_limits<double>::quiet_NaN();
  try {
    compensator.compensateFrom(ctx, guess, from_guess);
    ADD_FAILURE() << "a NaN guess was accepted";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("correction guess[2]"));
  }
  EXPECT_THROW(compensator.compensateFrom(ctx, JointVector::Zero(5), from_guess), InvalidArgument);
}

// Only the joints with a command-dependent error iterate (the RX170's harmonics are on joints 1 to 3). The
// others take Q_theo less their fixed errors at once: the compliance-only answer, bit for bit, whatever
// the guess says for them; a guess exact on the iterating joints then needs one evaluation, however wrong
// it is elsewhere. A fixed error that is not finite (a payload beyond any robot) is no fixed point.
TEST(Compensator, OnlyJointsWithCommandErrorsIterate) {
  const JointErrorModel model = rx170Model();
  Compensator all(model, model.allEffects()), compliance_only(model, model.loadsAnd({"compliance"}));
  const JointTrajectory& plan = plannedLine();
  JointContext ctx(6);
  JointVector reference, closed_form, from_guess;
  for (std::size_t k = 0; k < plan.size(); k += 11) {
    ctx.q = plan.q[k];
    ctx.velocity = plan.qd[k];
    ASSERT_TRUE(all.compensate(ctx, reference).converged);
    ASSERT_TRUE(compliance_only.compensate(ctx, closed_form).converged);
    for (int j = 3; j < 6; ++j) EXPECT_EQ(reference[j], closed_form[j]) << "point " << k << ", joint " << j + 1;
    EXPECT_GT((reference - closed_form).head<3>().cwiseAbs().maxCoeff(), 1e-7);  // the harmonics do act there

    JointVector guess = plan.q[k] - reference;
    guess.tail<3>().array() += 0.3;  // rad: far off where it does not matter
    const FixedPointReport report = all.compensateFrom(ctx, guess, from_guess);
    ASSERT_TRUE(report.converged) << "point " << k;
    EXPECT_EQ(report.iterations, 1) << "point " << k;
    EXPECT_LT((from_guess - reference).cwiseAbs().maxCoeff(), 1e-13) << "point " << k;
  }
  ctx.q = plan.q[0];
  ctx.payload_mass = 1e308;  // kg: its gravity torque overflows
  const FixedPointReport overflowed = all.compensate(ctx, reference);
  EXPECT_FALSE(overflowed.converged);
  EXPECT_FALSE(std::isfinite(overflowed.residual));
}

// Command-dependent effects other than the harmonics go through the Effect interface: a periodic table
// (with its slope: Newton steps) and an effect without a slope (plain steps) land on the plain fixed point.
TEST(Compensator, OtherCommandEffectsLandOnThePlainFixedPoint) {
  JointErrorModel with_table = rx170Model();
  PeriodicTable table;
  table.joint = 2;
  table.stage = 1;
  for (int k = 0; k < 12; ++k) table.coefficients_rad.push_back(2e-5 * std::sin(1.3 * k) + 1e-5 * (k % 3));
  with_table.addEffect(
      std::make_unique<PeriodicTableEffect>(with_table.robot(), with_table.gears(), std::vector<PeriodicTable>{table}));
  JointErrorModel with_slopeless = rx170Model();
  with_slopeless.addEffect(std::make_unique<SlopelessRipple>());
  const JointTrajectory& plan = plannedLine();
  for (const JointErrorModel* model : {&with_table, &with_slopeless}) {
    const EffectMask mask = model->allEffects();
    Compensator compensator(*model, mask);
    JointContext ctx(6);
    JointVector reference;
    double largest = 0.0;
    int most = 0;
    for (std::size_t k = 0; k < plan.size(); k += 13) {
      ctx.q = plan.q[k];
      ctx.velocity = plan.qd[k];
      const FixedPointReport report = compensator.compensate(ctx, reference);
      ASSERT_TRUE(report.converged) << "point " << k;
      most = std::max(most, report.iterations);
      largest = std::max(largest, (reference - plainFixedPoint(*model, mask, plan.q[k])).cwiseAbs().maxCoeff());
    }
    const std::string name = model == &with_table ? "periodic table" : "slopeless ripple";
    EXPECT_LT(largest, 1e-13) << name;
    EXPECT_LE(most, 8) << name;
    std::cout << "[ compensator ] with a " << name << ": at most " << most << " iterations, within " << largest
              << " rad of the plain fixed point\n";
  }
}

}  // namespace
}  // namespace jointcomp
