#include "model/dynamic_compensation/dynamic_compensation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "model/common/errors.hpp"
#include "model/compensation/compensator.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/workspace.hpp"

namespace jointcomp {
namespace {

// d/dt of sampled values: central differences inside, one-sided at both ends.
void differentiate(const std::vector<double>& time, const std::vector<JointVector>& values,
                   std::vector<JointVector>& rate) {
  const std::size_t count = values.size();
  rate.resize(count);
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t before = k == 0 ? 0 : k - 1;
    const std::size_t after = k + 1 == count ? k : k + 1;
    rate[k] = (values[after] - values[before]) / (time[after] - time[before]);
  }
}

void checkInputs(const Robot& robot, const std::vector<DriveParameters>& drives, const JointTrajectory& planned,
                 const DynamicCompensationOptions& options) {
  const std::size_t count = planned.time.size();
  if (count < 3) throw InvalidArgument("dynamic compensation: the trajectory needs at least three samples");
  if (planned.q.size() != count || planned.qd.size() != count) {
    throw InvalidArgument("dynamic compensation: the trajectory has " + std::to_string(count) + " times but " +
                          std::to_string(planned.q.size()) + " positions and " + std::to_string(planned.qd.size()) +
                          " velocities");
  }
  if (static_cast<int>(drives.size()) != robot.dof()) {
    throw InvalidArgument("dynamic compensation: " + std::to_string(drives.size()) + " drives for a robot with " +
                          std::to_string(robot.dof()) + " joints (the parameter file's \"plant\" object)");
  }
  for (std::size_t k = 0; k < count; ++k) {
    if (!std::isfinite(planned.time[k]) || (k > 0 && !(planned.time[k] > planned.time[k - 1]))) {
      throw InvalidArgument("dynamic compensation: sample " + std::to_string(k) +
                            ": times must be finite and increasing");
    }
    checkJointVector(robot, planned.q[k], "planned position");
    checkJointVector(robot, planned.qd[k], "planned velocity");
  }
  if (!(options.tolerance_rad > 0.0) || !std::isfinite(options.tolerance_rad) || options.max_iterations < 1 ||
      options.max_iterations > 1000) {
    throw InvalidArgument("dynamic compensation: tolerance_rad must be positive and max_iterations in 1..1000");
  }
  if (!std::isfinite(options.payload_mass) || options.payload_mass < 0.0 || !options.payload_com.allFinite() ||
      !options.tool_wrench.allFinite()) {
    throw InvalidArgument(
        "dynamic compensation: the payload mass must be finite and non-negative, its centre and "
        "the tool wrench finite");
  }
}

// The drive inverse filter of one joint, kd delta' + kp delta + ki int(delta) = right (stage 1b below):
// delta' for the filter's state and its right side.
double driveInverseRate(const DriveParameters& drive, double delta, double integral, double right) {
  const double kp = drive.kp_nm_per_rad, ki = drive.ki_nm_per_rad_s, kd = drive.kd_nms_per_rad;
  return kd > 0.0 ? (right - kp * delta - ki * integral) / kd : 0.0;
}

// One trapezoidal step of h seconds of that filter, from right side `right_before` to `right`: exact for
// a right side linear over the step, and stable for any step.
void driveInverseStep(const DriveParameters& drive, double h, double right_before, double right, double& delta,
                      double& integral) {
  const double kp = drive.kp_nm_per_rad, ki = drive.ki_nm_per_rad_s, kd = drive.kd_nms_per_rad;
  if (kd > 0.0) {
    // x = (integral, delta): x' = A x + b right, solved for the new x.
    const double a = 0.5 * h;
    const double rhs_integral = integral + a * delta;
    const double rhs_delta = delta + a * driveInverseRate(drive, delta, integral, right_before) + a * right / kd;
    // delta_new (1 + a kp / kd) + integral_new a ki / kd = rhs_delta; integral_new = rhs_integral + a delta_new
    const double c = a * ki / kd;
    delta = (rhs_delta - c * rhs_integral) / (1.0 + a * kp / kd + c * a);
    integral = rhs_integral + a * delta;
  } else if (kp > 0.0) {
    delta = right / kp;  // no derivative gain: the proportional term alone; the refinement does the rest
  }
}

// Stage 1b: the references that make each drive's motor follow the motor positions p_d of stage 1
// (`reference` on entry) while it pushes against `motor_reaction`. On the way, the controller's torque
// kp (r - p) + kd (r' - p') + ki int(r - p) + feed-forward (static load at r, friction at r') must equal
// B p_d'' + motor_reaction + friction(p_d'); with r = p_d + delta that asks
//   kd delta' + kp delta + ki int(delta) = B p_d'' + motor_reaction - static load(p_d) - (the same at rest),
// a stable second-order filter of the right side (the integral's rest value already holds the start),
// integrated here by the trapezoidal rule, exact for a right side linear between samples.
void invertDrives(const JointErrorModel& nominal, const std::vector<DriveParameters>& drives,
                  const DynamicCompensationOptions& options, const std::vector<double>& time,
                  const std::vector<JointVector>& motor_reaction, std::vector<JointVector>& reference,
                  std::vector<JointVector>& reference_velocity) {
  const Robot& robot = nominal.robot();
  const int n = robot.dof();
  const std::size_t count = time.size();
  std::vector<JointVector> velocity, acceleration;
  differentiate(time, reference, velocity);
  differentiate(time, velocity, acceleration);
  JointErrorWorkspace ws(robot);
  JointContext at_reference(n);  // the controller's static feed-forward sees the payload and the wrench too
  at_reference.payload_mass = options.payload_mass;
  at_reference.payload_com = options.payload_com;
  at_reference.tool_wrench = options.tool_wrench;
  std::vector<JointVector> demand(count);
  for (std::size_t k = 0; k < count; ++k) {
    at_reference.q = reference[k];
    computeLoadTorque(nominal, nominal.loadsAnd({}), ws, at_reference);
    demand[k] = motor_reaction[k] - at_reference.load_torque;
    for (int j = 0; j < n; ++j) demand[k][j] += drives[j].motor_inertia_kgm2 * acceleration[k][j];
  }
  reference_velocity.assign(count, JointVector::Zero(n));
  for (int j = 0; j < n; ++j) {
    double delta = 0.0, integral = 0.0;
    for (std::size_t k = 0; k < count; ++k) {
      const double right = demand[k][j] - demand[0][j];
      if (k > 0) {
        driveInverseStep(drives[j], time[k] - time[k - 1], demand[k - 1][j] - demand[0][j], right, delta, integral);
      }
      reference[k][j] += delta;
      reference_velocity[k][j] = velocity[k][j] + driveInverseRate(drives[j], delta, integral, right);
    }
  }
}

// The centred binomial filter [1 4 6 4 1] / 16 along the samples (ends held): zero phase, unit gain at rest,
// none at the sampling's Nyquist frequency, 0.98 at a fiftieth of the sampling rate.
void smoothZeroPhase(std::vector<JointVector>& values) {
  const std::size_t count = values.size();
  if (count < 5) return;
  const std::vector<JointVector> raw = values;
  auto at = [&](long k) -> const JointVector& {
    return raw[static_cast<std::size_t>(std::clamp(k, 0L, static_cast<long>(count) - 1))];
  };
  for (std::size_t k = 0; k < count; ++k) {
    const long i = static_cast<long>(k);
    values[k] = (at(i - 2) + 4.0 * at(i - 1) + 6.0 * at(i) + 4.0 * at(i + 1) + at(i + 2)) / 16.0;
  }
}

double largestError(const std::vector<JointVector>& actual, const std::vector<JointVector>& planned) {
  double largest = 0.0;
  for (std::size_t k = 0; k < actual.size(); ++k) {
    const double e = (actual[k] - planned[k]).cwiseAbs().maxCoeff();
    if (!std::isfinite(e)) return e;
    largest = std::max(largest, e);
  }
  return largest;
}

}  // namespace

