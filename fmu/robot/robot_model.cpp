// The robot model of the FMU (robot_model.hpp): loading, building, the reference, the outputs and one step.
// Its FMU-state functions are in robot_state_bytes.cpp.
#include "fmu/robot/robot_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "fmu/core/instance.hpp"
#include "fmu/robot/demo_move.hpp"
#include "fmu/robot/held_steps.hpp"
#include "model/common/bits.hpp"
#include "model/common/errors.hpp"
#include "model/plant/plant_options_by_name.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp::fmu {

std::unique_ptr<Model> loadModel(const std::string& resource_dir, const std::string& instantiation_token) {
  // An empty token would skip the check: it is never that of any resources.
  if (instantiation_token.empty()) throw Error("the instantiation token is empty");
  FmuResources resources = loadFmuResources(resource_dir, JOINTCOMP_FMU_VERSION, instantiation_token);
  return std::make_unique<RobotModel>(resources.robot, std::move(resources.parameters), std::move(resources.table));
}

RobotState RobotState::atStart(int dof) {
  RobotState state;
  state.last_q_desired.setZero(dof);
  state.earlier_q_desired.setZero(dof);
  state.earliest_q_desired.setZero(dof);
  OnlineDynamicState& d = state.dynamic;
  for (JointVector* v : {&d.correction, &d.demand_at_start, &d.demand, &d.delta, &d.integral}) v->setZero(dof);
  return state;
}

// Binds every parameter of the table to its place in the set.
RobotModel::RobotModel(std::shared_ptr<const Robot> robot, ParameterSet parameters, VariableTable table)
    : table_(std::move(table)),
      dof_(table_.dof()),
      robot_(std::move(robot)),
      base_(std::move(parameters)),
      binding_(base_, *robot_, table_),
      compensation_ctx_(robot_->dof()),
      prediction_ctx_(robot_->dof()),
      prediction_ws_(*robot_),
      live_(RobotState::atStart(dof_)) {
  const std::size_t count = table_.variables.size();
  fixed_parameter_.assign(count, false);
  desired_input_.assign(count, false);
  for (std::size_t i = 0; i < count; ++i) {
    const Variable& v = table_.variables[i];
    fixed_parameter_[i] = v.causality == Causality::Parameter && v.variability == Variability::Fixed;
  }
  for (int j = 0; j < dof_; ++j) {
    for (int index : {roles().q_desired[j], roles().qd_desired[j], roles().qdd_desired[j]})
      desired_input_[index] = true;
  }
  planned_ = JointVector::Zero(dof_);
  updateCoreFlags();
}

VariableTraits RobotModel::traits(int index) const {
  VariableTraits traits;
  for (int j = 0; j < dof_; ++j) {
    if (index == roles().q_link[j]) traits.output_group = kLinkOutputs;
    if (index == roles().qd_link[j]) traits.output_group = kLinkVelocityOutputs;
    if (index == roles().q_motor[j] || index == roles().qd_motor[j] || index == roles().dq_actual[j])
      traits.output_group = kMotorOutputs;
    if (index == roles().dq_predicted[j]) traits.output_group = kPredictedOutputs;
    if (index == roles().q_ref[j] || index == roles().q_planned[j]) traits.output_group = kReferenceOutputs;
  }
  for (int k : roles().tool_position) {
    if (index == k) traits.output_group = kToolOutputs;
  }
  // Setting a desired input, even to its start value, makes reference = auto follow the inputs; they are
  // refused in steps while the robot follows the demo move. Another compensation mode rebuilds the compensator.
  traits.watched = desired_input_[index] || index == roles().compensation;
  traits.held_when_restricted = desired_input_[index];
  return traits;
}

void RobotModel::setTolerance(CoreState& state, double tolerance) {
  // The importer's tolerance becomes the integrator's relative tolerance (and its parameter's value).
  for (int i = 0; i < table_.size(); ++i) {
    const PlantOptionByName* option = binding_.option(i);
    if (option && std::strcmp(option->name, "relative_tolerance") == 0) state.values[i] = tolerance;
  }
}

void RobotModel::onSet(CoreState& state, int index, bool changed, bool before_step) {
  if (desired_input_[index] && !live_.desired_inputs_set) {
    live_.desired_inputs_set = true;
    if (state.phase == kInitializationMode) state.initialized = false;
    updateCoreFlags();
  }
  if (index == roles().compensation && changed) {
    // Another compensation mode: the dynamic mode's drive filter starts afresh from the next sample.
    live_.dynamic.started = false;
    if (built_ && !before_step) ensureCompensator(state);
  }
}

