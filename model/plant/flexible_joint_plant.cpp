#include "model/plant/flexible_joint_plant.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "model/common/errors.hpp"
#include "model/plant/plant_newton_solver.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {

FlexibleJointPlant::FlexibleJointPlant(const JointErrorModel& truth, std::vector<DriveParameters> drives,
                                       PlantOptions options)
    : model_(truth, std::move(drives), options), data_(model_) {
  setWatchdog(model_.options.tracking_envelope_rad, model_.options.joint_limit_margin_rad);
  integrator_ = std::make_unique<PlantIntegrator>(model_, data_);
  reset(JointVector::Zero(model_.n));
}

FlexibleJointPlant::~FlexibleJointPlant() = default;

void FlexibleJointPlant::reset(const JointVector& command, double start_time) {
  checkJointVector(model_.truth.robot(), command, "command");
  if (!std::isfinite(start_time)) throw InvalidArgument("plant: start time is not finite");
  data_.ctx.command = command;
  const FixedPointReport settled = settleStatically(model_.truth, model_.truth.allEffects(), data_.ws, data_.ctx);
  if (!settled.converged) throw SolverError("plant: no static equilibrium found at the initial command");
  const JointVector q = data_.ctx.q;
  const JointVector rest = JointVector::Zero(model_.n);
  JointVector spring_torque, motor_reaction;
  plantTransmissionTorques(model_, data_, command, rest, q, rest, spring_torque, motor_reaction);
  time_ = start_time;
  data_.reference = command;
  data_.reference_velocity.setZero(model_.n);
  data_.reference_acceleration.setZero(model_.n);
  data_.reference_time = start_time;
  plantStaticFeedforward(model_, data_, command, data_.feedforward);
  data_.feedforward_rate.setZero(model_.n);
  data_.feedforward_pending = false;
  data_.blend_offset.setZero(model_.n);
  data_.blend_offset_velocity.setZero(model_.n);
  data_.blend_offset_acceleration.setZero(model_.n);
  data_.feedforward_offset.setZero(model_.n);
  data_.feedforward_offset_rate.setZero(model_.n);
  data_.blend_duration = 0.0;
  ahead_ = false;
  double* y = integrator_->state();
  for (int j = 0; j < model_.n; ++j) {
    y[j] = q[j];
    y[model_.n + j] = 0.0;
    y[2 * model_.n + j] = command[j];
    y[3 * model_.n + j] = 0.0;
    const double ki = model_.drives[j].ki_nm_per_rad_s;
    // The integral holds exactly what the motor must push against at rest, so the plant starts still.
    y[4 * model_.n + j] = ki > 0.0 ? (motor_reaction[j] - data_.feedforward[j]) / ki : 0.0;
  }
  restart_ = true;
  tripped_.clear();
}

void FlexibleJointPlant::setReference(const JointVector& position, const JointVector& velocity) {
  checkJointVector(model_.truth.robot(), position, "reference position");
  checkJointVector(model_.truth.robot(), velocity, "reference velocity");
  // The interpolator extrapolates with the acceleration seen between the last two updates, and the
  // static-load feed-forward with its rate along the motion, so that the controller's output is nearly
  // continuous across updates and the integrator is not knocked back to small steps at each one.
  if (model_.options.smooth_reference)
    plantEnsureFeedforward(model_, data_);  // the blend starts from the running feed-forward
  // Stepping past updates, CVODE may have integrated the old reference beyond time_ already: the new one
  // takes over from CVODE's next step only if it stays within step_past_tolerance_rad of the old one there.
  double ahead_time = time_;
  if (ahead_ && !restart_ && !integrator_->cvodeTime(ahead_time)) ahead_time = time_;
  // (CVODE ending a step on time_ within its roundoff, as it takes a stop time, is not ahead of it.)
  const bool check_departure =
      ahead_time - time_ > 100.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::fabs(time_));
  const double departure_times[3] = {time_, 0.5 * (time_ + ahead_time), ahead_time};
  double old_reference[3][kMaxJoints];
  for (int k = 0; k < 3 && check_departure; ++k) {
    for (int j = 0; j < model_.n; ++j) old_reference[k][j] = plantReferenceAt(data_, j, departure_times[k]);
  }
  updateReference(position, velocity);
  if (check_departure) {
    ++statistics_.updates_stepped_past;
    double departure = 0.0;
    for (int k = 0; k < 3; ++k) {
      for (int j = 0; j < model_.n; ++j) {
        departure =
            std::max(departure, std::fabs(plantReferenceAt(data_, j, departure_times[k]) - old_reference[k][j]));
      }
    }
    if (!(departure <= model_.options.step_past_tolerance_rad)) {
      ++statistics_.updates_restarted;
      restart_ = true;  // from the state at time_ (advance takes it from y_now), with the new reference
    }
  }
}

