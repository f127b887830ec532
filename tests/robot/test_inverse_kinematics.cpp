// Inverse kinematics as round trips through forward kinematics: every returned solution must reproduce
// the target, the configuration the target came from must be among the closed-form solutions, all eight
// arm/elbow/wrist branches must show up, and the singular, unreachable and invalid cases behave as
// documented in inverse_kinematics.hpp.
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <tuple>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <Eigen/SVD>

#include "model/common/errors.hpp"
#include "model/robot/inverse_kinematics.hpp"
#include "model/robot/kinematics.hpp"
#include "robot_test_support.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;
using testing_support::kPi;
using testing_support::maxWrappedDifference;
using testing_support::rotationDistance;

Eigen::Isometry3d toolPose(const Robot& robot, const JointVector& q) {
  RobotWorkspace ws(robot);
  forwardKinematics(robot, ws, q);
  return ws.tool_pose;
}

struct PoseGap {
  double position, rotation;
};

PoseGap gap(const Robot& robot, const JointVector& q, const Eigen::Isometry3d& target) {
  const Eigen::Isometry3d pose = toolPose(robot, q);
  return {(pose.translation() - target.translation()).norm(), rotationDistance(pose.linear(), target.linear())};
}

bool withinLimits(const Robot& robot, const JointVector& q) {
  for (int i = 0; i < robot.dof(); ++i) {
    if (q[i] < robot.joints[i].lower - 1e-12 || q[i] > robot.joints[i].upper + 1e-12) return false;
  }
  return true;
}

// Branch of an RX170 solution, from its geometry rather than from how the solver enumerates:
// shoulder (wrist centre in front of axis 1, on the side of the shoulder offset, or behind it),
// elbow (sign of sin q3; q3 = 0 is the stretched arm) and wrist (sign of sin q5; q5 = 0 is straight).
std::tuple<bool, bool, bool> branchOf(const Robot& robot, const JointVector& q) {
  RobotWorkspace ws(robot);
  forwardKinematics(robot, ws, q);
  const Eigen::Vector3d a1 = ws.axis[0];
  auto radial = [&](const Eigen::Vector3d& v) { return Eigen::Vector3d(v - a1 * a1.dot(v)); };
  const Eigen::Vector3d offset = radial(ws.origin[1] - ws.origin[0]);
  const Eigen::Vector3d wrist = radial(ws.origin[4] - ws.origin[0]);
  return {offset.dot(wrist) > 0.0, std::sin(q[2]) > 0.0, std::sin(q[4]) > 0.0};
}

TEST(InverseKinematics, ClosedFormIsDetectedForTheRx170Only) {
  EXPECT_TRUE(InverseKinematics(testing_support::rx170()).hasClosedForm());
  // The UR10's joints 2, 3 and 4 are parallel and its wrist axes do not meet.
  InverseKinematics ur10(testing_support::ur10());
  EXPECT_FALSE(ur10.hasClosedForm());
  std::array<IkSolution, 8> solutions;
  EXPECT_THROW(
      ur10.allSolutions(toolPose(testing_support::ur10(), JointVector::Zero(6)), JointVector::Zero(6), solutions),
      InvalidArgument);
}

