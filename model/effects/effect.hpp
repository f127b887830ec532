// One interface for every joint-error effect.
//
// An effect either adds to the torque each joint's transmission carries (a load: the spring balancer,
// a payload), or predicts a joint-angle error (link angle minus commanded angle) from the joint context
// (compliance from that torque, transmission error from the gear-stage angles). Effects expose named
// parameters so that identification can fit them, and are created by type name (registry.hpp).
#pragma once

#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "model/robot/sin_cos_near.hpp"
#include "model/robot/workspace.hpp"

namespace jointcomp {

// The largest joint error one entry of a parameter file may state (a table coefficient, a harmonic's
// amplitude): 0.1 rad (5.7 deg). A gear that loses more is broken, not calibrated; a file beyond it is refused
// naming the entry (a table of 1e300 rad once gave the paper 2.5 m errors and exit 0).
constexpr double kMaxStatedJointError = 0.1;  // rad
// A value of a parameter-file message, short ("1e+300").
inline std::string shortNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", value);
  return text;
}

// Everything an effect may depend on at one instant. The caller fills q, command, motor, velocity,
// time and temperature; JointErrorModel fills load_torque before asking for errors.
struct JointContext {
  JointVector q;         // link-side joint positions: where the robot actually is (rad)
  JointVector command;   // commanded joint positions as the controller sees them (rad)
  JointVector motor;     // motor angles (rad), motor = G * command through the gear train
  JointVector velocity;  // link-side joint velocities (rad/s): the direction of motion
  // The side of each joint's lost motion as its last move set it (LostMotionMemory, backlash.hpp): +1
  // approached from below, -1 from above, 0 not known (no move seen yet). Set for a robot at rest between
  // moves (measurement campaigns); empty for continuous motion, where the side follows `velocity`.
  JointVector approach;
  double time = 0.0;                                      // s
  double temperature = 20.0;                              // degC
  Vector6 tool_wrench = Vector6::Zero();                  // wrench applied by the environment at the tool, base frame
  double payload_mass = 0.0;                              // kg, carried at the tool
  Eigen::Vector3d payload_com = Eigen::Vector3d::Zero();  // m, tool frame
  // Torque each joint's transmission carries to hold the link (N m): gravity and payload and wrench,
  // plus what the load effects add. Positive like gravityTorques().
  JointVector load_torque;
  // Torque the motion's inertia asks of each transmission (M(q) qdd + C(q, qd) qd, N m), which
  // computeLoadTorque adds to load_torque when it has one value per joint: the dynamic compensation
  // (model/dynamic_compensation/dynamic_compensation.hpp) deflects the joints under it. Empty for quasi-static use.
  JointVector inertial_torque;

  explicit JointContext(int dof = 0);
};

// Parameters of one joint that the kinematic calibration (model/identify) fits itself.
enum class CalibrationParameter {
  Offset,           // the joint's zero (rad)
  Compliance,       // the joint's linear compliance under its load torque (rad/(N m))
  Placement,        // the six corrections of the joint's placement
  InstrumentScale,  // the instrument's relative scale error (of the fitted campaigns' set-up; no joint)
};

enum class EffectRole {
  Load,        // contributes to load_torque (acts in parallel with the transmission)
  JointError,  // predicts a joint-angle error
};

class JsonFields;

// The index of the joint a parameter file's entry names in "joint"; fails naming the entry when the robot
// has no such joint.
int readJoint(JsonFields& entry, const Robot& robot);

class Effect {
public:
  virtual ~Effect() = default;

  virtual std::string type() const = 0;  // the registry name
  virtual EffectRole role() const = 0;

