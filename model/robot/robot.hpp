// The robot: an immutable serial chain of revolute joints, loaded from URDF (load_urdf.hpp).
// Everything is in SI units and expressed in joint frames; per-call scratch lives in RobotWorkspace.
#pragma once

#include <string>
#include <vector>

#include "model/common/types.hpp"

namespace jointcomp {

// Mass properties of the body a joint moves (its child link with every link fixed to it merged in).
struct BodyInertia {
  double mass = 0.0;                                  // kg
  Eigen::Vector3d com = Eigen::Vector3d::Zero();      // m, in the joint frame
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  // kg m^2, about the com, joint-frame axes
};

struct Joint {
  std::string name;
  std::string child_link;
  // Pose of this joint's frame at q = 0 in the previous joint's frame (or in the root link's frame for
  // the first joint), with every fixed joint on the way folded in.
  Eigen::Isometry3d placement = Eigen::Isometry3d::Identity();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit vector, joint frame
  double lower = 0.0;                               // rad; -inf for continuous joints
  double upper = 0.0;                               // rad; +inf for continuous joints
  double velocity_limit = 0.0;                      // rad/s, 0 when the URDF gives none
  double effort_limit = 0.0;                        // N m, 0 when the URDF gives none
  BodyInertia body;
};

struct Robot {
  std::string name;    // the URDF's robot name
  std::string source;  // where it was loaded from, for messages
  std::string root_link;
  std::string tip_link;  // the tool frame's link
  std::vector<Joint> joints;
  // Tool frame in the last joint's frame (fixed joints after the last revolute joint).
  Eigen::Isometry3d tool = Eigen::Isometry3d::Identity();
  // Mass fixed to the root link is ignored: it never moves.
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};  // m/s^2, root frame
  // Empty when every moving body has mass; otherwise the first link without an inertial, for the
  // message of dynamics calls.
  std::string link_without_inertial;

  int dof() const { return static_cast<int>(joints.size()); }
  bool hasInertials() const { return link_without_inertial.empty(); }
  JointVector lowerLimits() const;
  JointVector upperLimits() const;
  // Index of the joint with this name; throws InvalidArgument naming it when there is none.
  int jointIndex(const std::string& joint_name) const;
};

// Throws InvalidArgument unless q has the robot's dof and only finite values. `what` names the argument.
// Inline, one branch for a good vector: the hot paths check every input (the messages are out of line).
[[noreturn]] void throwBadJointVector(const Robot& robot, const JointVector& q, const char* what);
inline void checkJointVector(const Robot& robot, const JointVector& q, const char* what) {
  if (q.size() == robot.dof()) {
    double zeros = 0.0;  // q_i * 0 is 0 for every finite q_i and not a number for the others
    for (Eigen::Index i = 0; i < q.size(); ++i) zeros += q[i] * 0.0;
    if (zeros == 0.0) return;
  }
  throwBadJointVector(robot, q, what);
}

}  // namespace jointcomp