// The update itself: the acceleration seen since the last update, the pending feed-forward and the blend.
void FlexibleJointPlant::updateReference(const JointVector& position, const JointVector& velocity) {
  const double since_last = time_ - data_.reference_time;
  // The reference as it runs now, before the update: the blend starts from it.
  JointVector before_value(model_.n), before_velocity(model_.n), before_acceleration(model_.n),
      before_feedforward(model_.n), before_feedforward_rate(model_.n);
  for (int j = 0; j < model_.n && model_.options.smooth_reference; ++j) {
    const PlantReferencePoint before = plantReferencePoint(data_, j, time_);
    before_value[j] = before.value;
    before_velocity[j] = before.velocity;
    before_acceleration[j] = before.acceleration;
    before_feedforward[j] = before.feedforward;
    before_feedforward_rate[j] = before.feedforward_rate;
  }
  if (since_last > 0.0) {
    data_.reference_acceleration = (velocity - data_.reference_velocity) / since_last;
    // A velocity of exactly zero is a stop: that joint holds the position given. (The acceleration of the
    // last interval, -100 rad/s^2 after a 1 rad/s motion stopped at 10 ms updates, would otherwise run it
    // away quadratically until the next update, and the watchdog would blame the drive.)
    for (int j = 0; j < model_.n; ++j) {
      if (velocity[j] == 0.0) data_.reference_acceleration[j] = 0.0;
    }
  } else {
    data_.reference_acceleration.setZero(model_.n);
  }
  data_.reference = position;
  data_.reference_velocity = velocity;
  data_.reference_time = time_;
  data_.feedforward_pending = true;
  if (model_.options.smooth_reference) plantEnsureFeedforward(model_, data_);
  // The new extrapolation takes over from the old one over the interval the last update took (the next
  // one is expected as long); a second update at the same time keeps the blend's duration.
  const bool blended_before = data_.blend_duration > 0.0;
  if (!model_.options.smooth_reference) {
    data_.blend_duration = 0.0;
  } else if (since_last > 0.0) {
    data_.blend_duration = since_last;
  }
  if (data_.blend_duration > 0.0) {
    data_.blend_offset = before_value - data_.reference;
    data_.blend_offset_velocity = before_velocity - data_.reference_velocity;
    data_.blend_offset_acceleration = before_acceleration - data_.reference_acceleration;
    data_.feedforward_offset = before_feedforward - data_.feedforward;
    data_.feedforward_offset_rate = before_feedforward_rate - data_.feedforward_rate;
  } else if (blended_before) {  // without a blend the offsets are zero already (reset, restoreState)
    data_.blend_offset.setZero(model_.n);
    data_.blend_offset_velocity.setZero(model_.n);
    data_.blend_offset_acceleration.setZero(model_.n);
    data_.feedforward_offset.setZero(model_.n);
    data_.feedforward_offset_rate.setZero(model_.n);
  }
}

void FlexibleJointPlant::setToolWrench(const Vector6& wrench) {
  if (!wrench.allFinite()) throw InvalidArgument("plant: tool wrench is not finite");
  plantEnsureFeedforward(model_, data_);  // at the loads of its update
  data_.ctx.tool_wrench = wrench;
  restart_ = true;  // a step in the load: start the integrator afresh
}

void FlexibleJointPlant::setPayload(double mass, const Eigen::Vector3d& com_in_tool) {
  if (!std::isfinite(mass) || mass < 0.0 || !com_in_tool.allFinite()) {
    throw InvalidArgument("plant: payload mass must be finite and non-negative, its centre finite");
  }
  plantEnsureFeedforward(model_, data_);  // at the loads of its update
  data_.ctx.payload_mass = mass;
  data_.ctx.payload_com = com_in_tool;
  restart_ = true;
}