std::string RobotModel::restriction(const CoreState& state) const {
  return std::string("the robot follows the built-in demo move (reference = ") +
         (state.values[roles().reference] == kReferenceDemo
              ? std::string("demo")
              : std::string("auto, and no q_desired or qd_desired input was set before the end of initialisation")) +
         "); set reference = inputs, or the inputs during initialisation";
}

void RobotModel::reset(const CoreState&) {
  live_ = RobotState::atStart(dof_);
  reference_valid_ = false;
  outputs_valid_ = 0;
  updateCoreFlags();
}

// ------------------------------------------------------------------------------------------------
// Models and reference.

bool RobotModel::fixedParametersDiffer(const std::vector<double>& values) const {
  if (!built_) return true;
  for (int i = 0; i < table_.size(); ++i) {
    if (fixed_parameter_[i] && !sameBits(values[i], built_values_[i])) return true;
  }
  return false;
}

void RobotModel::ensureModels(CoreState& state) {
  if (!fixedParametersDiffer(state.values)) {
    ensureCompensator(state);
    return;
  }
  VariableBinding::BoundModels built = binding_.apply(base_, *robot_, state.values);
  std::vector<DriveParameters> drives = built.drives;
  auto plant = std::make_unique<FlexibleJointPlant>(built.truth, std::move(built.drives), built.options);
  auto nominal_model = std::make_unique<JointErrorModel>(std::move(built.nominal));
  // Everything built: commit.
  compensator_.reset();
  online_.reset();
  nominal_ = std::move(nominal_model);
  drives_ = std::move(drives);
  plant_ = std::move(plant);
  compensator_mode_ = -1;
  built_values_ = state.values;
  built_ = true;
  state.initialized = false;
  ensureCompensator(state);
}

void RobotModel::ensureCompensator(const CoreState& state) {
  const int mode = static_cast<int>(state.values[roles().compensation]);
  if (compensator_ && compensator_mode_ == mode) return;
  EffectMask mask = 0;
  if (mode == 1) mask = nominal_->loadsAnd({"compliance"});
  // Mode 2 corrects every effect of the parameter file: for the shipped RX170 that is the paper's
  // compliance and transmission error; a file extended by discovery brings its effects along.
  if (mode >= 2) mask = nominal_->allEffects();
  compensator_ = std::make_unique<Compensator>(*nominal_, mask);
  online_.reset();
  if (mode == kCompensationDynamic) online_ = std::make_unique<OnlineDynamicCompensator>(*nominal_, drives_);
  compensator_mode_ = mode;
  reference_valid_ = false;
  outputs_valid_ &= ~kReferenceOutputs;
}

Status RobotModel::ensureReference(const CoreState& state, const char* function, ModelLog& log) {
  absorbValueChanges();
  if (reference_valid_) return Status::OK;
  JointVector& q = planned_;
  JointVector velocity = JointVector::Zero(dof_);
  JointVector acceleration = JointVector::Zero(dof_);
  copyJointValues(&state.values[roles().q_desired[0]], q.data(), dof_);
  const bool estimated = live_.has_last_step && state.time > live_.last_step_time;
  if (live_.demo) {
    const double t = state.time - state.start_time;
    demoMove(*robot_, t, q, velocity);
    // The demo's acceleration by a central difference of its velocity (it is smooth; 1e-4 s is far below
    // its 10 s period).
    constexpr double kHalfSpan = 1e-4;
    JointVector q_unused(dof_), before(dof_), after(dof_);
    demoMove(*robot_, t - kHalfSpan, q_unused, before);
    demoMove(*robot_, t + kHalfSpan, q_unused, after);
    acceleration = (after - before) / (2 * kHalfSpan);
  } else if (state.values[roles().use_velocity_inputs] != 0.0) {
    for (int j = 0; j < dof_; ++j) {
      velocity[j] = state.values[roles().qd_desired[j]];
      acceleration[j] = state.values[roles().qdd_desired[j]];
    }
  } else if (estimated) {
    estimateDesiredMotion(live_, state.time, *robot_, q.data(), compensator_mode_ == kCompensationDynamic,
                          velocity.data(), acceleration.data());
  }
  const Status status = compensateReference(state, velocity, acceleration, function, log);
  if (status == Status::OK) reference_valid_ = true;
  return status;
}

