// The flexible-joint plant: a simulated robot worth testing a compensation against.
//
// Per joint j, a motor (inertia B_j seen at the joint, viscous and smooth Coulomb friction) drives the
// link through the gear train and a joint spring: the transmission carries
//   tau_s = K (p + e(p) - q) + D ((I + de/dp) pd - qd),
// with p the motor position in joint units (what the controller sees: motor angles scaled by the gear
// ratios), e the transmission error of the gear-stage angles, q the link position and K the compliance
// effect's stiffness. The link side is the rigid-body dynamics of the robot under gravity, the spring
// balancer, the payload's weight and the tool wrench:  M(q) qdd = tau_s - h(q, qd) - tau_other_loads.
// Motor side: B pdd = tau_m - tau_s - friction(pd).
// Control: a continuous-time PID on the motor position with velocity, friction and static-load feed-forward,
// following a reference extrapolated between updates with its velocity and the acceleration seen
// between the last two updates, torques clamped to the URDF effort limits, with back-calculation
// anti-windup (while the torque is clamped, the integral is pulled back at the rate of the clamped
// excess over the tracking time sqrt(Ti Td), Astrom and Hagglund's rule). Continuous rather than sampled
// so that CVODE integrates a smooth system.
// State y = [q, qd, p, pd, integral of the position error], 5 n values.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Cholesky>

#include "model/effects/joint_error_model.hpp"
#include "model/plant/drive_parameters.hpp"

namespace jointcomp {

class TransmissionErrorEffect;

// Bounds that keep every integration's work finite (flexible_joint_plant.cpp says why).
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
  // difference quotients of the right-hand side, as before issue 17 (kept to compare against).
  bool analytic_jacobian = true;
  // With that Jacobian, solve CVODE's Newton systems by eliminating the link and motor positions and the
  // integrals (a 2n x 2n LU instead of 5n x 5n); false: SUNDIALS' dense LU (kept to compare against).
  bool structured_linear_solver = true;
  // In that Jacobian, the link dynamics' q and qd columns by tangent passes of inverse dynamics and the
  // loads' rates; false: forward differences of the link dynamics (2 n forward dynamics), as before.
  bool analytic_link_derivatives = true;
  // How long CVODE keeps a Jacobian and a Newton matrix: a fresh Jacobian at least every jacobian_reuse_steps
  // steps (CVodeSetJacEvalFrequency, msbj), a new I - gamma J at least every newton_setup_steps steps
  // (CVodeSetLSetupFrequency, msbp) or once gamma moved by more than newton_setup_gamma_change relative
  // (CVodeSetDeltaGammaMaxLSetup). CVODE's own 51, 20, 0.3 refresh more often than the plant needs: 200, 40,
  // 0.6 was the fastest of the 15 settings measured (plant_bench PlantSpiralSimulation: 71.2 -> 67.4 ms CPU,
  // 418 -> 131 Jacobians, 2494 -> 1183 setups; fmu_bench spiral at 1 ms 270x -> 276x, at 10 ms 617x -> 660x);
  // 20 or 1000 Jacobian steps were slower (75.2, 80.9 ms: more Newton iterations and steps).
  long jacobian_reuse_steps = 200;
  long newton_setup_steps = 40;
  double newton_setup_gamma_change = 0.6;
  // The reference across an update: true blends the old extrapolation into the new one over the interval
  // since the previous update (a quintic smoothstep), so that the controller's reference is C2 and its
  // feed-forward C1 at every update; false: the reference jumps to the new extrapolation at each update.
  // Off by default: on the paper's spiral (4 ms updates) the blend's high-order shape inside each interval
  // tripled CVODE's steps (24,072 -> 68,688), while the jumps, at the step boundaries CVodeSetStopTime
  // makes, cost none; and it moved Table II's Rz of run 2 by 0.15 um (model/plant/README.md).
  bool smooth_reference = false;
  // End each advance in two equal steps when the rest of it is between one and two of CVODE's planned steps
  // (the plant steps CVODE one step per call and moves the stop time to the rest's middle), not in the planned
  // step and a sliver: CVODE cuts only a step that would pass its stop time, and after a sliver it restarts
  // from the sliver's size at order 1. fmu_bench at 10 ms updates: 4.94 -> 3.22 steps and 1.20 -> 0.25 Newton
  // matrices per update. false: one CVODE call per advance with its end as the only stop time, as before.
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
  // departure the robot could not show. (On the paper's spiral the largest is 0.1-0.3 urad at 1 ms updates,
  // about 1 urad at 10 ms.)
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

// The transmission's rates through E = diag(motor_slope) G (de/dp from the effects' motor slopes and the gear
// matrix) without forming E: output_rate = pd + E pd and reaction = torque + E^T torque, with the arithmetic
// of Eigen's matrix-vector products (the same bits as those matrix expressions, which tests compare).
void transmissionOutputRate(const JointVector& motor_slope, const JointMatrix& gears, const JointVector& pd,
                            JointVector& output_rate);
void transmissionReaction(const JointVector& motor_slope, const JointMatrix& gears, const JointVector& torque,
                          JointVector& reaction);

class FlexibleJointPlant {
public:
  // `truth` is the plant's own joint-error model (the robot as it really is); it must hold a compliance
  // effect (the joint springs). Throws InvalidArgument naming what is missing or wrong.
  FlexibleJointPlant(const JointErrorModel& truth, std::vector<DriveParameters> drives, PlantOptions options = {});
  ~FlexibleJointPlant();
  FlexibleJointPlant(const FlexibleJointPlant&) = delete;
  FlexibleJointPlant& operator=(const FlexibleJointPlant&) = delete;

