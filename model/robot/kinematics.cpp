#include "model/robot/kinematics.hpp"

#include <cmath>

#include "model/common/errors.hpp"

namespace jointcomp {
namespace {

// parent * Rot(axis, angle), with a fast path for the usual z axis: only two columns change.
void rotateAboutAxis(Eigen::Matrix3d& rotation, const Eigen::Vector3d& axis, double angle) {
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  if (axis.x() == 0.0 && axis.y() == 0.0 && axis.z() == 1.0) {
    const Eigen::Vector3d x = rotation.col(0);
    const Eigen::Vector3d y = rotation.col(1);
    rotation.col(0) = c * x + s * y;
    rotation.col(1) = c * y - s * x;
    return;
  }
  Eigen::Matrix3d cross;
  cross << 0.0, -axis.z(), axis.y(), axis.z(), 0.0, -axis.x(), -axis.y(), axis.x(), 0.0;
  const Eigen::Matrix3d joint_rotation = Eigen::Matrix3d::Identity() + s * cross + (1.0 - c) * (cross * cross);
  rotation = rotation * joint_rotation;
}

}  // namespace

void forwardKinematics(const Robot& robot, RobotWorkspace& ws, const JointVector& q) {
  checkJointVector(robot, q, "q");
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  for (int i = 0; i < robot.dof(); ++i) {
    const Joint& joint = robot.joints[i];
    position += rotation * joint.placement.translation();
    rotation = rotation * joint.placement.linear();
    // The axis is fixed by the joint's own rotation. The usual z axis is the rotation's last column: the
    // product's other terms are exact zeros, so this equals it (a zero's sign aside), for 15 fewer operations.
    if (joint.axis.x() == 0.0 && joint.axis.y() == 0.0 && joint.axis.z() == 1.0) {
      ws.axis[i] = rotation.col(2);
    } else {
      ws.axis[i] = rotation * joint.axis;
    }
    rotateAboutAxis(rotation, joint.axis, q[i]);
    ws.joint_pose[i].linear() = rotation;
    ws.joint_pose[i].translation() = position;
    ws.origin[i] = position;
    ws.com[i] = position + rotation * joint.body.com;
  }
  ws.tool_pose.linear() = rotation * robot.tool.linear();
  ws.tool_pose.translation() = position + rotation * robot.tool.translation();
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