// Q_ref and v from Q_theo (planned_) and its velocity and acceleration, by the compensation mode (inlined into
// ensureReference, its one caller, on the step's path).
[[gnu::always_inline]] inline Status RobotModel::compensateReference(const CoreState& state,
                                                                     const JointVector& velocity,
                                                                     const JointVector& acceleration,
                                                                     const char* function, ModelLog& log) {
  const auto refused = [&](const char* what) {
    char text[400];
    std::snprintf(text, sizeof text, "at t = %.9g s: %s", state.time, what);
    return log.fail(Status::Discard, function, text);
  };
  const JointVector& q = planned_;
  const bool with_wrench = state.values[roles().compensate_wrench] != 0.0;
  FixedPointReport report;
  report.converged = true;
  if (compensator_mode_ == 0) {
    copyJoints(q, reference_);
    copyJoints(velocity, reference_velocity_);
  } else if (compensator_mode_ == kCompensationDynamic) {
    const Vector6 wrench = with_wrench ? wrenchOf(state.values, roles()) : Vector6::Zero();
    try {
      report = online_->compensate(live_.dynamic, state.time, q, velocity, acceleration, wrench, reference_,
                                   reference_velocity_, dynamic_after_);
    } catch (const Error& error) {  // unreachable, or an input the filter refuses
      return refused(error.what());
    }
  } else {
    JointContext& ctx = compensation_ctx_;
    copyJoints(q, ctx.q);
    copyJoints(velocity, ctx.velocity);
    ctx.time = state.time;
    if (with_wrench) {
      ctx.tool_wrench = wrenchOf(state.values, roles());
    } else {
      ctx.tool_wrench.setZero();
    }
    try {
      report = compensator_->compensate(ctx, reference_);
    } catch (const UnreachableError& error) {
      return refused(error.what());
    }
    copyJoints(velocity, reference_velocity_);
  }
  if (!report.converged) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "the compensation did not converge at t = %.9g s (residual %g rad after %d iterations)", state.time,
                  report.residual, report.iterations);
    return log.fail(Status::Discard, function, text);
  }
  return Status::OK;
}

// A ModelLog that turns the failure into an exception (for initialisation, which throws).
class ThrowingLog final : public ModelLog {
public:
  Status fail(Status, const char*, const std::string& what) override {
    throw SolverError("the compensation of the initial inputs failed: " + what);
  }
};

void RobotModel::initialize(CoreState& state) {
  ensureModels(state);
  if (state.initialized) return;
  state.time = state.start_time;
  live_.has_last_step = false;
  live_.has_earlier_step = false;
  live_.has_earliest_step = false;
  const double source = state.values[roles().reference];
  live_.demo = source == kReferenceDemo || (source == kReferenceAuto && !live_.desired_inputs_set);
  updateCoreFlags();
  reference_valid_ = false;
  ThrowingLog log;
  ensureReference(state, "initialization", log);
  live_.applied_wrench = wrenchOf(state.values, roles());
  plant_->setToolWrench(live_.applied_wrench);
  plant_->reset(reference_, state.start_time);
  state.initialized = true;
  outputs_valid_ = 0;
}

void RobotModel::startSteps(CoreState&) {
  live_.has_last_step = false;
  live_.has_earlier_step = false;
  live_.has_earliest_step = false;
}

// ------------------------------------------------------------------------------------------------
// Outputs and steps.

Status RobotModel::computeOutputs(CoreState& state, unsigned groups, const char* function, ModelLog& log) {
  absorbValueChanges();
  const unsigned missing = groups & ~outputs_valid_;
  if (missing == 0) return Status::OK;
  if (missing & kReferenceOutputs) {
    const Status status = ensureReference(state, function, log);
    if (status != Status::OK) return status;
    for (int j = 0; j < dof_; ++j) {
      state.values[roles().q_ref[j]] = reference_[j];
      state.values[roles().q_planned[j]] = planned_[j];
    }
  }
  if (missing & (kLinkOutputs | kLinkVelocityOutputs | kMotorOutputs | kToolOutputs | kPredictedOutputs)) {
    computePlantOutputs(state, missing);
  }
  outputs_valid_ |= missing;
  return Status::OK;
}