  int dof() const { return n_; }
  int stateSize() const { return 5 * n_; }
  double time() const { return time_; }

  // Starts at rest in static equilibrium with the motors at `command` (and the reference there).
  void reset(const JointVector& command, double start_time = 0.0);
  // The controller follows `position` from now on, extrapolated with `velocity` until the next update.
  void setReference(const JointVector& position, const JointVector& velocity);
  // The reference the controller follows at t (>= the last update): position, velocity, acceleration.
  void referenceAt(double t, JointVector& position, JointVector& velocity, JointVector& acceleration) const;
  void setToolWrench(const Vector6& wrench);
  void setPayload(double mass, const Eigen::Vector3d& com_in_tool);
  // The watchdog's limits (PlantOptions), changeable at any time; throws InvalidArgument naming a value
  // that is not finite or out of range, and changes nothing then.
  void setWatchdog(double tracking_envelope_rad, double joint_limit_margin_rad);
  // Integrates to `end_time` (> time()). Throws SolverError with CVODE's reason when it fails; the
  // plant is then left at the last good time. Throws PlantLimitError when the run ends outside the joint
  // limits or the tracking envelope (PlantOptions); the plant is then at end_time and refuses to
  // advance until reset() or restoreState().
  void advance(double end_time);

  JointVector linkPositions() const;
  JointVector linkVelocities() const;
  JointVector motorPositions() const;
  JointVector motorVelocities() const;
  // Motor torques (joint units) the controller applies now.
  JointVector motorTorques();
  // Total mechanical energy (kinetic, gravity, spring balancer, payload, joint springs), for tests.
  double mechanicalEnergy();

  // The integrator's state y now (stateSize() values, laid out as above); unlike saveState() it leaves
  // the integrator's step-size history alone, so reading it does not change the run.
  const double* state() const;
  PlantState saveState();
  void restoreState(const PlantState& state);
  // CVODE's counts are asked for here, not after every advance (eight calls cost about 190 instructions,
  // 1 % of a 1 ms FMU step).
  PlantStatistics statistics() const;

  // The right-hand side dy/dt at (t, y), both of stateSize(); exposed for linearisation and tests.
  void derivative(double t, const double* y, double* ydot);
  // True when every command-dependent joint error gives its motor slope: the plant then gives CVODE
  // jacobian() below, otherwise CVODE builds its Jacobians from difference quotients of derivative().
  bool hasAnalyticJacobian() const { return analytic_slope_; }
  // d(dy/dt)/dy at (t, y) into `jacobian`, stateSize() x stateSize() column-major; exposed for tests. Throws
  // InvalidArgument without hasAnalyticJacobian().
  void jacobian(double t, const double* y, double* jacobian);
  // Solves (I - gamma jacobian(t, y)) x = b as CVODE's Newton iterations do with structured_linear_solver;
  // exposed for tests. Throws SolverError when the system is singular.
  void solveNewtonSystem(double t, const double* y, double gamma, const double* b, double* x);
  // CVODE's linear-system function with structured_linear_solver: evaluates the Jacobian into the solver's
  // copy unless CVODE may reuse the last one, and hands gamma over; 0, or 1 (recoverable) when the
  // Jacobian is not finite. Not for other callers.
  int prepareNewtonSystem(double t, const double* y, bool jacobian_ok, double gamma, int* jacobian_current);

