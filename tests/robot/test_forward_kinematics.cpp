// Forward kinematics against an independent standard-DH chain written here from the DH tables the URDFs
// were made from (T_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)), plus hand-computed poses and argument checks.
#include <array>
#include <cmath>
#include <limits>
#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/robot/kinematics.hpp"
#include "robot_test_support.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;
using testing_support::kPi;
using testing_support::rotationDistance;

struct DhRow {
  double d, a, alpha, theta_offset;
};
using DhTable = std::array<DhRow, 6>;

// Staubli RX170 BL (ARTE robots/STAUBLI/RX170BL/parameters.m).
const DhTable kRx170Dh = {{{0.55, 0.15, -kPi / 2, 0.0},
                           {0.0, 0.825, 0.0, -kPi / 2},
                           {0.0, 0.0, kPi / 2, kPi / 2},
                           {0.925, 0.0, -kPi / 2, 0.0},
                           {0.0, 0.0, kPi / 2, 0.0},
                           {0.11, 0.0, 0.0, 0.0}}};

// Universal Robots UR10 (CB series), published DH.
const DhTable kUr10Dh = {{{0.1273, 0.0, kPi / 2, 0.0},
                          {0.0, -0.612, 0.0, 0.0},
                          {0.0, -0.5723, 0.0, 0.0},
                          {0.163941, 0.0, kPi / 2, 0.0},
                          {0.1157, 0.0, -kPi / 2, 0.0},
                          {0.0922, 0.0, 0.0, 0.0}}};

Eigen::Matrix4d rotZ(double angle) {
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  t(0, 0) = std::cos(angle);
  t(0, 1) = -std::sin(angle);
  t(1, 0) = std::sin(angle);
  t(1, 1) = std::cos(angle);
  return t;
}

Eigen::Matrix4d rotX(double angle) {
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  t(1, 1) = std::cos(angle);
  t(1, 2) = -std::sin(angle);
  t(2, 1) = std::sin(angle);
  t(2, 2) = std::cos(angle);
  return t;
}

Eigen::Matrix4d translation(double x, double y, double z) {
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity();
  t(0, 3) = x;
  t(1, 3) = y;
  t(2, 3) = z;
  return t;
}

// frames[0] is the base, frames[i] the DH frame i; the flange is frames[6].
std::array<Eigen::Matrix4d, 7> dhFrames(const DhTable& table, const JointVector& q) {
  std::array<Eigen::Matrix4d, 7> frames;
  frames[0].setIdentity();
  for (int i = 0; i < 6; ++i) {
    const DhRow& row = table[i];
    frames[i + 1] = frames[i] * rotZ(q[i] + row.theta_offset) * translation(0, 0, row.d) * translation(row.a, 0, 0) *
                    rotX(row.alpha);
  }
  return frames;
}

Eigen::Matrix4d dhFlange(const DhTable& table, const JointVector& q) { return dhFrames(table, q)[6]; }

struct Comparison {
  double position = 0.0;
  double rotation = 0.0;
};

Comparison compare(const Eigen::Isometry3d& pose, const Eigen::Matrix4d& reference) {
  Comparison result;
  result.position = (pose.translation() - reference.block<3, 1>(0, 3)).cwiseAbs().maxCoeff();
  result.rotation = rotationDistance(pose.linear(), reference.block<3, 3>(0, 0));
  return result;
}