[[gnu::always_inline]] inline void RobotModel::computePlantOutputs(CoreState& state, unsigned missing) {
  const int n = dof_;
  const double* y = plant_->state();
  const double *q = y, *qd = y + n, *p = y + 2 * n, *pd = y + 3 * n;
  std::vector<double>& values = state.values;
  if (missing & kLinkOutputs) {
    for (int j = 0; j < n; ++j) values[roles().q_link[j]] = q[j];
  }
  if (missing & kLinkVelocityOutputs) {
    for (int j = 0; j < n; ++j) values[roles().qd_link[j]] = qd[j];
  }
  if (missing & kMotorOutputs) {
    for (int j = 0; j < n; ++j) {
      values[roles().q_motor[j]] = p[j];
      values[roles().qd_motor[j]] = pd[j];
      values[roles().dq_actual[j]] = q[j] - p[j];
    }
  }
  if (missing & kToolOutputs) {
    const Eigen::Vector3d tool = toolPosition(*robot_, Eigen::Map<const Eigen::VectorXd>(q, n));
    for (int k = 0; k < 3; ++k) values[roles().tool_position[k]] = tool[k];
  }
  if (missing & kPredictedOutputs) computePredictedOutputs(state, q, qd, p);
}

// The nominal model's link-minus-command error at the plant's link and motor positions.
void RobotModel::computePredictedOutputs(CoreState& state, const double* link, const double* link_velocity,
                                         const double* motor) {
  const int n = dof_;
  JointContext& ctx = prediction_ctx_;
  ctx.q = Eigen::Map<const Eigen::VectorXd>(link, n);
  ctx.velocity = Eigen::Map<const Eigen::VectorXd>(link_velocity, n);
  ctx.time = state.time;
  ctx.tool_wrench = live_.applied_wrench;
  const EffectMask all = nominal_->allEffects();
  computeLoadTorque(*nominal_, all, prediction_ws_, ctx);
  ctx.command = Eigen::Map<const Eigen::VectorXd>(motor, n);
  updateMotorAngles(*nominal_, ctx);
  JointVector dq = JointVector::Zero(n);
  addSelectedJointErrors(*nominal_, all, ctx, dq);
  for (int j = 0; j < n; ++j) state.values[roles().dq_predicted[j]] = dq[j];
}

Status RobotModel::doStep(CoreState& state, double end, const char* function, ModelLog& log) {
  absorbValueChanges();
  FlexibleJointPlant& plant = *plant_;
  const Status reference = ensureReference(state, function, log);
  if (reference != Status::OK) return reference;
  // Compared by bits, or-ed without a branch per value (a wrench of -0 for 0 is applied again, harmlessly).
  std::uint64_t wrench_bits_differ = 0;
  for (int k = 0; k < 6; ++k)
    wrench_bits_differ |= bitsOf(state.values[roles().wrench[k]]) ^ bitsOf(live_.applied_wrench[k]);
  if (wrench_bits_differ != 0) {
    live_.applied_wrench = wrenchOf(state.values, roles());
    plant.setToolWrench(live_.applied_wrench);
  }
  plant.setReference(reference_, reference_velocity_);
  try {
    plant.advance(end);
  } catch (const SolverError& error) {
    return discardStep(function, error.what(), log);
  } catch (const PlantLimitError& error) {
    return discardStep(function, error.what(), log);
  }
  RobotState& s = live_;
  s.has_earliest_step = s.has_earlier_step;
  s.earliest_step_time = s.earlier_step_time;
  s.has_earlier_step = s.has_last_step;
  s.earlier_step_time = s.last_step_time;
  s.has_last_step = true;
  // The three vectors hold dof values from the start (RobotState::atStart, readState).
  copyJointValues(s.earlier_q_desired.data(), s.earliest_q_desired.data(), dof_);
  copyJointValues(s.last_q_desired.data(), s.earlier_q_desired.data(), dof_);
  copyJointValues(&state.values[roles().q_desired[0]], s.last_q_desired.data(), dof_);
  if (compensator_mode_ == kCompensationDynamic) s.dynamic = dynamic_after_;  // this step's sample is done
  s.last_step_time = state.time;
  reference_valid_ = false;
  outputs_valid_ = 0;
  return Status::OK;
}

// CVODE failed (SolverError: the plant stays at its last good time), or the watchdog stopped a run that left
// its joint limits or tracking envelope (PlantLimitError: the plant is at the end, and goes on only from a
// reset or an earlier FMU state). Either way the step is discarded with the reason.
Status RobotModel::discardStep(const char* function, const char* why, ModelLog& log) {
  reference_valid_ = false;
  outputs_valid_ = 0;
  return log.fail(Status::Discard, function, why);
}

}  // namespace jointcomp::fmu