std::vector<JointVector> runReference(FlexibleJointPlant& plant, const std::vector<double>& time,
                                      const std::vector<JointVector>& reference,
                                      const std::vector<JointVector>& reference_velocity) {
  std::vector<JointVector> actual(reference.size());
  plant.reset(reference[0], time[0]);
  for (std::size_t k = 0; k < reference.size(); ++k) {
    plant.setReference(reference[k], reference_velocity[k]);
    actual[k] = plant.linkPositions();
    if (k + 1 < reference.size()) plant.advance(time[k + 1]);
  }
  return actual;
}

namespace {

// Stage 1 at one sample: the static compensator under the motion's whole inverse-dynamics load (ctx holds the
// payload and the tool wrench), giving the motor positions `stage_one`, and what the motors must push
// against there, (I + E)^T tau_s: the transmission carries ctx.load_torque, and through the gears' error
// slope E = de/dp the motors feel (I + E)^T of it (as in the plant), E from the effects that give their slope.
FixedPointReport closedFormSample(const JointErrorModel& nominal, int compliance, Compensator& compensator,
                                  RobotWorkspace& workspace, JointContext& ctx, double time, const JointVector& q,
                                  const JointVector& qd, const JointVector& qdd, JointVector& with_motion,
                                  JointVector& at_rest, JointVector& stage_one, JointVector& motor_reaction) {
  const Robot& robot = nominal.robot();
  inverseDynamics(robot, workspace, q, qd, qdd, with_motion);
  gravityTorques(robot, workspace, q, at_rest);
  ctx.inertial_torque = with_motion - at_rest;
  ctx.q = q;
  ctx.velocity = qd;
  ctx.time = time;
  const FixedPointReport fixed_point = compensator.compensate(ctx, stage_one);
  if (!fixed_point.converged) return fixed_point;
  JointVector& motor_slope = at_rest;  // done with it: reused, nothing allocated
  motor_slope.setZero(robot.dof());
  for (int i = 0; i < nominal.effectCount(); ++i) {
    const Effect& effect = nominal.effect(i);
    if (i != compliance && effect.role() == EffectRole::JointError && effect.dependsOnCommand())
      effect.addMotorSlope(robot, ctx, motor_slope);
  }
  const JointMatrix slope = motor_slope.asDiagonal() * nominal.gears().motorFromJoint();
  motor_reaction = ctx.load_torque + slope.transpose() * ctx.load_torque;
  return fixed_point;
}

// Stages 1 and 1b for the link trajectory `target` (times, positions, velocities): the references and
// their velocities that the model says bring the links onto it.
void invertModel(const JointErrorModel& nominal, const std::vector<DriveParameters>& drives,
                 const DynamicCompensationOptions& options, Compensator& compensator, const JointTrajectory& target,
                 std::vector<JointVector>& reference, std::vector<JointVector>& reference_velocity) {
  const Robot& robot = nominal.robot();
  const int n = robot.dof();
  const std::size_t count = target.time.size();
  std::vector<JointVector> acceleration;
  differentiate(target.time, target.qd, acceleration);
  RobotWorkspace workspace(robot);
  JointContext ctx(n);
  ctx.payload_mass = options.payload_mass;
  ctx.payload_com = options.payload_com;
  ctx.tool_wrench = options.tool_wrench;
  JointVector with_motion, at_rest;
  std::vector<JointVector> motor_reaction(count);
  const int compliance = nominal.jointSprings();
  reference.resize(count);
  for (std::size_t k = 0; k < count; ++k) {
    const FixedPointReport fixed_point =
        closedFormSample(nominal, compliance, compensator, workspace, ctx, target.time[k], target.q[k], target.qd[k],
                         acceleration[k], with_motion, at_rest, reference[k], motor_reaction[k]);
    if (!fixed_point.converged) {
      throw SolverError("dynamic compensation: the compensation of sample " + std::to_string(k) +
                        " (t = " + std::to_string(target.time[k]) + " s) did not converge (residual " +
                        std::to_string(fixed_point.residual) + " rad)");
    }
  }
  invertDrives(nominal, drives, options, target.time, motor_reaction, reference, reference_velocity);
}

}  // namespace