  const JointErrorModel& model() const { return truth_; }
  const PlantOptions& options() const { return options_; }

private:
  struct Solver;
  // The controller's torques; `clamped_excess` (optional) receives, per joint, the clamped torque minus
  // the unclamped one (zero unless the drive saturates), which the anti-windup feeds back.
  void computeMotorTorques(double t, const JointVector& p, const JointVector& pd, const JointVector& integral,
                           JointVector& torque, JointVector* clamped_excess = nullptr) const;
  // Inline: setReference's departure check reads it at three times for every joint, and the watchdog for
  // every joint, at every update.
  double referenceAt(int joint, double t) const {
    const double dt = t - reference_time_;
    if (blend_duration_ > 0.0 && dt < blend_duration_) return referencePoint(joint, t).value;
    return reference_[joint] + reference_velocity_[joint] * dt + 0.5 * reference_acceleration_[joint] * dt * dt;
  }
  // The controller's reference of `joint` at t: value, rate and acceleration, and its static feed-forward
  // torque and that torque's rate (the rates feed the blend of the next update); feedforward_blend is the
  // blend's part of the feed-forward.
  struct ReferencePoint {
    double value, velocity, acceleration, feedforward, feedforward_rate, feedforward_blend;
  };
  ReferencePoint referencePoint(int joint, double t) const;
  void checkWatchdog();
  int integrateEvenly(double end_time, long budget, double& reached);
  int integratePast(double end_time, double cvode_time, long budget, double& reached);
  void ensureFeedforward();
  // The state at time_: CVODE's own when it stopped there, the interpolated one when it is ahead.
  const double* now() const;
  void transmissionError(const JointVector& p, const JointVector& q, JointVector& error);
  void transmissionTorques(const JointVector& p, const JointVector& pd, const JointVector& q, const JointVector& qd,
                           JointVector& link_torque, JointVector& motor_reaction);
  // transmissionError and, with analytic_slope_, addMotorSlopes at the motor angles of p, in one pass (the
  // transmission errors' phases once): the same bits as the two.
  void transmissionErrorAndMotorSlopes(const JointVector& p, const JointVector& q, JointVector& error,
                                       JointVector& motor_slope);
  // Sum of the command-dependent effects' motor slopes at the motor angles in ctx_.
  void addMotorSlopes(JointVector& slope) const;
  // Link accelerations for the transmitted torque `spring_torque`: loads, then forward dynamics at q.
  void linkAcceleration(const JointVector& q, const JointVector& qd, const JointVector& spring_torque,
                        JointVector& qdd);
  // d qdd/dq and d qdd/dqd at fixed transmitted torque into jacobian_scratch_.link_by_q, link_by_qd, after
  // linkAcceleration(q, qd, ...) gave qdd (its pose and loads still in ws_ and ctx_) and jacobian_scratch_.inverse_mass
  // holds M^-1: analytically (false when a load does not know its rate), or by forward differences.
  bool analyticLinkDerivatives(const JointVector& qd, const JointVector& qdd);
  void linkDerivativesByDifferences(const JointVector& q, const JointVector& qd, const JointVector& spring_torque,
                                    const JointVector& qdd);
  void staticFeedforward(const JointVector& position, JointVector& torque);

  JointErrorModel truth_;
  std::vector<DriveParameters> drives_;
  PlantOptions options_;
  int n_;
  int compliance_index_;
  EffectMask load_mask_;
  // No load effect reads the forward kinematics: without a payload or a tool wrench the static feed-forward
  // and its rate come from the joints' sines alone (gravity in joint frames, dynamics.hpp).
  bool loads_read_kinematics_ = true;
  EffectMask error_mask_;       // joint-error effects other than compliance: the transmission error
  bool analytic_slope_ = true;  // every command-dependent effect of error_mask_ gives its motor slope
  // Per effect of truth_: the effect as a transmission error, or null (one dynamic_cast, not one per rhs).
  std::vector<const TransmissionErrorEffect*> transmission_effects_;
  JointVector stiffness_;
  JointVector windup_gain_;  // per joint, 1 / (ki Tt): how fast a clamped excess pulls the integral back
  double time_ = 0.0;
  bool restart_ = true;  // the integrator restarts (fresh history) before the next step
  bool ahead_ = false;   // CVODE has stepped past time_ (step_past_updates_s): the state now is interpolated
  // The static feed-forward of the last update and its rate are computed when first needed (the right-hand
  // side, the Jacobian, motorTorques, saveState): with step_past_updates_s most updates are replaced by the
  // next one before CVODE takes a step. The same values as when computed at the update: what they read (the
  // reference and the loads) is set before, and a change of the loads first computes the pending ones.
  bool feedforward_pending_ = false;
  std::string tripped_;  // why the watchdog stopped the run; empty while it runs
  JointVector reference_, reference_velocity_, reference_acceleration_, feedforward_, feedforward_rate_;
  double reference_time_ = 0.0;
  JointVector blend_offset_, blend_offset_velocity_, blend_offset_acceleration_, feedforward_offset_,
      feedforward_offset_rate_;
  double blend_duration_ = 0.0;
  JointContext ctx_;
  JointErrorWorkspace ws_;
  PlantStatistics statistics_;  // the counts the plant keeps itself (updates stepped past, restarted)
  // The Jacobian's scratch, here so that jacobian() allocates nothing.
  struct JacobianScratch {
    JointMatrix inverse_mass, spring_by_motor, reaction_by_motor, reaction_by_motor_rate, link_by_q, link_by_qd,
        torque_by_q;
    JointVector curvature, ahead, behind, load_rate, shifted_qdd;
    Eigen::LLT<JointMatrix> mass_llt;
  } jacobian_scratch_;
  std::unique_ptr<Solver> solver_;
};

}  // namespace jointcomp
