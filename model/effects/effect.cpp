#include "model/effects/effect.hpp"

#include "model/common/json_fields.hpp"

namespace jointcomp {

JointContext::JointContext(int dof)
    : q(JointVector::Zero(dof)),
      command(JointVector::Zero(dof)),
      motor(JointVector::Zero(dof)),
      velocity(JointVector::Zero(dof)),
      load_torque(JointVector::Zero(dof)) {}

void Effect::addLoadTorque(const Robot&, const RobotWorkspace&, JointContext&) const {}

bool Effect::addLoadTorqueRate(const Robot&, const RobotWorkspace&, const JointContext&, const JointVector&,
                               JointVector&) const {
  return false;
}

void Effect::addJointError(const Robot&, const JointContext&, JointVector&) const {}

bool Effect::addMotorSlope(const Robot&, const JointContext&, JointVector&) const { return false; }

double Effect::calibrationValue(int) const { return 0.0; }

int readJoint(JsonFields& entry, const Robot& robot) {
  const std::string name = entry.text("joint");
  for (int j = 0; j < robot.dof(); ++j) {
    if (robot.joints[j].name == name) return j;
  }
  entry.fail("joint", "robot '" + robot.name + "' has no joint named '" + name + "'");
}

}  // namespace jointcomp