DynamicCompensationReport compensateDynamically(const JointErrorModel& nominal,
                                                const std::vector<DriveParameters>& drives,
                                                const JointTrajectory& planned, std::vector<JointVector>& reference,
                                                std::vector<JointVector>& reference_velocity,
                                                const DynamicCompensationOptions& options) {
  const Robot& robot = nominal.robot();
  checkInputs(robot, drives, planned, options);
  const std::size_t count = planned.time.size();
  DynamicCompensationReport report;
  Compensator compensator(nominal, nominal.allEffects(), options.fixed_point);
  JointTrajectory target = planned;
  invertModel(nominal, drives, options, compensator, target, reference, reference_velocity);

  // Stage 2: run the reference through the nominal plant, move the target by the error left at each
  // sample, and invert the model again for it: pre-distortion through the model's own inverse, which
  // converges where a plain "reference minus error" update excites the joints' resonances. The update is
  // damped (kLearningGain) and low-passed without phase (smoothZeroPhase): what the 4 ms samples cannot
  // represent is left alone instead of being amplified run after run. The best reference is kept.
  constexpr double kLearningGain = 0.7;
  FlexibleJointPlant plant(nominal, drives, options.plant);
  plant.setPayload(options.payload_mass, options.payload_com);
  plant.setToolWrench(options.tool_wrench);
  std::vector<JointVector> offset(count, JointVector::Zero(robot.dof())), offset_rate, increment(count);
  std::vector<JointVector> best_reference = reference, best_velocity = reference_velocity;
  double best = std::numeric_limits<double>::infinity();
  int best_run = 0;
  for (int run = 1; run <= options.max_iterations; ++run) {
    std::vector<JointVector> actual;
    try {
      actual = runReference(plant, planned.time, reference, reference_velocity);
    } catch (const Error& error) {
      throw SolverError("dynamic compensation: run " + std::to_string(run) +
                        " of the nominal plant failed: " + error.what());
    }
    const double error = largestError(actual, planned.q);
    report.iterations = run;
    report.error_per_run.push_back(error);
    if (!std::isfinite(error)) throw SolverError("dynamic compensation: the nominal plant's links left finite values");
    if (error < best) {
      best = error;
      best_run = run;
      best_reference = reference;
      best_velocity = reference_velocity;
    }
    // Done when within the tolerance, or when five runs brought nothing better (the refinement's floor).
    if (error <= options.tolerance_rad || run - best_run >= 5 || run == options.max_iterations) break;
    for (std::size_t k = 0; k < count; ++k) increment[k] = planned.q[k] - actual[k];
    smoothZeroPhase(increment);
    for (std::size_t k = 0; k < count; ++k) offset[k] += kLearningGain * increment[k];
    differentiate(planned.time, offset, offset_rate);
    for (std::size_t k = 0; k < count; ++k) {
      target.q[k] = planned.q[k] + offset[k];
      target.qd[k] = planned.qd[k] + offset_rate[k];
    }
    invertModel(nominal, drives, options, compensator, target, reference, reference_velocity);
  }
  report.initial_error_rad = report.error_per_run.front();
  report.max_error_rad = best;
  if (!(best <= options.tolerance_rad)) {
    throw SolverError("dynamic compensation: largest link error " + std::to_string(best) + " rad after " +
                      std::to_string(report.iterations) + " runs of the nominal plant (best at run " +
                      std::to_string(best_run) + "), above the tolerance " + std::to_string(options.tolerance_rad) +
                      " rad");
  }
  reference = std::move(best_reference);
  reference_velocity = std::move(best_velocity);
  for (std::size_t k = 0; k < count; ++k) {
    requireWithinLimits(robot, reference[k]);
    report.max_correction_rad =
        std::max(report.max_correction_rad, (planned.q[k] - reference[k]).cwiseAbs().maxCoeff());
  }
  return report;
}