TEST(InverseKinematics, Rx170RoundTripsOverRandomReachablePoses) {
  const Robot& robot = testing_support::rx170();
  InverseKinematics ik(robot);
  std::mt19937 rng(401u);
  std::set<std::tuple<bool, bool, bool>> branches_seen;
  int total_solutions = 0;
  int targets_with_eight = 0;
  const int samples = 1000;
  for (int sample = 0; sample < samples; ++sample) {
    const JointVector q = testing_support::randomConfiguration(robot, rng);
    const Eigen::Isometry3d target = toolPose(robot, q);
    const JointVector seed = testing_support::randomConfiguration(robot, rng);
    std::array<IkSolution, 8> solutions;
    const int count = ik.allSolutions(target, seed, solutions);
    ASSERT_GE(count, 1) << "sample " << sample << " q " << q.transpose();
    ASSERT_LE(count, 8);
    total_solutions += count;
    if (count == 8) ++targets_with_eight;
    bool found_original = false;
    std::set<std::tuple<bool, bool, bool>> branches_here;
    for (int s = 0; s < count; ++s) {
      const JointVector& solution = solutions[s].q;
      ASSERT_EQ(solution.size(), 6);
      EXPECT_FALSE(solutions[s].singular) << "sample " << sample;
      EXPECT_TRUE(withinLimits(robot, solution)) << "sample " << sample << " solution " << solution.transpose();
      const PoseGap g = gap(robot, solution, target);
      EXPECT_LT(g.position, 1e-9) << "sample " << sample << " solution " << s;
      EXPECT_LT(g.rotation, 1e-9) << "sample " << sample << " solution " << s;
      found_original = found_original || maxWrappedDifference(solution, q) < 1e-8;
      // Each joint as close to the seed as the limits allow: no 2 pi shift inside the limits is closer.
      for (int i = 0; i < 6; ++i) {
        for (double shift : {-2.0 * kPi, 2.0 * kPi}) {
          const double other = solution[i] + shift;
          if (other >= robot.joints[i].lower && other <= robot.joints[i].upper) {
            EXPECT_LE(std::abs(solution[i] - seed[i]), std::abs(other - seed[i]) + 1e-12)
                << "sample " << sample << " joint " << i + 1;
          }
        }
      }
      branches_here.insert(branchOf(robot, solution));
    }
    EXPECT_TRUE(found_original) << "sample " << sample << ": q = " << q.transpose() << " not among " << count;
    // Distinct solutions lie on distinct branches.
    EXPECT_EQ(static_cast<int>(branches_here.size()), count) << "sample " << sample;
    branches_seen.insert(branches_here.begin(), branches_here.end());
  }
  EXPECT_EQ(branches_seen.size(), 8u);
  EXPECT_GT(targets_with_eight, 0);
  RecordProperty("solutions", total_solutions);
  RecordProperty("targets_with_eight_solutions", targets_with_eight);
}

TEST(InverseKinematics, Rx170WithoutLimitsFindsAllEightBranchesOfAPoseNearTheBase) {
  // The folded elbow keeps the wrist centre near axis 1, within reach of the shoulder turned half round,
  // so the four "behind" branches exist as well as the four "in front".
  const Robot& robot = testing_support::rx170();
  IkOptions options;
  options.respect_limits = false;
  InverseKinematics ik(robot, options);
  JointVector q(6);
  q << 0.4, 0.3, 2.0, 0.5, 0.8, -0.3;
  const Eigen::Isometry3d target = toolPose(robot, q);
  std::array<IkSolution, 8> solutions;
  const int count = ik.allSolutions(target, q, solutions);
  ASSERT_EQ(count, 8);
  std::set<std::tuple<bool, bool, bool>> branches;
  for (int s = 0; s < count; ++s) {
    const PoseGap g = gap(robot, solutions[s].q, target);
    EXPECT_LT(g.position, 1e-9);
    EXPECT_LT(g.rotation, 1e-9);
    branches.insert(branchOf(robot, solutions[s].q));
  }
  EXPECT_EQ(branches.size(), 8u);
}