  // Load effects: add this effect's contribution to ctx.load_torque (ws holds forward kinematics at ctx.q).
  virtual void addLoadTorque(const Robot& robot, const RobotWorkspace& ws, JointContext& ctx) const;
  // False when addLoadTorque reads only ctx (not ws): a caller that needs the load torque alone may then
  // skip the forward kinematics. Every load effect reads them unless it says otherwise.
  virtual bool loadTorqueReadsKinematics() const { return role() == EffectRole::Load; }
  // Load effects: add the rate of this effect's contribution along the joint velocity qd, (d tau/dq) qd, to
  // `rate` and return true; false when the effect does not know it (the plant's feed-forward then takes a
  // difference quotient). At ctx.q, with ws at it.
  virtual bool addLoadTorqueRate(const Robot& robot, const RobotWorkspace& ws, const JointContext& ctx,
                                 const JointVector& qd, JointVector& rate) const;
  // Joint-error effects: add the predicted link-minus-command error to dq.
  virtual void addJointError(const Robot& robot, const JointContext& ctx, JointVector& dq) const;
  // True when the error depends on ctx.command or ctx.motor (so compensation must iterate on it).
  virtual bool dependsOnCommand() const { return false; }
  // For such an effect: adds d(joint error)/d(motor angle) of each joint to `slope` (n values, the error
  // of joint j depends on motor j only) and returns true; false when the effect does not know its slope
  // (the plant then differentiates it numerically). The plant needs it at every right-hand side.
  virtual bool addMotorSlope(const Robot& robot, const JointContext& ctx, JointVector& slope) const;
  // addJointError and addMotorSlope in one pass, with the same bits as the two calls (the plant's right-hand
  // side asks for both at every evaluation); returns addMotorSlope's answer. The default makes the two calls.
  virtual bool addJointErrorAndMotorSlope(const Robot& robot, const JointContext& ctx, JointVector& dq,
                                          JointVector& slope) const;
  // The joints whose error depends on the command: sets joints[j] for each (dof values). The default marks
  // every joint; an effect of a few joints marks those, so that compensation iterates on them alone.
  virtual void markCommandJoints(int dof, bool* joints) const;

  // The continuation, for a caller that evaluates a command-dependent effect again and again at nearby
  // commands (the compensator's iterations, a dense path): the effect keeps continuationSize() sines with
  // their angles in caller-owned `anchors` between calls. With `reuse` false the anchors are set afresh;
  // with true an angle near its anchor continues from it (sinCosNear), so the result matches the plain
  // evaluation to rounding (a few 1e-20 rad). Returns addMotorSlope's answer. The default keeps no anchors
  // and calls addJointErrorAndMotorSlope.
  virtual std::size_t continuationSize() const { return 0; }
  virtual bool continueJointErrorAndMotorSlope(const Robot& robot, const JointContext& ctx, SinCosAnchor* anchors,
                                               bool reuse, JointVector& dq, JointVector& slope) const;
  // True when continueJointErrorAndMotorDerivatives gives the error's second and third derivatives by the
  // motor angle too (the compensator's higher-order first step needs them of every command-dependent effect).
  virtual bool knowsMotorDerivatives() const { return false; }
  // The continued evaluation with those derivatives added to `second` and `third`; only where
  // knowsMotorDerivatives() (the default throws InvalidArgument).
  virtual void continueJointErrorAndMotorDerivatives(const Robot& robot, const JointContext& ctx, SinCosAnchor* anchors,
                                                     bool reuse, JointVector& dq, JointVector& slope,
                                                     JointVector& second, JointVector& third) const;

  // The joints' linear springs, dq = -tau / K: the effect that is them says so and gives each joint's K
  // (N m/rad, +infinity for a rigid joint). The plant integrates them as its elastic joints; the simulated
  // campaigns and the reports read K from them. Found by JointErrorModel::jointSprings().
  virtual bool isJointSpring() const { return false; }
  virtual double jointStiffness(int joint) const;

  // Load effects that store energy (a spring): its potential energy at ctx.q (J), for the plant's energy
  // balance; 0 by default.
  virtual double loadPotentialEnergy(const Robot& robot, const JointContext& ctx) const;

  // An effect whose per-joint values are one of the calibration's own parameters says which, and gives
  // them in the calibration's units, so that calibration starts from them and writes them back.
  virtual std::optional<CalibrationParameter> calibrationParameter() const { return std::nullopt; }
  virtual double calibrationValue(int joint) const;

  // Named parameters for identification, SI units, names with the unit ("joint_2.stiffness_nm_per_rad").
  virtual std::vector<std::string> parameterNames() const = 0;
  virtual std::vector<double> parameters() const = 0;
  // Throws ParameterError naming the parameter for a value out of range.
  virtual void setParameters(const std::vector<double>& values) = 0;

  // The effect as it appears in the parameter file.
  virtual nlohmann::json toJson() const = 0;
  virtual std::unique_ptr<Effect> clone() const = 0;

  // Free-text note when the values are estimates rather than measurements ("" when measured).
  std::string estimate_note;
};

}  // namespace jointcomp
