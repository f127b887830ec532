// The model of the FMU (Reference-FMUs' model.c): the robot and parameter set loaded from the resources,
// the plant and compensator built from the parameters, the reference for the current inputs, the outputs,
// and one communication step. The FMI plumbing around it (the state machine, value access, FMU states,
// logging) is instance.cpp.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "fmu/demo_move.hpp"
#include "fmu/held_steps.hpp"
#include "fmu/robot_models.hpp"
#include "model/common/bits.hpp"
#include "model/common/errors.hpp"
#include "model/common/input_file.hpp"
#include "model/effects/registry.hpp"
#include "model/io/parameter_file.hpp"
#include "model/io/robot_file.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp::fmu {

Instance::Instance(std::string name, const std::string& resource_dir, const std::string& instantiation_token,
                   LogSink sink, void* sink_context, bool logging_on)
    : name_(std::move(name)), sink_(sink), sink_context_(sink_context) {
  // The status categories (logStatusWarning, logStatusDiscard, logStatusError) are what FMI lets an FMU
  // report whether or not debug logging is on: the reason of a Discard or an Error reaches every user, and
  // the importer decides what to show. The one debug category, logCalls, is verbose and is switched on
  // only by name (fmi2SetDebugLogging / fmi3SetDebugLogging), whatever loggingOn says; so is a status
  // category switched off.
  for (bool& on : logging_) on = true;
  logging_[kLogCalls] = false;
  (void)logging_on;
  // An empty token would skip the check: it is never that of any resources.
  if (instantiation_token.empty()) throw Error("the instantiation token is empty");
  FmuResources resources = loadFmuResources(resource_dir, JOINTCOMP_FMU_VERSION, instantiation_token);
  table_ = std::make_shared<const VariableTable>(std::move(resources.table));
  variables_ = table_->variables.data();
  roles_ = &table_->roles;
  count_ = static_cast<std::uint32_t>(table_->variables.size());
  dof_ = table_->dof();
  flags_ = std::make_unique<VariableFlags>(*table_);
  planned_ = JointVector::Zero(dof_);
  // Binds every parameter of the table to its place in the set.
  models_ = std::make_unique<RobotModels>(resources.robot, std::move(resources.parameters), *table_);
  state_ = InstanceState::atStart(*table_);
}

Instance::~Instance() = default;

// ------------------------------------------------------------------------------------------------
// Models, reference, outputs.

bool Instance::fixedParametersDiffer(const std::vector<double>& values) const {
  const RobotModels& m = *models_;
  if (!m.built) return true;
  for (int i = 0; i < static_cast<int>(count_); ++i) {
    if (flags_->fixed_parameter[i] && !sameBits(values[i], m.built_values[i])) return true;
  }
  return false;
}

void Instance::ensureModels() {
  RobotModels& m = *models_;
  if (!fixedParametersDiffer(state_.values)) {
    ensureCompensator();
    return;
  }
  VariableBinding::BoundModels built = m.binding.apply(m.base, *m.robot, state_.values);
  std::vector<DriveParameters> drives = built.drives;
  auto plant = std::make_unique<FlexibleJointPlant>(built.truth, std::move(built.drives), built.options);
  auto nominal_model = std::make_unique<JointErrorModel>(std::move(built.nominal));
  // Everything built: commit.
  m.compensator.reset();
  m.online.reset();
  m.nominal = std::move(nominal_model);
  m.drives = std::move(drives);
  m.plant = std::move(plant);
  m.compensator_mode = -1;
  m.built_values = state_.values;
  m.built = true;
  state_.initialized = false;
  ensureCompensator();
}

