// The joint-error model of one robot: its gear train and the list of effects, with the two questions
// everything else asks of it: what torque does each joint carry at a pose, and what joint error follows.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include "model/effects/effect.hpp"
#include "model/effects/gear_train.hpp"

namespace jointcomp {

// Which effects of a model take part: bit i stands for effect i.
using EffectMask = std::uint64_t;
constexpr int kMaxEffects = 64;

class JointErrorModel {
public:
  JointErrorModel(std::shared_ptr<const Robot> robot, GearTrain gears, std::vector<std::unique_ptr<Effect>> effects);
  JointErrorModel(const JointErrorModel& other);
  JointErrorModel& operator=(const JointErrorModel& other);
  JointErrorModel(JointErrorModel&&) = default;
  JointErrorModel& operator=(JointErrorModel&&) = default;

  const Robot& robot() const { return *robot_; }
  std::shared_ptr<const Robot> sharedRobot() const { return robot_; }
  const GearTrain& gears() const { return gears_; }
  int effectCount() const { return static_cast<int>(effects_.size()); }
  const Effect& effect(int i) const { return *effects_[i]; }
  Effect& effect(int i) { return *effects_[i]; }
  void addEffect(std::unique_ptr<Effect> effect);
  // Index of the first effect of that type, -1 if none.
  int findEffect(const std::string& type) const;
  // Index of the effect that is the joints' linear springs (Effect::isJointSpring), -1 if none.
  int jointSprings() const;
  // Each joint's spring stiffness from that effect (N m/rad); +infinity (rigid) without one.
  JointVector jointStiffness() const;

  EffectMask allEffects() const;
  // Every load effect plus the joint-error effects of the given types (the paper's runs: {} for none,
  // {"compliance"} for stiffness, {"compliance", "transmission_error"} for both).
  EffectMask loadsAnd(std::initializer_list<const char*> error_types) const;

  // Free text kept from the parameter file.
  std::string notes;

private:
  std::shared_ptr<const Robot> robot_;
  GearTrain gears_;
  std::vector<std::unique_ptr<Effect>> effects_;
};

// Scratch for the model's calls; one per thread.
struct JointErrorWorkspace {
  explicit JointErrorWorkspace(const Robot& robot);
  RobotWorkspace robot;
  Jacobian jacobian;
  JointVector scratch;
};

// ctx.load_torque at ctx.q: gravity, payload, minus J^T of the tool wrench, plus the selected loads.
// Runs forward kinematics at ctx.q into ws.robot.
void computeLoadTorque(const JointErrorModel& model, EffectMask mask, JointErrorWorkspace& ws, JointContext& ctx);
// The same at the pose of the last forward kinematics in ws.robot (which must be of ctx.q).
void loadTorqueAtCurrentPose(const JointErrorModel& model, EffectMask mask, JointErrorWorkspace& ws, JointContext& ctx);
// The same from the joints' cosines and sines at ctx.q, without forward kinematics (gravity in joint
// frames, dynamics.hpp), for a caller that needs the load torque alone. Only where loadsReadKinematics is
// false for the mask and ctx has no payload and no tool wrench (which need the tool's pose; InvalidArgument).
void loadTorqueInJointFrames(const JointErrorModel& model, EffectMask mask, JointErrorWorkspace& ws, JointContext& ctx,
                             const double* cosines, const double* sines);
// The same with its rate along qd (loadTorqueRateAtCurrentPose's, into `rate`); false when a selected load
// effect does not know its rate (`rate` is then incomplete).
bool loadTorqueAndRateInJointFrames(const JointErrorModel& model, EffectMask mask, JointErrorWorkspace& ws,
                                    JointContext& ctx, const double* cosines, const double* sines,
                                    const JointVector& qd, JointVector& rate);
// True when a selected load effect reads the forward kinematics (Effect::loadTorqueReadsKinematics).
bool loadsReadKinematics(const JointErrorModel& model, EffectMask mask);
// True when ctx's load torque may come from the joints' sines alone (loadTorqueInJointFrames): no selected
// load effect reads the kinematics (`effects_read_kinematics`, loadsReadKinematics found once by the caller)
// and ctx has no payload and no tool wrench.
inline bool loadsWithoutKinematics(bool effects_read_kinematics, const JointContext& ctx) {
  return !effects_read_kinematics && ctx.payload_mass == 0.0 && ctx.tool_wrench.isZero(0.0);
}
// The rate of that load torque along the joint velocity qd, (d load_torque / dq) qd, into `rate` (ctx's
// inertial torque held), at the last forward kinematics in ws.robot (of ctx.q); false when a selected load
// effect does not know its rate (`rate` is then incomplete).
bool loadTorqueRateAtCurrentPose(const JointErrorModel& model, EffectMask mask, const JointErrorWorkspace& ws,
                                 const JointContext& ctx, const JointVector& qd, JointVector& rate);

// The same without gravity and without forward kinematics: adds payload, wrench and the selected load
// effects to ctx.load_torque, at the pose of the last forward kinematics in ws.robot.
void addNonGravityLoadsAtCurrentPose(const JointErrorModel& model, EffectMask mask, JointErrorWorkspace& ws,
                                     JointContext& ctx);

// Joint errors (link minus command) of the selected error effects, from ctx as it is (load_torque
// already computed, motor angles already set).
void addSelectedJointErrors(const JointErrorModel& model, EffectMask mask, const JointContext& ctx, JointVector& dq);

// ctx.motor = G * ctx.command.
void updateMotorAngles(const JointErrorModel& model, JointContext& ctx);

struct FixedPointReport {
  int iterations = 0;
  double residual = 0.0;  // rad, max |change| of the last iteration
  bool converged = false;
};

struct FixedPointOptions {
  double tolerance = 1e-12;  // rad
  int max_iterations = 50;
};

// Where settleStatically's iteration starts.
enum class SettleStart {
  Command,  // q = command
  Given,    // ctx.q as the caller set it: a guess near the solution (along a path, from the previous sample)
};

// How each iteration finds the load torque.
enum class SettleLoads {
  Kinematics,   // computeLoadTorque (forward kinematics at every iteration)
  JointFrames,  // loadTorqueInJointFrames from the joints' sines and cosines where loadsWithoutKinematics
                // allows it (gravity and kinematics-free load effects; no payload, no tool wrench), else
                // computeLoadTorque: the same torque to rounding, without the poses
};

// The quasi-static robot: where the links are when commanded ctx.command, solving
// q = command + dq(q, command) by fixed-point iteration from `start`. Result in ctx.q.
FixedPointReport settleStatically(const JointErrorModel& model, EffectMask mask, JointErrorWorkspace& ws,
                                  JointContext& ctx, const FixedPointOptions& options = {},
                                  SettleStart start = SettleStart::Command,
                                  SettleLoads loads = SettleLoads::Kinematics);

}  // namespace jointcomp