void expectToolMatchesDh(const Robot& robot, const DhTable& table, unsigned seed) {
  RobotWorkspace ws(robot);
  std::mt19937 rng(seed);
  double worst_position = 0.0;
  double worst_rotation = 0.0;
  for (int sample = 0; sample < 1000; ++sample) {
    const JointVector q = testing_support::randomConfiguration(robot, rng);
    forwardKinematics(robot, ws, q);
    const Eigen::Matrix4d flange = dhFlange(table, q);
    const Comparison c = compare(ws.tool_pose, flange);
    worst_position = std::max(worst_position, c.position);
    worst_position = std::max(worst_position, (toolPosition(robot, q) - flange.block<3, 1>(0, 3)).norm());
    worst_rotation = std::max(worst_rotation, c.rotation);
    // The rotation part must stay orthonormal.
    ASSERT_LT(
        (ws.tool_pose.linear().transpose() * ws.tool_pose.linear() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(),
        1e-14);
  }
  EXPECT_LT(worst_position, 1e-12) << robot.name;
  EXPECT_LT(worst_rotation, 1e-12) << robot.name;
}

// Joint i of jointcomp turns about the z axis of DH frame i-1 at that frame's origin: its frame at q is
// DH frame i-1 rotated by theta_i about z.
void expectJointFramesMatchDh(const Robot& robot, const DhTable& table, unsigned seed) {
  RobotWorkspace ws(robot);
  std::mt19937 rng(seed);
  for (int sample = 0; sample < 200; ++sample) {
    const JointVector q = testing_support::randomConfiguration(robot, rng);
    forwardKinematics(robot, ws, q);
    const auto frames = dhFrames(table, q);
    for (int i = 0; i < 6; ++i) {
      const Eigen::Matrix4d joint_frame = frames[i] * rotZ(q[i] + table[i].theta_offset);
      const Comparison c = compare(ws.joint_pose[i], joint_frame);
      ASSERT_LT(c.position, 1e-12) << robot.name << " joint " << i;
      ASSERT_LT(c.rotation, 1e-12) << robot.name << " joint " << i;
      ASSERT_LT((ws.origin[i] - frames[i].block<3, 1>(0, 3)).norm(), 1e-12) << robot.name << " joint " << i;
      ASSERT_LT((ws.axis[i] - frames[i].block<3, 1>(0, 2)).norm(), 1e-12) << robot.name << " joint " << i;
      // The centre of mass rides with the body: fixed in the joint frame.
      const Eigen::Vector3d com_expected =
          joint_frame.block<3, 3>(0, 0) * robot.joints[i].body.com + joint_frame.block<3, 1>(0, 3);
      ASSERT_LT((ws.com[i] - com_expected).norm(), 1e-12) << robot.name << " joint " << i;
    }
  }
}

TEST(ForwardKinematics, Rx170ToolPoseMatchesStandardDhOver1000RandomConfigurations) {
  ASSERT_EQ(testing_support::rx170().dof(), 6);
  expectToolMatchesDh(testing_support::rx170(), kRx170Dh, 17u);
}

TEST(ForwardKinematics, Ur10ToolPoseMatchesStandardDhOver1000RandomConfigurations) {
  ASSERT_EQ(testing_support::ur10().dof(), 6);
  expectToolMatchesDh(testing_support::ur10(), kUr10Dh, 29u);
}

TEST(ForwardKinematics, Rx170JointFramesAxesAndCentresOfMassMatchDh) {
  expectJointFramesMatchDh(testing_support::rx170(), kRx170Dh, 5u);
}

TEST(ForwardKinematics, Ur10JointFramesAxesAndCentresOfMassMatchDh) {
  expectJointFramesMatchDh(testing_support::ur10(), kUr10Dh, 6u);
}

TEST(ForwardKinematics, Rx170StandsVerticalAtZero) {
  const Robot& robot = testing_support::rx170();
  RobotWorkspace ws(robot);
  forwardKinematics(robot, ws, JointVector::Zero(6));
  const Eigen::Vector3d flange = ws.tool_pose.translation();
  EXPECT_NEAR(flange.x(), 0.15, 1e-12);
  EXPECT_NEAR(flange.y(), 0.0, 1e-12);
  EXPECT_NEAR(flange.z(), 0.55 + 0.825 + 0.925 + 0.11, 1e-12);
  // The whole arm above the shoulder is one vertical line: joints 2..6 all sit at x = 0.15, y = 0.
  for (int i = 1; i < 6; ++i) {
    EXPECT_NEAR(ws.origin[i].x(), 0.15, 1e-12) << "joint " << i + 1;
    EXPECT_NEAR(ws.origin[i].y(), 0.0, 1e-12) << "joint " << i + 1;
  }
  // The tool points straight up; axes 1, 4 and 6 are vertical.
  EXPECT_LT((ws.tool_pose.linear().col(2) - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
  for (int i : {0, 3, 5}) EXPECT_NEAR(std::abs(ws.axis[i].z()), 1.0, 1e-12) << "axis " << i + 1;
  for (int i : {1, 2, 4}) EXPECT_NEAR(ws.axis[i].z(), 0.0, 1e-12) << "axis " << i + 1;
}

TEST(ForwardKinematics, Ur10ZeroPoseIsTheTextbookOne) {
  // At q = 0 the UR arm lies stretched along x: p = (a2 + a3, -(d4 + d6), d1 - d5).
  const Robot& robot = testing_support::ur10();
  RobotWorkspace ws(robot);
  forwardKinematics(robot, ws, JointVector::Zero(6));
  EXPECT_NEAR(ws.tool_pose.translation().x(), -0.612 - 0.5723, 1e-12);
  EXPECT_NEAR(ws.tool_pose.translation().y(), -(0.163941 + 0.0922), 1e-12);
  EXPECT_NEAR(ws.tool_pose.translation().z(), 0.1273 - 0.1157, 1e-12);
}

TEST(ForwardKinematics, Rx170ShoulderRotationTurnsTheWholeArmAboutZ) {
  // Turning joint 1 by phi rotates the tool pose about the base z axis by phi, nothing else.
  const Robot& robot = testing_support::rx170();
  RobotWorkspace ws(robot);
  std::mt19937 rng(3u);
  for (int sample = 0; sample < 50; ++sample) {
    JointVector q = testing_support::randomConfiguration(robot, rng, 0.5);
    forwardKinematics(robot, ws, q);
    const Eigen::Isometry3d before = ws.tool_pose;
    const double phi = 0.4;
    q[0] += phi;
    forwardKinematics(robot, ws, q);
    const Eigen::Isometry3d expected = Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitZ()) * before;
    EXPECT_LT((ws.tool_pose.matrix() - expected.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST(ForwardKinematics, IsDeterministic) {
  const Robot& robot = testing_support::rx170();
  RobotWorkspace first(robot);
  RobotWorkspace second(robot);
  JointVector q(6);
  q << 0.1, -0.7, 1.3, 2.2, -0.4, 3.0;
  forwardKinematics(robot, first, q);
  forwardKinematics(robot, second, q);
  forwardKinematics(robot, second, q);
  EXPECT_TRUE(first.tool_pose.matrix() == second.tool_pose.matrix());
}

TEST(ForwardKinematics, WrongSizeConfigurationThrowsInvalidArgument) {
  const Robot& robot = testing_support::rx170();
  RobotWorkspace ws(robot);
  EXPECT_THROW(forwardKinematics(robot, ws, JointVector::Zero(5)), InvalidArgument);
  EXPECT_THROW(forwardKinematics(robot, ws, JointVector::Zero(7)), InvalidArgument);
  EXPECT_THROW(forwardKinematics(robot, ws, JointVector()), InvalidArgument);
  try {
    forwardKinematics(robot, ws, JointVector::Zero(5));
    FAIL() << "no exception";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("q"));
    EXPECT_THAT(error.what(), HasSubstr("5"));
    EXPECT_THAT(error.what(), HasSubstr("6"));
  }
}

TEST(ForwardKinematics, NonFiniteConfigurationThrowsInvalidArgumentNamingTheJoint) {
  const Robot& robot = testing_support::ur10();
  RobotWorkspace ws(robot);
  JointVector q = JointVector::Zero(6);
  q[2] = std::numeric_limits<double>::quiet_NaN();
  try {
    forwardKinematics(robot, ws, q);
    FAIL() << "no exception for NaN";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("joint_3"));
  }
  q[2] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(forwardKinematics(robot, ws, q), InvalidArgument);
  q[2] = -std::numeric_limits<double>::infinity();
  EXPECT_THROW(forwardKinematics(robot, ws, q), InvalidArgument);
}

// The check's one-branch test (the sum of q_i * 0) against the values it must pass and stop: the largest
// finite values pass (their products with 0 are 0, their sum too), every non-finite value at every joint
// stops, named by its joint.
TEST(ForwardKinematics, CheckPassesEveryFiniteValueAndStopsEveryOtherAtEveryJoint) {
  const Robot& robot = testing_support::rx170();
  RobotWorkspace ws(robot);
  const double largest = std::numeric_limits<double>::max();
  for (const double value : {largest, -largest, std::numeric_limits<double>::denorm_min(), -0.0}) {
    const JointVector q = JointVector::Constant(6, value);
    EXPECT_NO_THROW(checkJointVector(robot, q, "q")) << value;
  }
  for (int joint = 0; joint < 6; ++joint) {
    for (const double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                             -std::numeric_limits<double>::infinity()}) {
      JointVector q = JointVector::Constant(6, 0.5);
      q[joint] = bad;
      try {
        forwardKinematics(robot, ws, q);
        ADD_FAILURE() << "no exception for " << bad << " at joint " << joint;
      } catch (const InvalidArgument& error) {
        EXPECT_THAT(error.what(), HasSubstr(robot.joints[static_cast<std::size_t>(joint)].name));
      }
    }
  }
}

// forwardKinematicsNear: without reuse, forwardKinematics' bits (and the anchors at q); with reuse, poses
// within 1e-15 of forwardKinematics' at configurations moved 1e-9 .. 5e-2 rad from the anchors (the
// Taylor series), and its bits again beyond kSinCosNearAnchor, where every joint is re-anchored by libm.
TEST(ForwardKinematics, NearAnchorsGivesTheSamePosesWithoutLibm) {
  for (const Robot* robot : {&testing_support::rx170(), &testing_support::ur10()}) {
    RobotWorkspace direct(*robot), near(*robot);
    std::mt19937 rng(1726u);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    double largest = 0.0;
    for (int sample = 0; sample < 100; ++sample) {
      JointAngleAnchors anchors;
      const JointVector start = testing_support::randomConfiguration(*robot, rng);
      forwardKinematicsNear(*robot, near, start, anchors, false);
      forwardKinematics(*robot, direct, start);
      ASSERT_TRUE(near.tool_pose.matrix() == direct.tool_pose.matrix());
      for (int j = 0; j < robot->dof(); ++j) {
        ASSERT_EQ(anchors[static_cast<std::size_t>(j)].angle, start[j]);
        ASSERT_TRUE(near.com[static_cast<std::size_t>(j)] == direct.com[static_cast<std::size_t>(j)]);
      }
      for (const double move : {1e-9, 1e-6, 1e-3, 5e-2, 0.1}) {
        JointVector q = start;
        for (int j = 0; j < robot->dof(); ++j) {
          // At 0.1 every joint moves by 0.07 .. 0.1 rad, beyond kSinCosNearAnchor: libm again.
          q[j] += move == 0.1 ? 0.07 + 0.03 * std::abs(unit(rng)) : move * unit(rng);
        }
        JointAngleAnchors moved_anchors = anchors;
        forwardKinematicsNear(*robot, near, q, moved_anchors, true);
        forwardKinematics(*robot, direct, q);
        if (move == 0.1) {
          EXPECT_TRUE(near.tool_pose.matrix() == direct.tool_pose.matrix()) << "sample " << sample;
          for (int j = 0; j < robot->dof(); ++j) EXPECT_EQ(moved_anchors[static_cast<std::size_t>(j)].angle, q[j]);
          continue;
        }
        for (int j = 0; j < robot->dof(); ++j) {
          EXPECT_EQ(moved_anchors[static_cast<std::size_t>(j)].angle, start[j]);  // kept
          const std::size_t i = static_cast<std::size_t>(j);
          largest =
              std::max(largest, (near.joint_pose[i].matrix() - direct.joint_pose[i].matrix()).cwiseAbs().maxCoeff());
          largest = std::max(largest, (near.com[i] - direct.com[i]).cwiseAbs().maxCoeff());
          largest = std::max(largest, (near.axis[i] - direct.axis[i]).cwiseAbs().maxCoeff());
        }
        largest = std::max(largest, (near.tool_pose.matrix() - direct.tool_pose.matrix()).cwiseAbs().maxCoeff());
      }
    }
    EXPECT_LT(largest, 1e-15) << robot->name;
    EXPECT_GT(largest, 0.0) << robot->name << ": the Taylor path was not taken";
  }
}

// The tool's position alone against the chain's product written out here with Eigen's angle-axis rotations
// (placement_i Rot(axis_i, q_i), then the tool), on both robots and on an RX170 with tilted axes and a tool
// offset (the general-axis way); the same checks as forwardKinematics.
TEST(ToolPosition, IsTheChainProductsTranslationOnAnyAxes) {
  Robot tilted = testing_support::tiltedRx170();
  tilted.tool.translation() = Eigen::Vector3d(0.05, -0.02, 0.13);
  std::mt19937 rng(71u);
  for (const Robot* robot : {&testing_support::rx170(), &testing_support::ur10(), static_cast<const Robot*>(&tilted)}) {
    RobotWorkspace ws(*robot);
    double worst = 0.0, worst_fk = 0.0;
    for (int sample = 0; sample < 500; ++sample) {
      const JointVector q = testing_support::randomConfiguration(*robot, rng);
      Eigen::Matrix4d chain = Eigen::Matrix4d::Identity();
      for (int i = 0; i < robot->dof(); ++i) {
        const Joint& joint = robot->joints[static_cast<std::size_t>(i)];
        Eigen::Matrix4d rotation = Eigen::Matrix4d::Identity();
        rotation.block<3, 3>(0, 0) = Eigen::AngleAxisd(q[i], joint.axis).toRotationMatrix();
        chain = chain * joint.placement.matrix() * rotation;
      }
      chain = chain * robot->tool.matrix();
      const Eigen::Vector3d position = toolPosition(*robot, q);
      worst = std::max(worst, (position - chain.block<3, 1>(0, 3)).norm());
      forwardKinematics(*robot, ws, q);
      worst_fk = std::max(worst_fk, (position - ws.tool_pose.translation()).norm());
    }
    EXPECT_LT(worst, 1e-12) << robot->name;
    EXPECT_LT(worst_fk, 1e-13) << robot->name;
  }
  const Robot& robot = testing_support::ur10();
  EXPECT_THROW(toolPosition(robot, JointVector::Zero(5)), InvalidArgument);
  JointVector q = JointVector::Zero(6);
  q[4] = std::numeric_limits<double>::quiet_NaN();
  try {
    toolPosition(robot, q);
    FAIL() << "no exception for NaN";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("joint_5"));
  }
}

TEST(PoseError, IsThePositionDifferenceAndTheRotationVectorFromTo) {
  std::mt19937 rng(11u);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int sample = 0; sample < 100; ++sample) {
    Eigen::Isometry3d from = Eigen::Isometry3d::Identity();
    from.linear() =
        Eigen::Quaterniond(uniform(rng), uniform(rng), uniform(rng), uniform(rng)).normalized().toRotationMatrix();
    from.translation() = Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng));
    const Eigen::Vector3d rotation_vector =
        2.5 * Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng)) / std::sqrt(3.0);  // angle below pi
    const Eigen::Vector3d shift(uniform(rng), uniform(rng), uniform(rng));
    Eigen::Isometry3d to = Eigen::Isometry3d::Identity();
    to.linear() =
        Eigen::AngleAxisd(rotation_vector.norm(), rotation_vector.normalized()).toRotationMatrix() * from.linear();
    to.translation() = from.translation() + shift;
    const Vector6 error = poseError(from, to);
    EXPECT_LT((error.head<3>() - shift).norm(), 1e-14);
    EXPECT_LT((error.tail<3>() - rotation_vector).norm(), 1e-12);
  }
}

}  // namespace
}  // namespace jointcomp