TEST(InverseKinematics, Rx170SolvePicksTheSolutionClosestToTheSeed) {
  const Robot& robot = testing_support::rx170();
  InverseKinematics ik(robot);
  std::mt19937 rng(402u);
  int unambiguous = 0;
  for (int sample = 0; sample < 200; ++sample) {
    const JointVector q = testing_support::randomConfiguration(robot, rng, 0.05);
    const Eigen::Isometry3d target = toolPose(robot, q);
    std::array<IkSolution, 8> solutions;
    const int count = ik.allSolutions(target, q, solutions);
    ASSERT_GE(count, 1);
    for (int s = 0; s < count; ++s) {
      const JointVector seed = solutions[s].q + testing_support::randomVector(6, rng, 0.02);
      const IkSolution picked = ik.solve(target, seed);
      // solve() returns the solution nearest to the seed among all of them (each wrapped towards the seed).
      std::array<IkSolution, 8> around_seed;
      const int n = ik.allSolutions(target, seed, around_seed);
      double nearest = std::numeric_limits<double>::infinity();
      double second = std::numeric_limits<double>::infinity();
      for (int k = 0; k < n; ++k) {
        const double distance = (around_seed[k].q - seed).norm();
        if (distance < nearest) {
          second = nearest;
          nearest = distance;
        } else {
          second = std::min(second, distance);
        }
      }
      EXPECT_NEAR((picked.q - seed).norm(), nearest, 1e-12) << "sample " << sample;
      // When the seed is clearly nearest to the branch it was made from, that branch comes back (two
      // branches can lie closer together than the seed's noise, e.g. near a stretched arm).
      if (second - nearest > 0.1) {
        ++unambiguous;
        EXPECT_LT((picked.q - solutions[s].q).cwiseAbs().maxCoeff(), 1e-8)
            << "sample " << sample << " branch " << s << " q " << q.transpose();
      }
    }
    // The configuration the target came from, from a seed near it.
    const IkSolution back = ik.solve(target, q + testing_support::randomVector(6, rng, 1e-3));
    EXPECT_LT((back.q - q).cwiseAbs().maxCoeff(), 1e-8) << "sample " << sample << " q " << q.transpose();
  }
  EXPECT_GT(unambiguous, 500);
}

// Smallest singular value of the tool Jacobian: how far a configuration is from a singularity.
double smallestSingularValue(const Robot& robot, const JointVector& q) {
  RobotWorkspace ws(robot);
  forwardKinematics(robot, ws, q);
  Jacobian jacobian;
  toolJacobian(robot, ws, jacobian);
  const Eigen::Matrix<double, 6, 6> square = jacobian;
  return Eigen::JacobiSVD<Eigen::Matrix<double, 6, 6>>(square).singularValues()(5);
}

TEST(InverseKinematics, Ur10DampedLeastSquaresConvergesFromANearbySeed) {
  const Robot& robot = testing_support::ur10();
  InverseKinematics ik(robot);
  std::mt19937 rng(403u);
  int tested = 0;
  for (int sample = 0; sample < 200; ++sample) {
    const JointVector q = testing_support::randomConfiguration(robot, rng, 0.1);
    const JointVector seed = q + testing_support::randomVector(6, rng, 0.05);
    // Away from singularities only (near one the tolerance of 1e-10 is not reached in 200 iterations).
    if (smallestSingularValue(robot, q) < 1e-2) continue;
    ++tested;
    const Eigen::Isometry3d target = toolPose(robot, q);
    IkSolution solution;
    ASSERT_NO_THROW(solution = ik.solve(target, seed)) << "sample " << sample << " q " << q.transpose();
    const PoseGap g = gap(robot, solution.q, target);
    EXPECT_LT(g.position, 1e-9) << "sample " << sample;
    EXPECT_LT(g.rotation, 1e-9) << "sample " << sample;
    EXPECT_TRUE(withinLimits(robot, solution.q));
    EXPECT_FALSE(solution.singular) << "sample " << sample;
    // From that close, the iteration stays on the branch of the original configuration.
    EXPECT_LT(maxWrappedDifference(solution.q, q), 1e-6) << "sample " << sample;
  }
  EXPECT_GT(tested, 150);
}

TEST(InverseKinematics, FarTargetsAreUnreachable) {
  for (const Robot* robot : {&testing_support::rx170(), &testing_support::ur10()}) {
    InverseKinematics ik(*robot);
    JointVector seed = JointVector::Zero(6);
    seed[1] = 0.3;
    seed[2] = 0.5;
    seed[4] = 0.6;
    Eigen::Isometry3d target = toolPose(*robot, seed);
    target.translation() += Eigen::Vector3d(5.0, 0.0, 0.0);
    try {
      ik.solve(target, seed);
      ADD_FAILURE() << robot->name << ": a target 5 m away was reached";
    } catch (const UnreachableError& error) {
      EXPECT_THAT(error.what(), HasSubstr("target")) << robot->name;
      EXPECT_GT(std::string(error.what()).size(), 20u);
    }
    if (ik.hasClosedForm()) {
      std::array<IkSolution, 8> solutions;
      EXPECT_THROW(ik.allSolutions(target, seed, solutions), UnreachableError);
    }
  }
}

