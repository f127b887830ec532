#include "model/robot/robot.hpp"

#include <cmath>

#include "model/common/errors.hpp"

namespace jointcomp {

JointVector Robot::lowerLimits() const {
  JointVector limits(dof());
  for (int i = 0; i < dof(); ++i) limits[i] = joints[i].lower;
  return limits;
}

JointVector Robot::upperLimits() const {
  JointVector limits(dof());
  for (int i = 0; i < dof(); ++i) limits[i] = joints[i].upper;
  return limits;
}

int Robot::jointIndex(const std::string& joint_name) const {
  for (int i = 0; i < dof(); ++i) {
    if (joints[i].name == joint_name) return i;
  }
  throw InvalidArgument("robot '" + name + "' has no moving joint named '" + joint_name + "'");
}

void throwBadJointVector(const Robot& robot, const JointVector& q, const char* what) {
  if (q.size() != robot.dof()) {
    throw InvalidArgument(std::string(what) + " has " + std::to_string(q.size()) + " values, robot '" + robot.name +
                          "' has " + std::to_string(robot.dof()) + " joints");
  }
  for (int i = 0; i < q.size(); ++i) {
    if (!std::isfinite(q[i])) {
      throw InvalidArgument(std::string(what) + "[" + std::to_string(i) + "] (joint '" + robot.joints[i].name +
                            "') is not finite");
    }
  }
  throw InvalidArgument(std::string(what) + ": throwBadJointVector called on a good vector (a caller's bug)");
}

}  // namespace jointcomp