void Instance::ensureCompensator() {
  RobotModels& m = *models_;
  const int mode = static_cast<int>(state_.values[roles_->compensation]);
  if (m.compensator && m.compensator_mode == mode) return;
  EffectMask mask = 0;
  if (mode == 1) mask = m.nominal->loadsAnd({"compliance"});
  // Mode 2 corrects every effect of the parameter file: for the shipped RX170 that is the paper's
  // compliance and transmission error; a file extended by discovery brings its effects along.
  if (mode >= 2) mask = m.nominal->allEffects();
  m.compensator = std::make_unique<Compensator>(*m.nominal, mask);
  m.online.reset();
  if (mode == kCompensationDynamic) m.online = std::make_unique<OnlineDynamicCompensator>(*m.nominal, m.drives);
  m.compensator_mode = mode;
  reference_valid_ = false;
  outputs_valid_ &= ~kReferenceOutputs;
}

Status Instance::ensureReference(const char* function) {
  if (reference_valid_) return Status::OK;
  RobotModels& m = *models_;
  JointVector& q = planned_;
  JointVector velocity = JointVector::Zero(dof_);
  JointVector acceleration = JointVector::Zero(dof_);
  copyJointValues(&state_.values[roles_->q_desired[0]], q.data(), dof_);
  const bool estimated = state_.has_last_step && state_.time > state_.last_step_time;
  if (state_.demo) {
    demoMove(*m.robot, state_.time - state_.start_time, q, velocity);
    // The demo's acceleration by a central difference of its velocity (it is smooth; 1e-4 s is far below
    // its 10 s period).
    constexpr double kHalfSpan = 1e-4;
    JointVector q_unused(dof_), before(dof_), after(dof_);
    demoMove(*m.robot, state_.time - state_.start_time - kHalfSpan, q_unused, before);
    demoMove(*m.robot, state_.time - state_.start_time + kHalfSpan, q_unused, after);
    acceleration = (after - before) / (2 * kHalfSpan);
  } else if (state_.values[roles_->use_velocity_inputs] != 0.0) {
    for (int j = 0; j < dof_; ++j) {
      velocity[j] = state_.values[roles_->qd_desired[j]];
      acceleration[j] = state_.values[roles_->qdd_desired[j]];
    }
  } else if (estimated) {
    estimateDesiredMotion(state_, state_.time, *m.robot, q.data(), m.compensator_mode == kCompensationDynamic,
                          velocity.data(), acceleration.data());
  }
  const auto refused = [&](const char* what) {
    char text[400];
    std::snprintf(text, sizeof text, "at t = %.9g s: %s", state_.time, what);
    return fail(Status::Discard, function, text);
  };
  FixedPointReport report;
  report.converged = true;
  if (m.compensator_mode == 0) {
    copyJoints(q, reference_);
    copyJoints(velocity, reference_velocity_);
  } else if (m.compensator_mode == kCompensationDynamic) {
    const Vector6 wrench =
        state_.values[roles_->compensate_wrench] != 0.0 ? wrenchOf(state_.values, *roles_) : Vector6::Zero();
    try {
      report = m.online->compensate(state_.dynamic, state_.time, q, velocity, acceleration, wrench, reference_,
                                    reference_velocity_, dynamic_after_);
    } catch (const Error& error) {  // unreachable, or an input the filter refuses
      return refused(error.what());
    }
  } else {
    JointContext& ctx = m.compensation_ctx;
    copyJoints(q, ctx.q);
    copyJoints(velocity, ctx.velocity);
    ctx.time = state_.time;
    if (state_.values[roles_->compensate_wrench] != 0.0) {
      ctx.tool_wrench = wrenchOf(state_.values, *roles_);
    } else {
      ctx.tool_wrench.setZero();
    }
    try {
      report = m.compensator->compensate(ctx, reference_);
    } catch (const UnreachableError& error) {
      return refused(error.what());
    }
    copyJoints(velocity, reference_velocity_);
  }
  if (!report.converged) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "the compensation did not converge at t = %.9g s (residual %g rad after %d iterations)", state_.time,
                  report.residual, report.iterations);
    return fail(Status::Discard, function, text);
  }
  reference_valid_ = true;
  return Status::OK;
}

