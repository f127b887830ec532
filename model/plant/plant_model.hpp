// The flexible-joint plant's model, as Pinocchio splits Model and Data: what a run never changes (the robot
// as it really is, its drives, the options and what follows from them), checked once when it is built.
// The plant's equations are in flexible_joint_plant.hpp; its workspace in plant_data.hpp.
#pragma once

#include <vector>

#include "model/effects/joint_error_model.hpp"
#include "model/robot/drive_parameters.hpp"

namespace jointcomp {

// Bounds that keep every integration's work finite (plant_model.cpp says why).
constexpr double kMaxLoopFrequency = 1e4;     // rad/s: sqrt(kp / J), kd / J; ki / J below its cube
constexpr double kStepBudgetFloor = 2000.0;   // CVODE steps per advance, whatever its length
constexpr double kStepBudgetPerSecond = 1e5;  // and per simulated second on top

struct PlantOptions {
  double relative_tolerance = 1e-6;
  double absolute_tolerance = 1e-8;          // rad on positions and on the integral state (0.02 um at 2 m);
  double velocity_tolerance_factor = 100.0;  // velocities get absolute_tolerance * this, in rad/s: an error
                                             // of 1e-6 rad/s moves a joint 4e-9 rad in a 4 ms period
  double max_step = 0.0;                     // s, 0: CVODE's default (unbounded)
  long max_steps_per_advance = 200000;
  // BDF order cap. The joint springs give lightly damped modes near the imaginary axis, where BDF of
  // order 4 and 5 is unstable at large steps (A(alpha)-stability 73 and 51 degrees); order 3 is not.
  int max_order = 3;
  // The watchdog, checked at the end of every advance: a drive whose motor is further than this from its
  // reference (the following-error window of industrial drives; a 0.5 rad step trips it, a runaway
  // does), or a link further than joint_limit_margin_rad beyond its URDF limits, stops the run with a
  // PlantLimitError.
  double tracking_envelope_rad = 0.2;
  double joint_limit_margin_rad = 0.02;
  // The plant's own Jacobian for CVODE's Newton iterations (when hasAnalyticJacobian()); false: CVODE's
  // difference quotients of the right-hand side (kept to compare against).
  bool analytic_jacobian = true;
  // With that Jacobian, solve CVODE's Newton systems by eliminating the link and motor positions and the
  // integrals (a 2n x 2n LU instead of 5n x 5n); false: SUNDIALS' dense LU (kept to compare against).
  bool structured_linear_solver = true;
  // In that Jacobian, the link dynamics' q and qd columns by tangent passes of inverse dynamics and the
  // loads' rates; false: forward differences of the link dynamics (2 n forward dynamics).
  bool analytic_link_derivatives = true;
  // How long CVODE keeps a Jacobian and a Newton matrix: a fresh Jacobian at least every jacobian_reuse_steps
  // steps (CVodeSetJacEvalFrequency, msbj), a new I - gamma J at least every newton_setup_steps steps
  // (CVodeSetLSetupFrequency, msbp) or once gamma moved by more than newton_setup_gamma_change relative
  // (CVodeSetDeltaGammaMaxLSetup). CVODE's own 51, 20, 0.3 refresh more often than the plant needs; these
  // were the fastest measured (docs/performance.md, "The plant's integrator settings").
  long jacobian_reuse_steps = 200;
  long newton_setup_steps = 40;
  double newton_setup_gamma_change = 0.6;
  // The reference across an update: true blends the old extrapolation into the new one over the interval
  // since the previous update (a quintic smoothstep), so that the controller's reference is C2 and its
  // feed-forward C1 at every update; false: the reference jumps to the new extrapolation at each update.
  // Off by default: the blend's shape costs CVODE more steps than the jumps, which fall on step boundaries
  // (docs/performance.md).
  bool smooth_reference = false;
  // End each advance in two equal steps when the rest of it is between one and two of CVODE's planned steps
  // (the plant steps CVODE one step per call and moves the stop time to the rest's middle), not in the planned
  // step and a sliver: CVODE cuts only a step that would pass its stop time, and after a sliver it restarts
  // from the sliver's size at order 1. false: one CVODE call per advance with its end as the only stop time.
  bool even_steps = true;
  // How far past the end of an advance CVODE may step, in s (0: it stops at every advance's end). An advance
  // shorter than CVODE's planned step (a 1 ms co-simulation) then does not stop CVODE: it takes its own steps
  // through several updates, the state at each update's end is interpolated from its last step, and an
  // update's new reference takes over from CVODE's next step on, so it lands up to one CVODE step late, the
  // old reference extrapolated until then. A longer advance, or one of half this time or more, still ends on
  // its time (even_steps applies).
  double step_past_updates_s = 0.0;
  // With step_past_updates_s: how far, in rad, an update's reference may depart from the old one that CVODE
  // has already integrated past the update (the old reference extrapolated), at the update, halfway to
  // CVODE's time and at it, for the update to take over from CVODE's next step. An update that departs
  // further restarts CVODE from the update's time, so that it takes effect there, as without the option:
  // smooth inputs keep the fast path, a jump or a turn of the inputs is not delayed. 5 urad is under 10 um at
  // the RX170's 1.8 m reach, below the repeatability of robots of its class (a few hundredths of a mm): a
  // departure the robot could not show.
  double step_past_tolerance_rad = 5e-6;
  bool control = true;         // false: no motor torque at all (free response)
  bool motors_locked = false;  // true: motor positions held where they are (static tests)
};

struct PlantStatistics {
  long steps = 0;
  long rhs_evaluations = 0;  // right-hand sides, those of the difference-quotient Jacobians included
  long jacobian_rhs_evaluations =
      0;  // of which CVODE's difference-quotient Jacobians used (0 with the plant's Jacobian)
  long jacobian_evaluations = 0;
  long nonlinear_iterations = 0;
  long linear_solver_setups = 0;  // LU factorisations of I - gamma J
  long error_test_failures = 0;
  long nonlinear_convergence_failures = 0;
  // step_past_updates_s: updates that came while CVODE was ahead of them, and of those the ones that departed
  // from the reference CVODE had integrated by more than step_past_tolerance_rad (CVODE restarted there).
  long updates_stepped_past = 0;
  long updates_restarted = 0;
};

// Everything needed to continue a simulation exactly: restoring it and advancing gives the same
// results, bit for bit, as advancing from the moment it was saved.
struct PlantState {
  double time = 0.0;
  std::vector<double> y;
  JointVector reference, reference_velocity, reference_acceleration, feedforward, feedforward_rate;
  double reference_time = 0.0;
  // The blend from the previous extrapolation (smooth_reference): its offset from the new one at the update
  // (value, rate, acceleration; feed-forward value and rate) and the blend's duration (0: none).
  JointVector blend_offset, blend_offset_velocity, blend_offset_acceleration, feedforward_offset,
      feedforward_offset_rate;
  double blend_duration = 0.0;
  Vector6 tool_wrench = Vector6::Zero();
  double payload_mass = 0.0;
  Eigen::Vector3d payload_com = Eigen::Vector3d::Zero();
};

// The plant's constant model. Throws InvalidArgument naming what is missing or wrong: a link without its
// inertial, a drive value out of range, gains no drive can have, an option out of range, a model without
// joint springs (Effect::isJointSpring) or with a rigid joint.
struct PlantModel {
  PlantModel(const JointErrorModel& truth, std::vector<DriveParameters> drives, PlantOptions options);

  int stateSize() const { return 5 * n; }

  JointErrorModel truth;
  std::vector<DriveParameters> drives;
  // Changed only by FlexibleJointPlant::setWatchdog (the watchdog's two limits), between advances.
  PlantOptions options;
  int n = 0;
  int springs = -1;  // the effect of truth that is the joint springs
  EffectMask load_mask = 0;
  EffectMask error_mask = 0;  // joint-error effects other than the springs: the transmission error
  // No load effect reads the forward kinematics: without a payload or a tool wrench the static feed-forward
  // and its rate come from the joints' sines alone (gravity in joint frames, dynamics.hpp).
  bool loads_read_kinematics = true;
  bool analytic_slope = true;  // every command-dependent effect of error_mask gives its motor slope
  JointVector stiffness;       // the springs' K
  JointVector damping;         // the transmissions' D
  JointVector windup_gain;     // per joint, 1 / (ki Tt): how fast a clamped excess pulls the integral back
};

}  // namespace jointcomp