void FlexibleJointPlant::referenceAt(double t, JointVector& position, JointVector& velocity,
                                     JointVector& acceleration) const {
  position.resize(model_.n);
  velocity.resize(model_.n);
  acceleration.resize(model_.n);
  for (int j = 0; j < model_.n; ++j) {
    const PlantReferencePoint point = plantReferencePoint(data_, j, t);
    position[j] = point.value;
    velocity[j] = point.velocity;
    acceleration[j] = point.acceleration;
  }
}

void FlexibleJointPlant::derivative(double t, const double* y, double* ydot) {
  plantDerivative(model_, data_, t, y, ydot);
}

void FlexibleJointPlant::jacobian(double t, const double* y, double* jacobian) {
  plantJacobian(model_, data_, t, y, jacobian);
}

void FlexibleJointPlant::solveNewtonSystem(double t, const double* y, double gamma, const double* b, double* x) {
  const int size = model_.stateSize();
  std::vector<double> matrix(static_cast<std::size_t>(size) * size);
  jacobian(t, y, matrix.data());
  StructuredLinearSolver solver(model_.n);
  if (solver.setup(matrix.data(), gamma) != SUNLS_SUCCESS) throw SolverError("plant: the Newton system is singular");
  solver.solve(x, b);
}

PlantStatistics FlexibleJointPlant::statistics() const { return integrator_->statistics(statistics_); }

void FlexibleJointPlant::advance(double end_time) {
  if (!std::isfinite(end_time) || !(end_time > time_)) {
    throw InvalidArgument("plant: advance to t = " + std::to_string(end_time) +
                          " s, which is not after the current t = " + std::to_string(time_) + " s");
  }
  if (!tripped_.empty()) {
    throw PlantLimitError(tripped_ + "; the run stopped there: reset the plant or restore a saved state to go on");
  }
  if (restart_) {
    integrator_->restart(time_, ahead_);
    ahead_ = false;
    restart_ = false;
  }
  // The work budget of this advance: a floor for the start-up transients plus a rate per simulated second
  // far above what the plant needs (about 800 steps per second on the paper's spiral), so that a plant
  // that cannot be integrated fails within seconds instead of running for minutes.
  const double budget = std::min(static_cast<double>(model_.options.max_steps_per_advance),
                                 kStepBudgetFloor + kStepBudgetPerSecond * (end_time - time_));
  bool past = false;
  double reached = time_;
  const int flag = integrator_->advance(time_, end_time, ahead_, static_cast<long>(budget), past, reached);
  if (flag < 0) {
    // Keep the last good state: CVODE leaves y at the last successful step.
    time_ = reached;
    restart_ = true;
    ahead_ = false;
    if (PlantIntegrator::budgetSpent(flag)) {
      throw SolverError("plant: the integration spent its work budget (" + std::to_string(static_cast<long>(budget)) +
                        " CVODE steps, CV_TOO_MUCH_WORK) between t = " + std::to_string(reached) + " s and " +
                        std::to_string(end_time) +
                        " s: the plant is too stiff for its parameters (look at the drive gains and the joint "
                        "stiffnesses) or the motion leaves what it can follow" +
                        (integrator_->lastError().empty() ? std::string() : "; CVODE: " + integrator_->lastError()));
    }
    throw SolverError(
        "plant: CVODE failed between t = " + std::to_string(reached) + " s and " + std::to_string(end_time) +
        " s: " + (integrator_->lastError().empty() ? PlantIntegrator::flagName(flag) : integrator_->lastError()));
  }
  ahead_ = past;  // past: the state at end_time is interpolated (y_now); otherwise CVODE stopped on end_time
  time_ = end_time;
  checkWatchdog();
}

const double* FlexibleJointPlant::now() const { return integrator_->state(ahead_); }

void FlexibleJointPlant::setWatchdog(double tracking_envelope_rad, double joint_limit_margin_rad) {
  if (!std::isfinite(tracking_envelope_rad) || !(tracking_envelope_rad > 0.0)) {
    throw InvalidArgument("plant: tracking_envelope_rad must be finite and positive; it is " +
                          std::to_string(tracking_envelope_rad));
  }
  if (!std::isfinite(joint_limit_margin_rad) || joint_limit_margin_rad < 0.0) {
    throw InvalidArgument("plant: joint_limit_margin_rad must be finite and not negative; it is " +
                          std::to_string(joint_limit_margin_rad));
  }
  model_.options.tracking_envelope_rad = tracking_envelope_rad;
  model_.options.joint_limit_margin_rad = joint_limit_margin_rad;
}