TEST(InverseKinematics, Rx170TargetReachableOnlyBeyondTheLimitsIsUnreachable) {
  const Robot& robot = testing_support::rx170();
  // q3 = 2.8 is beyond the 150 degree elbow limit; every other branch of this pose is outside too.
  JointVector q(6);
  q << 0.0, 0.3, 2.8, 0.2, 0.5, 0.1;
  ASSERT_FALSE(withinLimits(robot, q));
  const Eigen::Isometry3d target = toolPose(robot, q);
  IkOptions free;
  free.respect_limits = false;
  InverseKinematics unlimited(robot, free);
  std::array<IkSolution, 8> solutions;
  const int without_limits = unlimited.allSolutions(target, q, solutions);
  ASSERT_GT(without_limits, 0);
  bool found_original = false;
  for (int s = 0; s < without_limits; ++s)
    found_original = found_original || maxWrappedDifference(solutions[s].q, q) < 1e-8;
  EXPECT_TRUE(found_original);

  InverseKinematics limited(robot);
  EXPECT_EQ(limited.allSolutions(target, q, solutions), 0);
  try {
    limited.solve(target, JointVector::Zero(6));
    ADD_FAILURE() << "solved beyond the limits";
  } catch (const UnreachableError& error) {
    EXPECT_THAT(error.what(), HasSubstr("limit"));
  }
}

