#include "model/robot/kinematics.hpp"

#include <cmath>

#include "model/common/errors.hpp"
#include "model/common/sin_cos.hpp"

namespace jointcomp {
namespace {

// parent * Rot(axis, angle) about any axis (Rodrigues), from the angle's cosine c and sine s.
void rotateAboutGeneralAxis(Eigen::Matrix3d& rotation, const Eigen::Vector3d& axis, double c, double s) {
  Eigen::Matrix3d cross;
  cross << 0.0, -axis.z(), axis.y(), axis.z(), 0.0, -axis.x(), -axis.y(), axis.x(), 0.0;
  const Eigen::Matrix3d joint_rotation = Eigen::Matrix3d::Identity() + s * cross + (1.0 - c) * (cross * cross);
  rotation = rotation * joint_rotation;
}

// parent * Rot(axis, angle) from the angle's cosine c and sine s, with a fast path for the usual z axis:
// only two columns change (inline: a call costs as much as that path).
inline void rotateAboutAxis(Eigen::Matrix3d& rotation, const Eigen::Vector3d& axis, double c, double s) {
  if (isZAxis(axis)) {
    const Eigen::Vector3d x = rotation.col(0);
    const Eigen::Vector3d y = rotation.col(1);
    rotation.col(0) = c * x + s * y;
    rotation.col(1) = c * y - s * x;
    return;
  }
  rotateAboutGeneralAxis(rotation, axis, c, s);
}

// The chain's poses, with joint i's cosine and sine from sin_cos(i, c, s).
template <typename SinCos>
void forwardKinematicsWith(const Robot& robot, RobotWorkspace& ws, SinCos sin_cos) {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  for (int i = 0; i < robot.dof(); ++i) {
    const Joint& joint = robot.joints[i];
    position += rotation * joint.placement.translation();
    rotation = rotation * joint.placement.linear();
    // The axis is fixed by the joint's own rotation. The usual z axis is the rotation's last column: the
    // product's other terms are exact zeros, so this equals it (a zero's sign aside), for 15 fewer operations.
    if (isZAxis(joint.axis)) {
      ws.axis[i] = rotation.col(2);
    } else {
      ws.axis[i] = rotation * joint.axis;
    }
    double c, s;
    sin_cos(i, c, s);
    rotateAboutAxis(rotation, joint.axis, c, s);
    ws.joint_pose[i].linear() = rotation;
    ws.joint_pose[i].translation() = position;
    ws.origin[i] = position;
    ws.com[i] = position + rotation * joint.body.com;
  }
  ws.tool_pose.linear() = rotation * robot.tool.linear();
  ws.tool_pose.translation() = position + rotation * robot.tool.translation();
}

}  // namespace

void forwardKinematics(const Robot& robot, RobotWorkspace& ws, const JointVector& q) {
  checkJointVector(robot, q, "q");
  // All the joints' sines and cosines at once (vectorised, a pure function of q: no libm call).
  double sines[kMaxJoints], cosines[kMaxJoints];
  sinCosBatch(q.data(), robot.dof(), sines, cosines);
  forwardKinematicsWith(robot, ws, [&sines, &cosines](int i, double& c, double& s) {
    c = cosines[i];
    s = sines[i];
  });
}

Eigen::Vector3d toolPosition(const Robot& robot, const JointVector& q) {
  checkJointVector(robot, q, "q");
  double sines[kMaxJoints], cosines[kMaxJoints];
  sinCosBatch(q.data(), robot.dof(), sines, cosines);
  // base p = P_1 R_1 P_2 R_2 ... P_n R_n tool p, from the right.
  Eigen::Vector3d p = robot.tool.translation();
  for (int i = robot.dof() - 1; i >= 0; --i) {
    const Joint& joint = robot.joints[static_cast<std::size_t>(i)];
    const double c = cosines[i], s = sines[i];
    if (isZAxis(joint.axis)) {
      const double x = p.x();
      p.x() = c * x - s * p.y();
      p.y() = s * x + c * p.y();
    } else {
      p = rotatedAboutAxis(joint.axis, c, s, p);
    }
    p = joint.placement.linear() * p + joint.placement.translation();
  }
  return p;
}

void forwardKinematicsNear(const Robot& robot, RobotWorkspace& ws, const JointVector& q, JointAngleAnchors& anchors,
                           bool reuse_anchors) {
  checkJointVector(robot, q, "q");
  forwardKinematicsWith(robot, ws, [&q, &anchors, reuse_anchors](int i, double& c, double& s) {
    sinCosNear(q[i], reuse_anchors, anchors[static_cast<std::size_t>(i)], s, c);
  });
}

void pointJacobian(const Robot& robot, const RobotWorkspace& ws, const Eigen::Vector3d& point, Jacobian& jacobian) {
  jacobian.resize(6, robot.dof());
  for (int i = 0; i < robot.dof(); ++i) {
    jacobian.col(i).head<3>() = ws.axis[i].cross(point - ws.origin[i]);
    jacobian.col(i).tail<3>() = ws.axis[i];
  }
}

void toolJacobian(const Robot& robot, const RobotWorkspace& ws, Jacobian& jacobian) {
  pointJacobian(robot, ws, ws.tool_pose.translation(), jacobian);
}

Vector6 poseError(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to) {
  Vector6 error;
  error.head<3>() = to.translation() - from.translation();
  const Eigen::AngleAxisd rotation(to.linear() * from.linear().transpose());
  error.tail<3>() = rotation.angle() * rotation.axis();
  return error;
}

}  // namespace jointcomp