void FlexibleJointPlant::checkWatchdog() {
  const Robot& robot = model_.truth.robot();
  const double* y = now();
  const double margin = model_.options.joint_limit_margin_rad;
  // The two limits, each written once for the test below and for the messages.
  const auto beyond_limits = [&](int j) {  // continuous joints: +-inf
    const Joint& joint = robot.joints[static_cast<std::size_t>(j)];
    return (y[j] > joint.upper + margin) | (y[j] < joint.lower - margin);
  };
  const auto following_error = [&](int j) { return plantReferenceAt(data_, j, time_) - y[2 * model_.n + j]; };
  const auto beyond_envelope = [&](int j) {
    return std::abs(following_error(j)) > model_.options.tracking_envelope_rad;
  };
  // Every joint first, without a branch per joint; a message only when one is crossed (a NaN crosses none).
  if (tripped_.empty()) {
    bool beyond = false;
    for (int j = 0; j < model_.n; ++j) beyond |= beyond_limits(j);
    for (int j = 0; j < model_.n && model_.options.control; ++j) beyond |= beyond_envelope(j);
    if (!beyond) return;
  }
  char text[400];
  for (int j = 0; j < model_.n && tripped_.empty(); ++j) {
    if (!beyond_limits(j)) continue;
    const Joint& joint = robot.joints[static_cast<std::size_t>(j)];
    std::snprintf(text, sizeof text,
                  "plant: at t = %.9g s link %s is at %.6g rad, beyond its joint limits [%.6g, %.6g] rad by more "
                  "than the %.3g rad margin",
                  time_, joint.name.c_str(), y[j], joint.lower, joint.upper, margin);
    tripped_ = text;
  }
  for (int j = 0; j < model_.n && tripped_.empty() && model_.options.control; ++j) {
    if (!beyond_envelope(j)) continue;
    std::snprintf(text, sizeof text,
                  "plant: at t = %.9g s the drive of %s has a following error of %.6g rad (reference %.6g, motor "
                  "%.6g), beyond its tracking envelope of %.3g rad: the drive cannot follow its reference",
                  time_, robot.joints[static_cast<std::size_t>(j)].name.c_str(), following_error(j),
                  plantReferenceAt(data_, j, time_), y[2 * model_.n + j], model_.options.tracking_envelope_rad);
    tripped_ = text;
  }
  if (!tripped_.empty()) throw PlantLimitError(tripped_);
}

JointVector FlexibleJointPlant::linkPositions() const { return Eigen::Map<const Eigen::VectorXd>(now(), model_.n); }
JointVector FlexibleJointPlant::linkVelocities() const {
  return Eigen::Map<const Eigen::VectorXd>(now() + model_.n, model_.n);
}
JointVector FlexibleJointPlant::motorPositions() const {
  return Eigen::Map<const Eigen::VectorXd>(now() + 2 * model_.n, model_.n);
}
JointVector FlexibleJointPlant::motorVelocities() const {
  return Eigen::Map<const Eigen::VectorXd>(now() + 3 * model_.n, model_.n);
}

JointVector FlexibleJointPlant::motorTorques() {
  plantEnsureFeedforward(model_, data_);
  const double* y = now();
  const Eigen::Map<const Eigen::VectorXd> state(y, model_.stateSize());
  JointVector torque;
  plantMotorTorques(model_, data_, time_, state.segment(2 * model_.n, model_.n), state.segment(3 * model_.n, model_.n),
                    state.segment(4 * model_.n, model_.n), torque);
  return torque;
}

double FlexibleJointPlant::mechanicalEnergy() {
  const Robot& robot = model_.truth.robot();
  const JointVector q = linkPositions();
  const JointVector qd = linkVelocities();
  const JointVector p = motorPositions();
  const JointVector pd = motorVelocities();
  double energy = kineticEnergy(robot, data_.ws.robot, q, qd) + potentialEnergy(robot, data_.ws.robot, q);
  for (int j = 0; j < model_.n; ++j) energy += 0.5 * model_.drives[j].motor_inertia_kgm2 * pd[j] * pd[j];
  JointVector error;
  plantTransmissionError(model_, data_, p, q, error);
  const JointVector stretch = p + error - q;
  energy += 0.5 * stretch.dot(model_.stiffness.cwiseProduct(stretch));
  data_.ctx.q = q;
  for (int i = 0; i < model_.truth.effectCount(); ++i)
    energy += model_.truth.effect(i).loadPotentialEnergy(robot, data_.ctx);
  if (data_.ctx.payload_mass != 0.0) {
    forwardKinematics(robot, data_.ws.robot, q);
    energy -= data_.ctx.payload_mass * robot.gravity.dot(data_.ws.robot.tool_pose * data_.ctx.payload_com);
  }
  return energy;
}

