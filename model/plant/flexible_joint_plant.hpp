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

#include "model/plant/flexible_joint_dynamics.hpp"
#include "model/plant/plant_data.hpp"
#include "model/plant/plant_integrator.hpp"
#include "model/plant/plant_model.hpp"

namespace jointcomp {

class FlexibleJointPlant {
public:
  // `truth` is the plant's own joint-error model (the robot as it really is); it must hold a compliance
  // effect (the joint springs). Throws InvalidArgument naming what is missing or wrong.
  FlexibleJointPlant(const JointErrorModel& truth, std::vector<DriveParameters> drives, PlantOptions options = {});
  ~FlexibleJointPlant();
  FlexibleJointPlant(const FlexibleJointPlant&) = delete;
  FlexibleJointPlant& operator=(const FlexibleJointPlant&) = delete;

  int dof() const { return model_.n; }
  int stateSize() const { return model_.stateSize(); }
  double time() const { return time_; }

  // Starts at rest in static equilibrium with the motors at `command` (and the reference there).
  void reset(const JointVector& command, double start_time = 0.0);
  // The controller follows `position` from now on, extrapolated with `velocity` (and the acceleration between
  // the last two updates) until the next update. A joint given a velocity of exactly 0 stops: its reference
  // holds `position` (no acceleration is extrapolated) however long the next update takes.
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
  bool hasAnalyticJacobian() const { return model_.analytic_slope; }
  // d(dy/dt)/dy at (t, y) into `jacobian`, stateSize() x stateSize() column-major; exposed for tests. Throws
  // InvalidArgument without hasAnalyticJacobian().
  void jacobian(double t, const double* y, double* jacobian);
  // Solves (I - gamma jacobian(t, y)) x = b as CVODE's Newton iterations do with structured_linear_solver;
  // exposed for tests. Throws SolverError when the system is singular.
  void solveNewtonSystem(double t, const double* y, double gamma, const double* b, double* x);

  const JointErrorModel& model() const { return model_.truth; }
  const PlantOptions& options() const { return model_.options; }
  // The plant's constant model and its workspace (plant_model.hpp, plant_data.hpp), for the free functions
  // of flexible_joint_dynamics.hpp.
  const PlantModel& plantModel() const { return model_; }
  PlantData& plantData() { return data_; }

private:
  void checkWatchdog();
  // The reference of an update (setReference) without the check against CVODE's time.
  void updateReference(const JointVector& position, const JointVector& velocity);
  // The state at time_: CVODE's own when it stopped there, the interpolated one when it is ahead.
  const double* now() const;

  PlantModel model_;
  PlantData data_;
  std::unique_ptr<PlantIntegrator> integrator_;
  double time_ = 0.0;
  bool restart_ = true;         // the integrator restarts (fresh history) before the next step
  bool ahead_ = false;          // CVODE has stepped past time_ (step_past_updates_s): the state now is interpolated
  std::string tripped_;         // why the watchdog stopped the run; empty while it runs
  PlantStatistics statistics_;  // the counts the plant keeps itself (updates stepped past, restarted)
};

}  // namespace jointcomp