OnlineDynamicCompensator::OnlineDynamicCompensator(const JointErrorModel& nominal,
                                                   const std::vector<DriveParameters>& drives,
                                                   const DynamicCompensationOptions& options)
    : nominal_(nominal),
      drives_(drives),
      options_(options),
      compensator_(nominal, nominal.allEffects(), options.fixed_point),
      robot_ws_(nominal.robot()),
      load_ws_(nominal.robot()),
      ctx_(nominal.robot().dof()),
      at_reference_(nominal.robot().dof()),
      compliance_(nominal.jointSprings()) {
  const int n = nominal.robot().dof();
  if (static_cast<int>(drives.size()) != n) {
    throw InvalidArgument("dynamic compensation: " + std::to_string(drives.size()) + " drives for a robot with " +
                          std::to_string(n) + " joints (the parameter file's \"plant\" object)");
  }
  if (!std::isfinite(options.payload_mass) || options.payload_mass < 0.0 || !options.payload_com.allFinite()) {
    throw InvalidArgument("dynamic compensation: the payload mass must be finite and non-negative, its centre finite");
  }
  for (JointContext* ctx : {&ctx_, &at_reference_}) {
    ctx->payload_mass = options.payload_mass;
    ctx->payload_com = options.payload_com;
  }
  for (JointVector* v : {&with_motion_, &at_rest_, &stage_one_, &motor_reaction_, &demand_}) v->setZero(n);
}

