// Per-thread scratch of the robot algorithms (Pinocchio's Data): one per thread, reused across calls,
// fixed-size so that no algorithm allocates.
#pragma once

#include <array>

#include "model/robot/robot.hpp"

namespace jointcomp {

struct RobotWorkspace {
  explicit RobotWorkspace(const Robot& robot);  // throws InvalidArgument for more than kMaxJoints

  int dof = 0;
  // Filled by forwardKinematics.
  std::array<Eigen::Isometry3d, kMaxJoints> joint_pose;  // base-frame pose of each joint frame at q
  std::array<Eigen::Vector3d, kMaxJoints> axis;          // joint axes, base frame
  std::array<Eigen::Vector3d, kMaxJoints> origin;        // joint frame origins, base frame
  std::array<Eigen::Vector3d, kMaxJoints> com;           // body centres of mass, base frame
  Eigen::Isometry3d tool_pose = Eigen::Isometry3d::Identity();

  // Dynamics scratch.
  std::array<Eigen::Matrix3d, kMaxJoints> inertia;                // body inertia about its com, base axes
  std::array<Eigen::Vector3d, kMaxJoints> omega, omega_dot, acc;  // per body
  std::array<Eigen::Vector3d, kMaxJoints> force, moment;          // transmitted by each joint
  JointMatrix mass_matrix;
  JointMatrix mass_factor;  // its Cholesky factor (lower triangle), by forwardDynamics
  JointVector bias;
};

}  // namespace jointcomp