void Instance::ensureInitialized() {
  ensureModels();
  if (state_.initialized) return;
  state_.time = state_.start_time;
  state_.has_last_step = false;
  state_.has_earlier_step = false;
  state_.has_earliest_step = false;
  const double source = state_.values[roles_->reference];
  state_.demo = source == kReferenceDemo || (source == kReferenceAuto && !state_.desired_inputs_set);
  reference_valid_ = false;
  if (ensureReference("initialization") != Status::OK) {
    throw SolverError("the compensation of the initial inputs did not converge");
  }
  RobotModels& m = *models_;
  state_.applied_wrench = wrenchOf(state_.values, *roles_);
  m.plant->setToolWrench(state_.applied_wrench);
  m.plant->reset(reference_, state_.start_time);
  state_.initialized = true;
  outputs_valid_ = 0;
}

Status Instance::updateOutputs(const char* function, unsigned groups) {
  RobotModels& m = *models_;
  const unsigned missing = groups & ~outputs_valid_;
  if (missing == 0) return Status::OK;
  if (missing & kReferenceOutputs) {
    const Status status = ensureReference(function);
    if (status != Status::OK) return status;
    for (int j = 0; j < dof_; ++j) {
      state_.values[roles_->q_ref[j]] = reference_[j];
      state_.values[roles_->q_planned[j]] = planned_[j];
    }
  }
  const FlexibleJointPlant& plant = *m.plant;
  if (missing & (kLinkOutputs | kLinkVelocityOutputs | kMotorOutputs | kToolOutputs | kPredictedOutputs)) {
    const int n = dof_;
    const double* y = plant.state();
    const Eigen::Map<const Eigen::VectorXd> q(y, n), qd(y + n, n), p(y + 2 * n, n), pd(y + 3 * n, n);
    if (missing & kLinkOutputs) {
      for (int j = 0; j < dof_; ++j) state_.values[roles_->q_link[j]] = q[j];
    }
    if (missing & kLinkVelocityOutputs) {
      for (int j = 0; j < dof_; ++j) state_.values[roles_->qd_link[j]] = qd[j];
    }
    if (missing & kMotorOutputs) {
      for (int j = 0; j < dof_; ++j) {
        state_.values[roles_->q_motor[j]] = p[j];
        state_.values[roles_->qd_motor[j]] = pd[j];
        state_.values[roles_->dq_actual[j]] = q[j] - p[j];
      }
    }
    if (missing & kToolOutputs) {
      const Eigen::Vector3d tool = toolPosition(*m.robot, q);
      for (int k = 0; k < 3; ++k) state_.values[roles_->tool_position[k]] = tool[k];
    }
    if (missing & kPredictedOutputs) {
      // The nominal model's link-minus-command error at the plant's link and motor positions.
      JointContext& ctx = m.prediction_ctx;
      ctx.q = q;
      ctx.velocity = qd;
      ctx.time = state_.time;
      ctx.tool_wrench = state_.applied_wrench;
      const EffectMask all = m.nominal->allEffects();
      computeLoadTorque(*m.nominal, all, m.prediction_ws, ctx);
      ctx.command = p;
      updateMotorAngles(*m.nominal, ctx);
      JointVector dq = JointVector::Zero(dof_);
      addSelectedJointErrors(*m.nominal, all, ctx, dq);
      for (int j = 0; j < dof_; ++j) state_.values[roles_->dq_predicted[j]] = dq[j];
    }
  }
  outputs_valid_ |= missing;
  return Status::OK;
}

Status Instance::doStep(const char* function, double current_time, double step, double* last_successful_time) noexcept {
  try {
    return doStepUnguarded(function, current_time, step, last_successful_time);
  } catch (...) {
    return internalErrorOfCurrentException(function);
  }
}