OnlineDynamicState OnlineDynamicCompensator::initialState() const {
  const int n = nominal_.robot().dof();
  OnlineDynamicState state;
  for (JointVector* v : {&state.correction, &state.demand_at_start, &state.demand, &state.delta, &state.integral})
    v->setZero(n);
  return state;
}

FixedPointReport OnlineDynamicCompensator::compensate(const OnlineDynamicState& before, double time,
                                                      const JointVector& q, const JointVector& qd,
                                                      const JointVector& qdd, const Vector6& tool_wrench,
                                                      JointVector& reference, JointVector& reference_velocity,
                                                      OnlineDynamicState& after) {
  const Robot& robot = nominal_.robot();
  const int n = robot.dof();
  if (!std::isfinite(time) || (before.started && !(time > before.time))) {
    throw InvalidArgument("dynamic compensation: sample at t = " + std::to_string(time) +
                          " s, which is not after the last one (t = " + std::to_string(before.time) + " s)");
  }
  checkJointVector(robot, q, "planned position");
  checkJointVector(robot, qd, "planned velocity");
  checkJointVector(robot, qdd, "planned acceleration");
  if (!tool_wrench.allFinite()) throw InvalidArgument("dynamic compensation: the tool wrench is not finite");
  reference.resize(n);  // within JointVector's fixed capacity: no allocation
  reference_velocity.resize(n);
  ctx_.tool_wrench = tool_wrench;
  at_reference_.tool_wrench = tool_wrench;
  const FixedPointReport fixed_point = closedFormSample(nominal_, compliance_, compensator_, robot_ws_, ctx_, time, q,
                                                        qd, qdd, with_motion_, at_rest_, stage_one_, motor_reaction_);
  if (!fixed_point.converged) return fixed_point;
  // Stage 1b, causal: the right side at this sample, then one filter step from the last one.
  at_reference_.q = stage_one_;
  computeLoadTorque(nominal_, nominal_.loadsAnd({}), load_ws_, at_reference_);
  demand_ = motor_reaction_ - at_reference_.load_torque;
  for (int j = 0; j < n; ++j) demand_[j] += drives_[j].motor_inertia_kgm2 * qdd[j];
  const double h = before.started ? time - before.time : 0.0;
  if (&after != &before) after = before;
  for (int j = 0; j < n; ++j) {
    const double correction = stage_one_[j] - q[j];
    const double correction_rate = before.started ? (correction - before.correction[j]) / h : 0.0;
    if (!before.started) after.demand_at_start[j] = demand_[j];
    const double right = demand_[j] - after.demand_at_start[j];
    if (before.started) {
      driveInverseStep(drives_[j], h, before.demand[j] - before.demand_at_start[j], right, after.delta[j],
                       after.integral[j]);
    }
    reference[j] = stage_one_[j] + after.delta[j];
    reference_velocity[j] =
        qd[j] + correction_rate + driveInverseRate(drives_[j], after.delta[j], after.integral[j], right);
    after.correction[j] = correction;
    after.demand[j] = demand_[j];
  }
  after.started = true;
  after.time = time;
  requireWithinLimits(robot, reference);
  return fixed_point;
}

}  // namespace jointcomp
