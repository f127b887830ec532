#include "model/effects/joint_error_model.hpp"

#include <cmath>
#include <limits>

#include "model/common/errors.hpp"
#include "model/common/sin_cos.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {

JointErrorModel::JointErrorModel(std::shared_ptr<const Robot> robot, GearTrain gears,
                                 std::vector<std::unique_ptr<Effect>> effects)
    : robot_(std::move(robot)), gears_(std::move(gears)) {
  if (!robot_) throw InvalidArgument("joint-error model needs a robot");
  if (gears_.dof() != robot_->dof()) throw InvalidArgument("gear train and robot differ in joint count");
  for (auto& effect : effects) addEffect(std::move(effect));
}

JointErrorModel::JointErrorModel(const JointErrorModel& other)
    : notes(other.notes), robot_(other.robot_), gears_(other.gears_) {
  for (const auto& effect : other.effects_) effects_.push_back(effect->clone());
}

JointErrorModel& JointErrorModel::operator=(const JointErrorModel& other) {
  if (this != &other) *this = JointErrorModel(other);
  return *this;
}

void JointErrorModel::addEffect(std::unique_ptr<Effect> effect) {
  if (!effect) throw InvalidArgument("joint-error model: null effect");
  if (effectCount() >= kMaxEffects) throw InvalidArgument("joint-error model: more than 64 effects");
  effects_.push_back(std::move(effect));
}

int JointErrorModel::jointSprings() const {
  for (int i = 0; i < effectCount(); ++i) {
    if (effects_[static_cast<std::size_t>(i)]->isJointSpring()) return i;
  }
  return -1;
}

JointVector JointErrorModel::jointStiffness() const {
  const int dof = robot_->dof();
  JointVector stiffness = JointVector::Constant(dof, std::numeric_limits<double>::infinity());
  const int springs = jointSprings();
  for (int j = 0; j < dof && springs >= 0; ++j) stiffness[j] = effect(springs).jointStiffness(j);
  return stiffness;
}

int JointErrorModel::findEffect(const std::string& type) const {
  for (int i = 0; i < effectCount(); ++i) {
    if (effects_[i]->type() == type) return i;
  }
  return -1;
}

EffectMask JointErrorModel::allEffects() const {
  return effectCount() == kMaxEffects ? ~EffectMask(0) : (EffectMask(1) << effectCount()) - 1;
}

EffectMask JointErrorModel::loadsAnd(std::initializer_list<const char*> error_types) const {
  EffectMask mask = 0;
  for (int i = 0; i < effectCount(); ++i) {
    bool selected = effects_[i]->role() == EffectRole::Load;
    for (const char* type : error_types) selected = selected || effects_[i]->type() == type;
    if (selected) mask |= EffectMask(1) << i;
  }
  return mask;
}

JointErrorWorkspace::JointErrorWorkspace(const Robot& robot_model)
    : robot(robot_model), jacobian(6, robot_model.dof()), scratch(JointVector::Zero(robot_model.dof())) {}

void computeLoadTorque(const JointErrorModel& model, EffectMask mask, JointErrorWorkspace& ws, JointContext& ctx) {
  forwardKinematics(model.robot(), ws.robot, ctx.q);
  loadTorqueAtCurrentPose(model, mask, ws, ctx);
}

void loadTorqueAtCurrentPose(const JointErrorModel& model, EffectMask mask, JointErrorWorkspace& ws,
                             JointContext& ctx) {
  gravityTorquesAtCurrentPose(model.robot(), ws.robot, ctx.load_torque);
  addNonGravityLoadsAtCurrentPose(model, mask, ws, ctx);
  if (ctx.inertial_torque.size() == ctx.load_torque.size()) ctx.load_torque += ctx.inertial_torque;
}

namespace {
void requireNoToolLoads(const JointContext& ctx, const char* function) {
  if (ctx.payload_mass != 0.0 || !ctx.tool_wrench.isZero(0.0)) {
    throw InvalidArgument(std::string(function) +
                          ": a payload or a tool wrench needs the tool's pose (computeLoadTorque)");
  }
}

// The selected load effects' rates along qd added to `rate`; false at the first that does not know its own.
bool addLoadEffectRates(const JointErrorModel& model, EffectMask mask, const JointErrorWorkspace& ws,
                        const JointContext& ctx, const JointVector& qd, JointVector& rate) {
  for (int i = 0; i < model.effectCount(); ++i) {
    const Effect& effect = model.effect(i);
    if (((mask >> i) & 1U) && effect.role() == EffectRole::Load &&
        !effect.addLoadTorqueRate(model.robot(), ws.robot, ctx, qd, rate)) {
      return false;
    }
  }
  return true;
}
}  // namespace

void loadTorqueInJointFrames(const JointErrorModel& model, EffectMask mask, JointErrorWorkspace& ws, JointContext& ctx,
                             const double* cosines, const double* sines) {
  requireNoToolLoads(ctx, "loadTorqueInJointFrames");
  gravityTorquesInJointFrames(model.robot(), cosines, sines, ctx.load_torque);
  addNonGravityLoadsAtCurrentPose(model, mask, ws, ctx);  // the load effects alone: none reads ws.robot
  if (ctx.inertial_torque.size() == ctx.load_torque.size()) ctx.load_torque += ctx.inertial_torque;
}