const double* FlexibleJointPlant::state() const { return now(); }

PlantState FlexibleJointPlant::saveState() {
  plantEnsureFeedforward(model_, data_);
  PlantState state;
  state.time = time_;
  const double* y = now();
  state.y.assign(y, y + model_.stateSize());
  state.reference = data_.reference;
  state.reference_velocity = data_.reference_velocity;
  state.reference_acceleration = data_.reference_acceleration;
  state.feedforward = data_.feedforward;
  state.feedforward_rate = data_.feedforward_rate;
  state.reference_time = data_.reference_time;
  state.blend_offset = data_.blend_offset;
  state.blend_offset_velocity = data_.blend_offset_velocity;
  state.blend_offset_acceleration = data_.blend_offset_acceleration;
  state.feedforward_offset = data_.feedforward_offset;
  state.feedforward_offset_rate = data_.feedforward_offset_rate;
  state.blend_duration = data_.blend_duration;
  state.tool_wrench = data_.ctx.tool_wrench;
  state.payload_mass = data_.ctx.payload_mass;
  state.payload_com = data_.ctx.payload_com;
  restart_ = true;  // continuing from here must match continuing from a restored copy, bit for bit
  return state;
}

void FlexibleJointPlant::restoreState(const PlantState& state) {
  if (static_cast<int>(state.y.size()) != model_.stateSize() || state.reference.size() != model_.n ||
      state.reference_velocity.size() != model_.n || state.reference_acceleration.size() != model_.n ||
      state.feedforward.size() != model_.n || state.feedforward_rate.size() != model_.n) {
    throw InvalidArgument("plant: the saved state is for a plant of another size");
  }
  // A state without a blend may leave its parts empty (the C API's snapshots do: their plants never blend).
  const JointVector* blend_parts[] = {&state.blend_offset, &state.blend_offset_velocity,
                                      &state.blend_offset_acceleration, &state.feedforward_offset,
                                      &state.feedforward_offset_rate};
  const bool without_blend = state.blend_duration == 0.0;
  for (const JointVector* part : blend_parts) {
    if (part->size() != model_.n && !(without_blend && part->size() == 0)) {
      throw InvalidArgument("plant: the saved state's reference blend is for a plant of another size");
    }
    if (!part->allFinite()) throw InvalidArgument("plant: the saved state's reference blend is not finite");
  }
  for (double v : state.y) {
    if (!std::isfinite(v)) throw InvalidArgument("plant: the saved state holds a value that is not finite");
  }
  if (!std::isfinite(state.time)) throw InvalidArgument("plant: the saved state's time is not finite");
  if (!std::isfinite(state.blend_duration) || state.blend_duration < 0.0) {
    throw InvalidArgument("plant: the saved state's blend duration is not finite and non-negative");
  }
  time_ = state.time;
  ahead_ = false;
  std::copy(state.y.begin(), state.y.end(), integrator_->state());
  data_.reference = state.reference;
  data_.reference_velocity = state.reference_velocity;
  data_.reference_acceleration = state.reference_acceleration;
  data_.feedforward = state.feedforward;
  data_.feedforward_rate = state.feedforward_rate;
  data_.feedforward_pending = false;
  data_.reference_time = state.reference_time;
  JointVector* blend_targets[] = {&data_.blend_offset, &data_.blend_offset_velocity, &data_.blend_offset_acceleration,
                                  &data_.feedforward_offset, &data_.feedforward_offset_rate};
  // Without a blend the offsets are never read, and are kept zero (setReference relies on it).
  for (int i = 0; i < 5; ++i) {
    if (!without_blend) {
      *blend_targets[i] = *blend_parts[i];
    } else {
      blend_targets[i]->setZero(model_.n);
    }
  }
  data_.blend_duration = state.blend_duration;
  data_.ctx.tool_wrench = state.tool_wrench;
  data_.ctx.payload_mass = state.payload_mass;
  data_.ctx.payload_com = state.payload_com;
  restart_ = true;
  tripped_.clear();
}

}  // namespace jointcomp
