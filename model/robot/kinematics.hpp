// Forward kinematics and the geometric Jacobian.
#pragma once

#include "model/robot/workspace.hpp"

namespace jointcomp {

// Fills ws.joint_pose, ws.axis, ws.origin, ws.com and ws.tool_pose for the configuration q.
// Throws InvalidArgument for a q of the wrong size or with non-finite values. Allocates nothing.
void forwardKinematics(const Robot& robot, RobotWorkspace& ws, const JointVector& q);

// Geometric Jacobian of the tool frame at the configuration of the last forwardKinematics call:
// rows 0-2 map qd to the tool point's linear velocity, rows 3-5 to the angular velocity, base frame.
void toolJacobian(const Robot& robot, const RobotWorkspace& ws, Jacobian& jacobian);

// Geometric Jacobian of a point fixed to the tool (given in the base frame) at the last forwardKinematics.
void pointJacobian(const Robot& robot, const RobotWorkspace& ws, const Eigen::Vector3d& point, Jacobian& jacobian);

// Pose error (position difference, then rotation vector) taking `from` to `to`, base frame.
Vector6 poseError(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to);

}  // namespace jointcomp