TEST(InverseKinematics, Rx170StraightWristKeepsJoint4AtTheSeed) {
  const Robot& robot = testing_support::rx170();
  InverseKinematics ik(robot);
  JointVector q(6);
  q << 0.3, -0.4, 1.1, 0.7, 0.0, -0.2;
  const Eigen::Isometry3d target = toolPose(robot, q);
  for (double seed4 : {-0.5, 0.7, 2.0}) {
    JointVector seed = q;
    seed[3] = seed4;
    const IkSolution solution = ik.solve(target, seed);
    EXPECT_TRUE(solution.singular) << "seed q4 " << seed4;
    EXPECT_NEAR(solution.q[3], seed4, 1e-12);
    const PoseGap g = gap(robot, solution.q, target);
    EXPECT_LT(g.position, 1e-9);
    EXPECT_LT(g.rotation, 1e-9);
    // Axes 4 and 6 are aligned: q4 and q6 only matter through their sum (or difference).
    EXPECT_NEAR(testing_support::angleDifference(solution.q[3] + solution.q[5], q[3] + q[5]), 0.0, 1e-9);
    EXPECT_LT((solution.q.head<3>() - q.head<3>()).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_NEAR(std::remainder(solution.q[4], 2 * kPi), 0.0, 1e-9);
  }
  std::array<IkSolution, 8> solutions;
  JointVector seed = q;
  seed[3] = -0.5;
  const int count = ik.allSolutions(target, seed, solutions);
  ASSERT_GT(count, 0);
  int straight = 0;
  for (int s = 0; s < count; ++s) {
    // Only the branches whose forearm points along the tool have q5 = 0; the others (elbow or shoulder
    // flipped) bend the wrist and are regular.
    if (std::abs(std::sin(solutions[s].q[4])) < 1e-9) {
      ++straight;
      EXPECT_TRUE(solutions[s].singular);
      EXPECT_NEAR(solutions[s].q[3], -0.5, 1e-12);
    } else {
      EXPECT_FALSE(solutions[s].singular);
    }
    EXPECT_LT(gap(robot, solutions[s].q, target).position, 1e-9);
    EXPECT_LT(gap(robot, solutions[s].q, target).rotation, 1e-9);
  }
  EXPECT_GE(straight, 1);
}

TEST(InverseKinematics, Rx170WristCentreOnAxis1KeepsJoint1AtTheSeed) {
  // The 0.15 m shoulder offset does not keep the wrist centre off axis 1: with q1 = 0 and q2 = 0.2, find
  // the q3 that brings the wrist centre (origin of joint 5) onto the z axis by a secant iteration.
  const Robot& robot = testing_support::rx170();
  RobotWorkspace ws(robot);
  JointVector q(6);
  q << 0.0, 0.2, -0.5, 0.6, 0.9, -0.4;
  auto wristX = [&](double q3) {
    JointVector trial = q;
    trial[2] = q3;
    forwardKinematics(robot, ws, trial);
    return ws.origin[4].x();
  };
  double a = -0.5, b = -0.4;
  double fa = wristX(a), fb = wristX(b);
  for (int iteration = 0; iteration < 50 && std::abs(fb) > 1e-16 && fb != fa; ++iteration) {
    const double c = b - fb * (b - a) / (fb - fa);
    a = b;
    fa = fb;
    b = c;
    fb = wristX(b);
  }
  q[2] = b;
  forwardKinematics(robot, ws, q);
  ASSERT_LT(ws.origin[4].head<2>().norm(), 1e-14) << "the wrist centre is not on axis 1: " << ws.origin[4].transpose();
  ASSERT_TRUE(withinLimits(robot, q));
  const Eigen::Isometry3d target = ws.tool_pose;

  InverseKinematics ik(robot);
  for (double seed1 : {0.0, 0.5, -1.2}) {
    JointVector seed = q;
    seed[0] = seed1;
    const IkSolution solution = ik.solve(target, seed);
    EXPECT_TRUE(solution.singular) << "seed q1 " << seed1;
    EXPECT_NEAR(solution.q[0], seed1, 1e-12);
    const PoseGap g = gap(robot, solution.q, target);
    EXPECT_LT(g.position, 1e-9) << "seed q1 " << seed1;
    EXPECT_LT(g.rotation, 1e-9) << "seed q1 " << seed1;
    // Arm and elbow are unchanged by turning about the axis the wrist centre sits on.
    EXPECT_LT((solution.q.segment(1, 2) - q.segment(1, 2)).cwiseAbs().maxCoeff(), 1e-9) << "seed q1 " << seed1;
  }
}

TEST(InverseKinematics, Rx170StretchedArmIsSingularAndReproducesThePose) {
  const Robot& robot = testing_support::rx170();
  InverseKinematics ik(robot);
  JointVector q(6);
  q << 0.4, 0.3, 0.0, 0.5, 0.8, -0.3;
  const Eigen::Isometry3d target = toolPose(robot, q);
  const IkSolution solution = ik.solve(target, q);
  EXPECT_TRUE(solution.singular);
  const PoseGap g = gap(robot, solution.q, target);
  EXPECT_LT(g.position, 1e-9);
  EXPECT_LT(g.rotation, 1e-9);
  // acos near 1 loses half the digits: the joints are only good to about 1e-7 here.
  EXPECT_LT((solution.q - q).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(InverseKinematics, NonFiniteTargetOrSeedThrowsInvalidArgument) {
  for (const Robot* robot : {&testing_support::rx170(), &testing_support::ur10()}) {
    InverseKinematics ik(*robot);
    const JointVector seed = JointVector::Constant(6, 0.3);
    Eigen::Isometry3d target = toolPose(*robot, seed);
    Eigen::Isometry3d nan_target = target;
    nan_target.translation().y() = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(ik.solve(nan_target, seed), InvalidArgument) << robot->name;
    Eigen::Isometry3d nan_rotation = target;
    nan_rotation.linear()(1, 1) = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(ik.solve(nan_rotation, seed), InvalidArgument) << robot->name;
    JointVector nan_seed = seed;
    nan_seed[2] = std::numeric_limits<double>::quiet_NaN();
    EXPECT_THROW(ik.solve(target, nan_seed), InvalidArgument) << robot->name;
    EXPECT_THROW(ik.solve(target, JointVector::Zero(5)), InvalidArgument) << robot->name;
    if (ik.hasClosedForm()) {
      std::array<IkSolution, 8> solutions;
      EXPECT_THROW(ik.allSolutions(nan_target, seed, solutions), InvalidArgument);
      EXPECT_THROW(ik.allSolutions(target, nan_seed, solutions), InvalidArgument);
    }
  }
}

}  // namespace
}  // namespace jointcomp
