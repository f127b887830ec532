#include "model/robot/workspace.hpp"

#include "model/common/errors.hpp"

namespace jointcomp {

RobotWorkspace::RobotWorkspace(const Robot& robot) : dof(robot.dof()) {
  if (dof < 1 || dof > kMaxJoints) {
    throw InvalidArgument("robot '" + robot.name + "' has " + std::to_string(dof) +
                          " moving joints; jointcomp handles 1 to " + std::to_string(kMaxJoints));
  }
  for (int i = 0; i < kMaxJoints; ++i) {
    joint_pose[i].setIdentity();
    axis[i].setZero();
    origin[i].setZero();
    com[i].setZero();
    inertia[i].setZero();
    omega[i].setZero();
    omega_dot[i].setZero();
    acc[i].setZero();
    force[i].setZero();
    moment[i].setZero();
  }
  mass_matrix.setZero(dof, dof);
  mass_factor.setZero(dof, dof);
  bias.setZero(dof);
}

}  // namespace jointcomp