// Inlined into doStep, which is then the only frame between the glue and the plant.
[[gnu::always_inline]] inline Status Instance::doStepUnguarded(const char* function, double current_time, double step,
                                                               double* last_successful_time) {
  if (!std::isfinite(current_time) || !std::isfinite(step) || !(step > 0.0)) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "currentCommunicationPoint (%g) and communicationStepSize (%g) must be finite, "
                  "the step size positive",
                  current_time, step);
    return fail(Status::Error, function, text);
  }
  const double tolerance = 1e-9 * std::max(1.0, std::abs(state_.time));
  if (std::abs(current_time - state_.time) > tolerance) {
    char text[160];
    std::snprintf(text, sizeof text, "currentCommunicationPoint %.17g is not the FMU's time %.17g", current_time,
                  state_.time);
    return fail(Status::Error, function, text);
  }
  const double end = current_time + step;
  if (!(end > current_time && end > state_.time)) {
    return fail(Status::Error, function, "the step is too small to advance the time");
  }
  if (state_.stop_time_defined && end > state_.stop_time + tolerance) {
    char text[160];
    std::snprintf(text, sizeof text, "the step to %.17g s goes beyond the stop time %.17g s", end, state_.stop_time);
    return fail(Status::Error, function, text);
  }
  if (!sameBits(current_time, state_.time)) {
    // Within rounding of the FMU's time: the importer's clock is the one to follow.
    state_.time = current_time;
    reference_valid_ = false;
    outputs_valid_ &= ~kReferenceOutputs;
  }
  if (logging_[kLogCalls]) log(Status::OK, "%s(%.17g, %.17g)", function, current_time, step);
  RobotModels& m = *models_;
  FlexibleJointPlant& plant = *m.plant;
  const Status reference = ensureReference(function);
  if (reference != Status::OK) {
    state_.phase = kStepDiscarded;
    if (last_successful_time) *last_successful_time = state_.time;
    return reference;
  }
  // Compared by bits, or-ed without a branch per value (a wrench of -0 for 0 is applied again, harmlessly).
  std::uint64_t wrench_bits_differ = 0;
  for (int k = 0; k < 6; ++k)
    wrench_bits_differ |= bitsOf(state_.values[roles_->wrench[k]]) ^ bitsOf(state_.applied_wrench[k]);
  if (wrench_bits_differ != 0) {
    state_.applied_wrench = wrenchOf(state_.values, *roles_);
    plant.setToolWrench(state_.applied_wrench);
  }
  plant.setReference(reference_, reference_velocity_);
  try {
    plant.advance(end);
  } catch (const SolverError& error) {
    return discardStep(function, error.what(), last_successful_time);
  } catch (const PlantLimitError& error) {
    return discardStep(function, error.what(), last_successful_time);
  }
  state_.has_earliest_step = state_.has_earlier_step;
  state_.earliest_step_time = state_.earlier_step_time;
  state_.has_earlier_step = state_.has_last_step;
  state_.earlier_step_time = state_.last_step_time;
  state_.has_last_step = true;
  // Both vectors hold kDof values from the start (InstanceState::atStart, deserializeState).
  copyJointValues(state_.earlier_q_desired.data(), state_.earliest_q_desired.data(), dof_);
  copyJointValues(state_.last_q_desired.data(), state_.earlier_q_desired.data(), dof_);
  copyJointValues(&state_.values[roles_->q_desired[0]], state_.last_q_desired.data(), dof_);
  if (m.compensator_mode == kCompensationDynamic) state_.dynamic = dynamic_after_;  // this step's sample is done
  state_.last_step_time = state_.time;
  state_.time = end;
  reference_valid_ = false;
  outputs_valid_ = 0;
  if (last_successful_time) *last_successful_time = state_.time;
  return Status::OK;
}

// CVODE failed (SolverError: the plant stays at its last good time), or the watchdog stopped a run that left
// its joint limits or tracking envelope (PlantLimitError: the plant is at the end, and goes on only from a
// reset or an earlier FMU state). Either way the step is discarded with the reason.
// The FMU's time stays at the start of the discarded step: the end of the last successful one (FMI 2.0,
// fmi2LastSuccessfulTime), whatever time the plant stopped at.
Status Instance::discardStep(const char* function, const char* why, double* last_successful_time) {
  state_.phase = kStepDiscarded;
  reference_valid_ = false;
  outputs_valid_ = 0;
  if (last_successful_time) *last_successful_time = state_.time;
  return fail(Status::Discard, function, why);
}

}  // namespace jointcomp::fmu
