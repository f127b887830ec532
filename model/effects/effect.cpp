#include "model/effects/effect.hpp"

#include <limits>

#include "model/common/errors.hpp"
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

bool Effect::addJointErrorAndMotorSlope(const Robot& robot, const JointContext& ctx, JointVector& dq,
                                        JointVector& slope) const {
  addJointError(robot, ctx, dq);
  return addMotorSlope(robot, ctx, slope);
}

void Effect::markCommandJoints(int dof, bool* joints) const {
  for (int j = 0; j < dof; ++j) joints[j] = true;
}

bool Effect::continueJointErrorAndMotorSlope(const Robot& robot, const JointContext& ctx, SinCosAnchor*, bool,
                                             JointVector& dq, JointVector& slope) const {
  return addJointErrorAndMotorSlope(robot, ctx, dq, slope);
}

void Effect::continueJointErrorAndMotorDerivatives(const Robot&, const JointContext&, SinCosAnchor*, bool, JointVector&,
                                                   JointVector&, JointVector&, JointVector&) const {
  throw InvalidArgument("effect " + type() + " does not give its error's second and third motor derivatives");
}

double Effect::jointStiffness(int) const { return std::numeric_limits<double>::quiet_NaN(); }

double Effect::loadPotentialEnergy(const Robot&, const JointContext&) const { return 0.0; }

double Effect::calibrationValue(int) const { return 0.0; }

int readJoint(JsonFields& entry, const Robot& robot) {
  const std::string name = entry.text("joint");
  for (int j = 0; j < robot.dof(); ++j) {
    if (robot.joints[j].name == name) return j;
  }
  entry.fail("joint", "robot '" + robot.name + "' has no joint named '" + name + "'");
}

}  // namespace jointcomp
