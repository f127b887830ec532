// Offline compensation: the joint references Q_ref that bring the links to the planned Q_theo,
// Q_ref = Q_theo - dQ(Q_theo, Q_ref) (Olabi et al. 2012 with dQ = dQ_stiff + dQ_gear and any other effect).
// Errors that depend on where the links are (compliance, from the load at Q_theo) are evaluated once;
// errors that depend on the command (transmission error, through the motor angles) are iterated to the
// fixed point by Newton steps on each joint (their slope with respect to the motor angle is known in closed
// form), stopping when the fixed-point map moves the reference by no more than the tolerance.
#pragma once

#include <array>
#include <vector>

#include "model/effects/joint_error_model.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {

// Throws UnreachableError naming the joint, its value and its limits when `reference` leaves them.
void requireWithinLimits(const Robot& robot, const JointVector& reference);

class Compensator {
public:
  Compensator(const JointErrorModel& model, EffectMask mask, FixedPointOptions options = {});

  // Q_ref for the planned link positions ctx.q (ctx.velocity, time, wrench and payload as planned).
  // Fills ctx.command and ctx.motor with the result; depends on nothing else (not on earlier calls).
  // Allocates nothing. Throws UnreachableError when the
  // converged reference leaves a joint's limits (a result that cannot be commanded is no result).
  FixedPointReport compensate(JointContext& ctx, JointVector& reference);
  // The same, starting from Q_theo - correction_guess (a guess of Q_theo - Q_ref) instead of from Q_theo less
  // the command-independent errors (on the joints that iterate; the others need no guess). Along a dense path
  // the previous point's correction is within a fraction of a microradian of this one's, and one Newton step
  // then meets the tolerance. The stopping test is the same, so the result is compensate()'s up to rounding:
  // the effects' continuations (Effect::continuationSize) and the joint angles' sines in the forward
  // kinematics continue from those of the previous call where it was near, so the result depends on earlier
  // calls at the rounding level (1e-19 rad), not beyond.
  FixedPointReport compensateFrom(JointContext& ctx, const JointVector& correction_guess, JointVector& reference);

  const JointErrorModel& model() const { return model_; }
  EffectMask mask() const { return mask_; }

private:
  // Evaluates the command-dependent effects at ctx.motor into dq_ and slope_ (and second_, third_ with
  // higher_order); false when one does not know its slope.
  bool evaluateCommandEffects(const JointContext& ctx, bool reuse_anchors, bool higher_order);
  // Load torque at ctx.q and the command-independent errors into fixed_dq_; along_path: the forward
  // kinematics' sines from the joint angles' anchors (set by the previous call along the path, or here).
  void prepare(JointContext& ctx, bool along_path);
  // From the start in ctx.command to the fixed point; continue_anchors: the harmonics' anchors of the
  // previous call are a valid start; cold_start: the start is Q_theo less the command-independent errors (not a
  // guess), a whole command-dependent error from the fixed point.
  FixedPointReport iterate(JointContext& ctx, JointVector& reference, bool continue_anchors, bool cold_start);
  // The steps of iterate (inline: defined and called in compensator.cpp only, on the hot path). Every joint's reference
  // Q_theo less its command-independent errors; returns 0 when they are all finite (not a number otherwise).
  inline double startAtFixedErrors(const JointContext& ctx, JointVector& reference) const;
  // ctx.motor of the active joints from ctx.command.
  inline void activeMotorAngles(JointContext& ctx) const;
  // The plain map Q_theo - dQ(command) of the active joints into reference; returns how far it moves the
  // command (the largest change), with finite false and that change when one is not finite.
  inline double plainStep(const JointContext& ctx, JointVector& reference, bool& finite) const;
  // The active joints' commands moved toward reference: by a Newton step on each joint (where the slope is known
  // and small enough, else the plain step), or by the higher-order step from dQ's second and third derivatives.
  inline void newtonStep(JointContext& ctx, const JointVector& reference, bool slopes_known) const;
  inline void higherOrderStep(JointContext& ctx, const JointVector& reference) const;
  // motor = G * command.
  void motorAngles(const JointVector& command, JointVector& motor) const;

  const JointErrorModel& model_;
  EffectMask mask_;
  FixedPointOptions options_;
  bool iterate_;
  JointErrorWorkspace ws_;
  // The selected error effects, split once: those that do not read the command are summed once per point.
  std::vector<int> fixed_effects_, command_effects_;
  // Each command-dependent effect's continuation (Effect::continuationSize anchors) in anchors_.
  std::vector<std::size_t> first_anchor_;
  std::vector<SinCosAnchor> anchors_;
  // Every command-dependent effect gives its second and third motor derivatives (the higher-order step).
  bool derivatives_known_ = true;
  bool anchors_set_ = false;  // by an earlier call (each harmonic's sine and cosine at some phase, from sinCos)
  // No selected load reads the forward kinematics: with no payload or wrench in the context, the load
  // torque comes from the joints' sines and cosines alone (gravity in joint frames).
  bool loads_read_kinematics_ = true;
  JointAngleAnchors joint_anchors_;  // the joint angles' sines and cosines, by compensateFrom
  bool joint_anchors_set_ = false;
  JointVector fixed_dq_, dq_, slope_, second_, third_;  // slope_, second_, third_: dQ's derivatives by the motor angle
  // G's nonzero entries row by row, and its diagonal, in place: the iteration reads them without a pointer chase.
  int gear_entry_count_ = 0;
  std::array<int, kMaxJoints + 1> gear_row_start_{};
  std::array<int, kMaxJoints * kMaxJoints> gear_columns_{};
  std::array<double, kMaxJoints * kMaxJoints> gear_values_{};
  std::array<double, kMaxJoints> gear_diagonal_{};
  // The rows with an entry off the diagonal (a coupled wrist): the others are their diagonal term alone.
  int coupled_row_count_ = 0;
  std::array<int, kMaxJoints> coupled_rows_{};
  // The joints whose error depends on the command (Effect::markCommandJoints): only they iterate. Each other joint's
  // reference is Q_theo less its command-independent errors from the first evaluation on, where the plain map leaves it
  // (its change is exactly zero).
  int active_count_ = 0;
  std::array<int, kMaxJoints> active_joints_{};
};

struct TrajectoryCompensationReport {
  int max_iterations = 0;
  double max_residual = 0.0;
  double max_correction = 0.0;  // rad, largest |Q_theo - Q_ref|
};

// Compensates every point of a joint trajectory (rows of q with their velocities), each on its own
// (Compensator::compensate), so that the trajectory's references are its points', bit for bit; throws
// SolverError naming the point when the iteration does not converge.
TrajectoryCompensationReport compensateTrajectory(const JointErrorModel& model, EffectMask mask,
                                                  const std::vector<JointVector>& planned,
                                                  const std::vector<JointVector>& velocities,
                                                  std::vector<JointVector>& references,
                                                  const FixedPointOptions& options = {});

}  // namespace jointcomp
