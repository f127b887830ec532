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

// rotation * vector (rotation column-major) with the arithmetic of Eigen's fixed-size 3 x 3 products under
// SSE2, so that results keep their bits: rows 0 and 1 (its packet path) sum (a0 b0 + a1 b1) + a2 b2, row 2
// (its unrolled sum) a0 b0 + (a1 b1 + a2 b2). Written out, the products skip Eigen's temporaries and
// shuffles: a quarter less time per forward kinematics, which the plant runs five times per communication
// step (checked against the Eigen expressions in tests/robot/test_forward_kinematics.cpp).
void rotate(const double* rotation, const double* vector, double* out) {
  out[0] = (rotation[0] * vector[0] + rotation[3] * vector[1]) + rotation[6] * vector[2];
  out[1] = (rotation[1] * vector[0] + rotation[4] * vector[1]) + rotation[7] * vector[2];
  out[2] = rotation[2] * vector[0] + (rotation[5] * vector[1] + rotation[8] * vector[2]);
}

}  // namespace

void forwardKinematics(const Robot& robot, RobotWorkspace& ws, const JointVector& q) {
  checkJointVector(robot, q, "q");
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  for (int i = 0; i < robot.dof(); ++i) {
    const Joint& joint = robot.joints[i];
    double step[3];
    rotate(rotation.data(), joint.placement.translation().data(), step);
    for (int k = 0; k < 3; ++k) position[k] += step[k];
    const Eigen::Matrix3d placement = joint.placement.linear();
    Eigen::Matrix3d placed;
    for (int c = 0; c < 3; ++c) rotate(rotation.data(), placement.data() + 3 * c, placed.data() + 3 * c);
    rotation = placed;
    rotate(rotation.data(), joint.axis.data(), ws.axis[i].data());  // the axis is fixed by the joint's own rotation
    rotateAboutAxis(rotation, joint.axis, q[i]);
    ws.joint_pose[i].linear() = rotation;
    ws.joint_pose[i].translation() = position;
    ws.origin[i] = position;
    double com[3];
    rotate(rotation.data(), joint.body.com.data(), com);
    for (int k = 0; k < 3; ++k) ws.com[i][k] = position[k] + com[k];
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
