// Forward kinematics and the geometric Jacobian.
#pragma once

#include "model/robot/sin_cos_near.hpp"
#include "model/robot/workspace.hpp"

namespace jointcomp {

// Fills ws.joint_pose, ws.axis, ws.origin, ws.com and ws.tool_pose for the configuration q, with the joints'
// sines and cosines from sinCosBatch (model/common/sin_cos.hpp: a pure function of q, no libm).
// Throws InvalidArgument for a q of the wrong size or with non-finite values. Allocates nothing.
void forwardKinematics(const Robot& robot, RobotWorkspace& ws, const JointVector& q);

// The tool's position in the base frame at q, and nothing else: the tool point carried back through each
// joint's rotation and placement, about half of forwardKinematics' instructions (the FMU's tool output at
// every step). Equal to forwardKinematics' tool translation to rounding, not bit for bit (another order of
// the products). Same checks as forwardKinematics; allocates nothing.
Eigen::Vector3d toolPosition(const Robot& robot, const JointVector& q);

// The usual joint axis, exactly (0, 0, 1): rotations about it turn two coordinates, which the kinematics and
// the dynamics take as a fast path.
inline bool isZAxis(const Eigen::Vector3d& axis) { return axis.x() == 0.0 && axis.y() == 0.0 && axis.z() == 1.0; }

// Rot(axis, angle) v about a unit axis from the angle's cosine c and sine s (Rodrigues): v c + (axis x v) s +
// axis (axis . v)(1 - c). The general-axis way of toolPosition and of the joint-frame gravity.
inline Eigen::Vector3d rotatedAboutAxis(const Eigen::Vector3d& axis, double c, double s, const Eigen::Vector3d& v) {
  return c * v + s * axis.cross(v) + ((1.0 - c) * axis.dot(v)) * axis;
}

// Each joint angle with its sine and cosine, for forwardKinematicsNear (caller-owned, one per path).
using JointAngleAnchors = std::array<SinCosAnchor, kMaxJoints>;
// forwardKinematics with each joint's sine and cosine by sinCosNear: with reuse_anchors, a joint within
// kSinCosNearAnchor of its anchor gets them by the angle-addition formula (along a dense path), equal to
// sinCos's to about 1e-19; without, sinCos's (the same bits as forwardKinematics) and the anchors move to q. Same
// checks as forwardKinematics; allocates nothing.
void forwardKinematicsNear(const Robot& robot, RobotWorkspace& ws, const JointVector& q, JointAngleAnchors& anchors,
                           bool reuse_anchors);

// Geometric Jacobian of the tool frame at the configuration of the last forwardKinematics call:
// rows 0-2 map qd to the tool point's linear velocity, rows 3-5 to the angular velocity, base frame.
void toolJacobian(const Robot& robot, const RobotWorkspace& ws, Jacobian& jacobian);

// Geometric Jacobian of a point fixed to the tool (given in the base frame) at the last forwardKinematics.
void pointJacobian(const Robot& robot, const RobotWorkspace& ws, const Eigen::Vector3d& point, Jacobian& jacobian);

// Pose error (position difference, then rotation vector) taking `from` to `to`, base frame.
Vector6 poseError(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to);

}  // namespace jointcomp
