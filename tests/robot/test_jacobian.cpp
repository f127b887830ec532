// Geometric Jacobians against central finite differences of forward kinematics: the tool position, and
// the orientation through the rotation vector of R(q + h e_i) R(q - h e_i)^T divided by 2h.
#include <random>

#include <gtest/gtest.h>
#include <Eigen/SVD>

#include "model/robot/kinematics.hpp"
#include "robot_test_support.hpp"

namespace jointcomp {
namespace {

using testing_support::rotationVector;

// Finite-difference Jacobian of a point fixed to the tool (given in tool coordinates).
Jacobian finiteDifferenceJacobian(const Robot& robot, const JointVector& q, const Eigen::Vector3d& point_in_tool,
                                  double h) {
  RobotWorkspace ws(robot);
  Jacobian jacobian(6, robot.dof());
  for (int i = 0; i < robot.dof(); ++i) {
    JointVector plus = q;
    JointVector minus = q;
    plus[i] += h;
    minus[i] -= h;
    forwardKinematics(robot, ws, plus);
    const Eigen::Isometry3d pose_plus = ws.tool_pose;
    forwardKinematics(robot, ws, minus);
    const Eigen::Isometry3d pose_minus = ws.tool_pose;
    jacobian.col(i).head<3>() = (pose_plus * point_in_tool - pose_minus * point_in_tool) / (2.0 * h);
    jacobian.col(i).tail<3>() = rotationVector(pose_plus.linear() * pose_minus.linear().transpose()) / (2.0 * h);
  }
  return jacobian;
}

void expectToolJacobianMatchesFiniteDifferences(const Robot& robot, unsigned seed) {
  RobotWorkspace ws(robot);
  std::mt19937 rng(seed);
  const double h = 1e-6;
  double worst = 0.0;
  for (int sample = 0; sample < 200; ++sample) {
    const JointVector q = testing_support::randomConfiguration(robot, rng);
    forwardKinematics(robot, ws, q);
    Jacobian jacobian;
    toolJacobian(robot, ws, jacobian);
    ASSERT_EQ(jacobian.cols(), robot.dof());
    const Jacobian reference = finiteDifferenceJacobian(robot, q, Eigen::Vector3d::Zero(), h);
    worst = std::max(worst, (jacobian - reference).cwiseAbs().maxCoeff());
  }
  // Central differences: truncation ~ h^2 |d3 f| (metres), rounding ~ eps |f| / h.
  EXPECT_LT(worst, 1e-8) << robot.name;
}

TEST(ToolJacobian, Rx170MatchesCentralFiniteDifferences) {
  expectToolJacobianMatchesFiniteDifferences(testing_support::rx170(), 101u);
}

TEST(ToolJacobian, Ur10MatchesCentralFiniteDifferences) {
  expectToolJacobianMatchesFiniteDifferences(testing_support::ur10(), 102u);
}

TEST(PointJacobian, PointFixedToTheToolMatchesFiniteDifferences) {
  for (const Robot* robot : {&testing_support::rx170(), &testing_support::ur10()}) {
    RobotWorkspace ws(*robot);
    std::mt19937 rng(103u);
    const Eigen::Vector3d point_in_tool(0.05, -0.12, 0.2);
    for (int sample = 0; sample < 50; ++sample) {
      const JointVector q = testing_support::randomConfiguration(*robot, rng);
      forwardKinematics(*robot, ws, q);
      Jacobian jacobian;
      pointJacobian(*robot, ws, ws.tool_pose * point_in_tool, jacobian);
      const Jacobian reference = finiteDifferenceJacobian(*robot, q, point_in_tool, 1e-6);
      EXPECT_LT((jacobian - reference).cwiseAbs().maxCoeff(), 1e-8) << robot->name;
    }
  }
}

TEST(ToolJacobian, PredictsTheToolVelocityAlongAMotion) {
  // d/dt of the tool pose along q(t) = q0 + t qd equals J qd (a directional finite difference, so every
  // column enters at once with its own weight).
  const Robot& robot = testing_support::rx170();
  RobotWorkspace ws(robot);
  std::mt19937 rng(104u);
  for (int sample = 0; sample < 50; ++sample) {
    const JointVector q = testing_support::randomConfiguration(robot, rng);
    const JointVector qd = testing_support::randomVector(6, rng, 1.0);
    const double h = 1e-6;
    forwardKinematics(robot, ws, q + h * qd);
    const Eigen::Isometry3d plus = ws.tool_pose;
    forwardKinematics(robot, ws, q - h * qd);
    const Eigen::Isometry3d minus = ws.tool_pose;
    forwardKinematics(robot, ws, q);
    Jacobian jacobian;
    toolJacobian(robot, ws, jacobian);
    const Vector6 twist = jacobian * qd;
    EXPECT_LT((twist.head<3>() - (plus.translation() - minus.translation()) / (2 * h)).norm(), 1e-8);
    EXPECT_LT((twist.tail<3>() - rotationVector(plus.linear() * minus.linear().transpose()) / (2 * h)).norm(), 1e-8);
  }
}

TEST(ToolJacobian, Rx170IsRankDeficientWhenTheWristIsStraight) {
  // q5 = 0 aligns axes 4 and 6: the Jacobian loses a rank there, and only there among these samples.
  const Robot& robot = testing_support::rx170();
  RobotWorkspace ws(robot);
  JointVector q(6);
  q << 0.3, -0.4, 1.1, 0.7, 0.0, -0.2;
  forwardKinematics(robot, ws, q);
  Jacobian jacobian;
  toolJacobian(robot, ws, jacobian);
  const Eigen::Matrix<double, 6, 6> square_singular = jacobian;
  Eigen::JacobiSVD<Eigen::Matrix<double, 6, 6>> singular(square_singular);
  EXPECT_LT(singular.singularValues()(5), 1e-12);
  q[4] = 0.5;
  forwardKinematics(robot, ws, q);
  toolJacobian(robot, ws, jacobian);
  const Eigen::Matrix<double, 6, 6> square_regular = jacobian;
  Eigen::JacobiSVD<Eigen::Matrix<double, 6, 6>> regular(square_regular);
  EXPECT_GT(regular.singularValues()(5), 1e-3);
}

}  // namespace
}  // namespace jointcomp