bool loadTorqueAndRateInJointFrames(const JointErrorModel& model, EffectMask mask, JointErrorWorkspace& ws,
                                    JointContext& ctx, const double* cosines, const double* sines,
                                    const JointVector& qd, JointVector& rate) {
  requireNoToolLoads(ctx, "loadTorqueAndRateInJointFrames");
  gravityTorquesAndRateInJointFrames(model.robot(), cosines, sines, qd, ctx.load_torque, rate);
  addNonGravityLoadsAtCurrentPose(model, mask, ws, ctx);
  if (ctx.inertial_torque.size() == ctx.load_torque.size()) ctx.load_torque += ctx.inertial_torque;
  return addLoadEffectRates(model, mask, ws, ctx, qd, rate);
}

bool loadsReadKinematics(const JointErrorModel& model, EffectMask mask) {
  for (int i = 0; i < model.effectCount(); ++i) {
    if (((mask >> i) & 1U) && model.effect(i).loadTorqueReadsKinematics()) return true;
  }
  return false;
}

void addNonGravityLoadsAtCurrentPose(const JointErrorModel& model, EffectMask mask, JointErrorWorkspace& ws,
                                     JointContext& ctx) {
  const Robot& robot = model.robot();
  if (ctx.payload_mass != 0.0) {
    const Eigen::Vector3d point = ws.robot.tool_pose * ctx.payload_com;
    pointJacobian(robot, ws.robot, point, ws.jacobian);
    ctx.load_torque.noalias() -= ws.jacobian.topRows<3>().transpose() * (ctx.payload_mass * robot.gravity);
  }
  if (!ctx.tool_wrench.isZero(0.0)) {
    wrenchTorquesAtCurrentPose(robot, ws.robot, ctx.tool_wrench, ws.scratch);
    ctx.load_torque -= ws.scratch;
  }
  for (int i = 0; i < model.effectCount(); ++i) {
    if ((mask >> i) & 1U) model.effect(i).addLoadTorque(robot, ws.robot, ctx);
  }
}

bool loadTorqueRateAtCurrentPose(const JointErrorModel& model, EffectMask mask, const JointErrorWorkspace& ws,
                                 const JointContext& ctx, const JointVector& qd, JointVector& rate) {
  const Robot& robot = model.robot();
  rate.setZero(robot.dof());
  addGravityTorqueRateAtCurrentPose(robot, ws.robot, qd, rate);
  if (ctx.payload_mass != 0.0) {
    addPointForceTorqueRateAtCurrentPose(robot, ws.robot, ws.robot.tool_pose * ctx.payload_com,
                                         -ctx.payload_mass * robot.gravity, qd, rate);
  }
  if (!ctx.tool_wrench.isZero(0.0)) {
    // load_torque -= J^T w: the rate with the opposite wrench.
    addWrenchTorqueRateAtCurrentPose(robot, ws.robot, -ctx.tool_wrench, qd, rate);
  }
  return addLoadEffectRates(model, mask, ws, ctx, qd, rate);
}

void addSelectedJointErrors(const JointErrorModel& model, EffectMask mask, const JointContext& ctx, JointVector& dq) {
  for (int i = 0; i < model.effectCount(); ++i) {
    if (((mask >> i) & 1U) && model.effect(i).role() == EffectRole::JointError) {
      model.effect(i).addJointError(model.robot(), ctx, dq);
    }
  }
}

void updateMotorAngles(const JointErrorModel& model, JointContext& ctx) {
  model.gears().motorAngles(ctx.command, ctx.motor);
}

FixedPointReport settleStatically(const JointErrorModel& model, EffectMask mask, JointErrorWorkspace& ws,
                                  JointContext& ctx, const FixedPointOptions& options, SettleStart start,
                                  SettleLoads loads) {
  const int dof = model.robot().dof();
  checkJointVector(model.robot(), ctx.command, "command");
  if (start == SettleStart::Given) checkJointVector(model.robot(), ctx.q, "q (the settling's start)");
  updateMotorAngles(model, ctx);
  if (start == SettleStart::Command) ctx.q = ctx.command;
  const bool joint_frames =
      loads == SettleLoads::JointFrames && loadsWithoutKinematics(loadsReadKinematics(model, mask), ctx);
  double cosines[kMaxJoints], sines[kMaxJoints];
  FixedPointReport report;
  JointVector dq;
  for (report.iterations = 1; report.iterations <= options.max_iterations; ++report.iterations) {
    if (joint_frames) {
      sinCosBatch(ctx.q.data(), dof, sines, cosines);
      loadTorqueInJointFrames(model, mask, ws, ctx, cosines, sines);
    } else {
      computeLoadTorque(model, mask, ws, ctx);
    }
    dq.setZero(dof);
    addSelectedJointErrors(model, mask, ctx, dq);
    const JointVector next = ctx.command + dq;
    report.residual = (next - ctx.q).cwiseAbs().maxCoeff();
    ctx.q = next;
    if (!std::isfinite(report.residual)) break;
    if (report.residual <= options.tolerance) {
      report.converged = true;
      return report;
    }
  }
  report.iterations = std::min(report.iterations, options.max_iterations);
  return report;
}

}  // namespace jointcomp
