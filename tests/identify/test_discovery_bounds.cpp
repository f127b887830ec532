// The bound every joint-error family shares (DiscoveryFamily::physicalProblem's default): no joint turned by
// more than kMaxPlausibleJointError over the fitted rows. A thermal drift, a time drift, a bent link and an
// undeclared payload are each driven across it, with the turn re-derived independently (the drift by hand,
// the payload's torques by finite differences of its potential energy); a link may not bend against its
// load, even when a campaign tempts the fit to.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/effects/link_bending.hpp"
#include "model/effects/payload.hpp"
#include "model/effects/thermal_drift.hpp"
#include "model/identify/discovery.hpp"
#include "model/robot/kinematics.hpp"
#include "tests/identify/identify_test_support.hpp"

namespace jointcomp {
namespace {

using namespace identify_test;

// Three fitted rows at the given poses, with load torques, times and temperatures.
DiscoveryData rowsAt(const JointErrorModel& model, const std::vector<JointVector>& poses) {
  DiscoveryData data;
  data.robot = &model.robot();
  data.gears = &model.gears();
  data.torque_known = true;
  data.have_temperature = true;
  const std::vector<double> times = {0.0, 100.0, 3600.0}, temperatures = {18.0, 22.0, 30.0};
  for (std::size_t i = 0; i < poses.size(); ++i) {
    data.command.push_back(poses[i]);
    data.approach.push_back(JointVector::Zero(6));
    JointVector tau = JointVector::Zero(6);
    tau[1] = 40.0 * static_cast<double>(i) - 100.0;  // joint 2: -100, -60, -20 N m
    tau[2] = 25.0 * static_cast<double>(i);          // joint 3: 0, 25, 50 N m
    data.load_torque.push_back(tau);
    data.time.push_back(times[i % 3]);
    data.temperature.push_back(temperatures[i % 3]);
  }
  data.time0 = 0.0;
  data.temperature0 = 22.0;
  return data;
}

std::vector<JointVector> threePoses() {
  std::vector<JointVector> poses(3, JointVector::Zero(6));
  poses[0] << 0.1, -0.4, 1.2, 0.0, 0.5, 0.0;
  poses[1] << -0.3, 0.2, 1.6, 0.3, -0.4, 0.2;
  poses[2] << 0.5, -0.9, 2.0, -0.2, 0.8, -0.1;
  return poses;
}

// Expects `problem` to accept `bound` * 0.99 and refuse `bound` * 1.01 (either sign), naming `joint`.
template <typename Problem>
void expectBoundAt(Problem problem, double bound, const std::string& joint) {
  EXPECT_EQ(problem(0.99 * bound), "");
  EXPECT_EQ(problem(-0.99 * bound), "");
  for (double sign : {1.0, -1.0}) {
    const std::string message = problem(sign * 1.01 * bound);
    EXPECT_NE(message.find("beyond the plausible"), std::string::npos) << message;
    EXPECT_NE(message.find(joint), std::string::npos) << message;
  }
  EXPECT_NE(problem(std::nan("")), "");  // a coefficient that is not a number is not physical either
}

TEST(DiscoveryBounds, AThermalOrTimeDriftTurnsItsJointByItsCoefficientTimesTheLargestChange) {
  const JointErrorModel model = rx170Model();
  const DiscoveryData data = rowsAt(model, threePoses());
  std::vector<DiscoveryCandidate> candidates;
  const ThermalDriftDiscovery family;
  family.offer(data, 2, candidates);
  ASSERT_EQ(candidates.size(), 2u);
  const JointVector compliance = JointVector::Constant(6, 1e-6);
  for (const DiscoveryCandidate& candidate : candidates) {
    // By hand: temperature 18..30 degC about 22 -> at most 8 K; time 0..3600 s from 0 -> 3600 s.
    const double largest_change = candidate.part == "temperature" ? 8.0 : 3600.0;
    auto problem = [&](double coefficient) {
      return family.physicalProblem(data, candidate, Eigen::VectorXd::Constant(1, coefficient), compliance);
    };
    expectBoundAt(problem, kMaxPlausibleJointError / largest_change, model.robot().joints[2].name);
  }
}

TEST(DiscoveryBounds, ALinkBendsWithItsLoadAndByLittle) {
  const JointErrorModel model = rx170Model();
  const DiscoveryData data = rowsAt(model, threePoses());
  const double lever = parallelLinkLevers(model.robot())[1];  // the upper arm, joint 2 to joint 3
  ASSERT_GT(lever, 0.1);
  std::vector<DiscoveryCandidate> candidates;
  const LinkBendingDiscovery family;
  family.offer(data, 1, candidates);
  ASSERT_EQ(candidates.size(), 1u);
  const JointVector compliance = JointVector::Constant(6, 1e-6);
  auto problem = [&](double s) {
    return family.physicalProblem(data, candidates[0], Eigen::VectorXd::Constant(1, s), compliance);
  };
  // Both joints turn by s |tau_2 - tau_3| / L^2, the largest difference being 100 N m (row 1).
  const double bound = kMaxPlausibleJointError * lever * lever / 100.0;
  EXPECT_EQ(problem(0.99 * bound), "");
  const std::string beyond = problem(1.01 * bound);
  EXPECT_NE(beyond.find("beyond the plausible"), std::string::npos) << beyond;
  const std::string backwards = problem(-1e-9);
  EXPECT_NE(backwards.find("against its load"), std::string::npos) << backwards;
  EXPECT_NE(backwards.find(model.robot().joints[1].name), std::string::npos) << backwards;
}

// |d(g . p_tool)/dq_j| at q by central differences: the torque a unit mass at the tool puts on each joint.
JointVector unitMassTorques(const Robot& robot, const JointVector& q) {
  JointVector tau(robot.dof());
  const double h = 1e-6;
  for (int j = 0; j < robot.dof(); ++j) {
    JointVector up = q, down = q;
    up[j] += h;
    down[j] -= h;
    tau[j] = robot.gravity.dot(toolPosition(robot, up) - toolPosition(robot, down)) / (2.0 * h);
  }
  return tau;
}

TEST(DiscoveryBounds, AnUndeclaredPayloadDeflectsTheJointsThroughTheirCompliances) {
  const JointErrorModel model = rx170Model();
  const std::vector<JointVector> poses = threePoses();
  const DiscoveryData data = rowsAt(model, poses);
  std::vector<DiscoveryCandidate> candidates;
  const PayloadDiscovery family;
  family.offer(data, -1, candidates);
  ASSERT_EQ(candidates.size(), 1u);
  JointVector compliance(6);
  compliance << 1e-6, 2e-6, 3e-6, 1e-5, 2e-5, 3e-5;
  // A mass at the tool's origin: its largest deflection per kg, from the finite-difference torques.
  double per_kg = 0.0;
  int joint = -1;
  for (const JointVector& q : poses) {
    const JointVector tau = unitMassTorques(model.robot(), q);
    for (int j = 0; j < 6; ++j) {
      if (std::abs(compliance[j] * tau[j]) > per_kg) per_kg = std::abs(compliance[j] * tau[j]), joint = j;
    }
  }
  Eigen::VectorXd theta = Eigen::VectorXd::Zero(4);
  theta[0] = 1.0;
  const LargestJointError one_kg = largestJointError(data, candidates[0], theta, compliance);
  EXPECT_NEAR(one_kg.value, per_kg, 1e-6 * per_kg);
  EXPECT_EQ(one_kg.joint, joint);
  auto problem = [&](double mass) {
    Eigen::VectorXd mass_at_origin = Eigen::VectorXd::Zero(4);
    mass_at_origin[0] = mass;
    return family.physicalProblem(data, candidates[0], mass_at_origin, compliance);
  };
  expectBoundAt(problem, kMaxPlausibleJointError / per_kg, model.robot().joints[static_cast<std::size_t>(joint)].name);
}

TEST(DiscoveryBounds, ALinkBentAgainstItsLoadIsNotDiscovered) {
  // The truth's upper arm bends backwards (a negative s: no beam does that), enough to tempt the fit.
  JointErrorModel truth = rx170Model();
  truth.addEffect(std::make_unique<LinkBendingEffect>(truth.robot(), std::vector<double>{0, -4e-7, 0, 0, 0, 0}));
  DiscoveryOptions options;
  options.types = {"link_bending"};
  options.max_steps = 2;
  const DiscoveryResult r =
      discoverEffects(rx170Model(), {randomCampaign(truth, 240, 81)}, {randomCampaign(truth, 120, 82)}, options);
  std::string rejected = r.rejected_at_stop;
  for (const DiscoveryStep& s : r.steps) rejected += " " + s.rejected;
  std::printf("[ bounds ] steps %zu; rejected: %s\n", r.steps.size(), rejected.c_str());
  for (const DiscoveryStep& s : r.steps) {
    for (const DiscoveredParameter& p : s.parameters) {
      std::printf("[ bounds ]   %s %s = %g\n", s.type.c_str(), p.name.c_str(), p.value);
      if (p.name.find("deflection") != std::string::npos) {
        EXPECT_GE(p.value, 0.0) << p.name;
      }
    }
  }
  EXPECT_NE(rejected.find("against its load"), std::string::npos) << rejected;
  // Refused as not physical, which is not said to be a failure to transfer.
  EXPECT_EQ(rejected.find("does not transfer"), std::string::npos) << rejected;
}

}  // namespace
}  // namespace jointcomp
