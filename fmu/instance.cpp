#include "fmu/instance.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <limits>
#include <type_traits>
#include <vector>

#include "fmu/demo_move.hpp"
#include "fmu/held_steps.hpp"
#include "fmu/value_blocks.hpp"
#include "fmu/variable_binding.hpp"
#include "model/common/bits.hpp"
#include "model/common/errors.hpp"
#include "model/io/parameter_file.hpp"
#include "model/io/robot_file.hpp"
#include "model/plant/plant_options_by_name.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp::fmu {

using table::kVariables;
namespace role = table::role;

// ------------------------------------------------------------------------------------------------
// What the resources hold and what is built from them.

struct Instance::Models {
  Models(std::shared_ptr<const Robot> loaded_robot, ParameterSet loaded, const std::string& parameter_path)
      : robot(std::move(loaded_robot)),
        base(std::move(loaded)),
        binding(base, *robot, parameter_path),
        compensation_ctx(robot->dof()),
        prediction_ctx(robot->dof()),
        prediction_ws(*robot) {}

  std::shared_ptr<const Robot> robot;
  ParameterSet base;  // the parameter file as shipped
  VariableBinding binding;

  // Built from the fixed parameters (built_values), rebuilt when they change.
  bool built = false;
  std::vector<double> built_values;
  std::unique_ptr<JointErrorModel> nominal;
  std::unique_ptr<FlexibleJointPlant> plant;
  std::vector<DriveParameters> drives;               // the plant's drives: the dynamic mode inverts their tracking
  std::unique_ptr<Compensator> compensator;          // after nominal: it refers to it
  std::unique_ptr<OnlineDynamicCompensator> online;  // compensation = dynamic; refers to nominal too
  int compensator_mode = -1;

  JointContext compensation_ctx;
  JointContext prediction_ctx;
  JointErrorWorkspace prediction_ws;
};

namespace {

constexpr const char* kCategoryNames[] = {"logStatusWarning", "logStatusDiscard", "logStatusError", "logCalls"};
static_assert(sizeof kCategoryNames / sizeof kCategoryNames[0] == table::kLogCategoryCount,
              "the log categories of model.json and of the instance differ");

const char* typeName(table::Type type) {
  switch (type) {
    case table::Type::Real: return "Real (fmi2Real, fmi3Float64)";
    case table::Type::Integer: return "Integer (fmi2Integer, fmi3Int32)";
    case table::Type::Boolean: return "Boolean";
    case table::Type::Enumeration: return "Enumeration (fmi2Integer, fmi3Int64)";
  }
  return "?";
}

unsigned typeBit(table::Type type) {
  switch (type) {
    case table::Type::Real: return kReal;
    case table::Type::Integer: return kInteger;
    case table::Type::Boolean: return kBoolean;
    case table::Type::Enumeration: return kEnumeration;
  }
  return 0;
}

enum SettableReal : unsigned char { kSettableBeforeSteps = 1, kSettableInSteps = 2, kSettableInDemoSteps = 4 };

// A value of any FMI type as the table holds it for the variable at `index`: a Boolean's as 0 or 1
// (fmi2Boolean is an int), the others exactly.
template <typename T>
double tableValue(int index, T value) {
  // A real is a value of a Real variable, or of no variable set will take (no table look-up per value).
  if constexpr (std::is_floating_point_v<T>) return static_cast<double>(value);
  return kVariables[index].type == table::Type::Boolean ? (value != T(0) ? 1.0 : 0.0) : static_cast<double>(value);
}

// What every get and set asks of a variable, by index, looked up once instead of recomputed per value:
// its output group (0 for non-outputs), its type's bit, and whether it is a desired input (q_desired,
// qd_desired or qdd_desired: the inputs the robot follows unless it follows the demo move).
struct VariableFlags {
  unsigned group[table::kCount] = {};
  unsigned type_bit[table::kCount] = {};
  bool desired_input[table::kCount] = {};
  // For reals only, which of set's common cases allow setting it (SettableReal bits): an input or
  // parameter before the steps; an input or tunable parameter in them, and while the robot follows the
  // demo move, not a desired input.
  unsigned char settable_real[table::kCount] = {};
  bool computed[table::kCount] = {};  // an output or the independent variable: computed by the FMU
  // The same, packed in one word per variable for the loops of get and set, which read one word per value
  // instead of one entry of each array (the Packed bits).
  unsigned packed[table::kCount] = {};
  VariableFlags() {
    for (int i = 0; i < table::kCount; ++i) {
      type_bit[i] = typeBit(kVariables[i].type);
      computed[i] = kVariables[i].causality == table::Causality::Output ||
                    kVariables[i].causality == table::Causality::Independent;
    }
    for (int j = 0; j < table::kDof; ++j) {
      group[role::q_link[j]] = 1u;    // kLinkOutputs
      group[role::qd_link[j]] = 32u;  // kLinkVelocityOutputs
      for (int index : {role::q_motor[j], role::qd_motor[j], role::dq_actual[j]}) group[index] = 16u;  // kMotorOutputs
      group[role::dq_predicted[j]] = 4u;  // kPredictedOutputs
      group[role::q_ref[j]] = 8u;         // kReferenceOutputs
      group[role::q_planned[j]] = 8u;
      for (int index : {role::q_desired[j], role::qd_desired[j], role::qdd_desired[j]}) desired_input[index] = true;
    }
    for (int index : role::tool_position) group[index] = 2u;  // kToolOutputs
    for (int i = 0; i < table::kCount; ++i) {
      const table::Variable& v = kVariables[i];
      if (v.type != table::Type::Real) continue;
      const bool input = v.causality == table::Causality::Input;
      const bool parameter = v.causality == table::Causality::Parameter;
      const bool tunable = parameter && v.variability == table::Variability::Tunable;
      if (input || parameter) settable_real[i] |= kSettableBeforeSteps;
      if (input || tunable) settable_real[i] |= kSettableInSteps;
      if ((input && !desired_input[i]) || tunable) settable_real[i] |= kSettableInDemoSteps;
    }
    for (int i = 0; i < table::kCount; ++i) {
      packed[i] = type_bit[i] | (computed[i] ? kPackedComputed : 0u) | group[i] << kPackedGroupShift |
                  unsigned{settable_real[i]} << kPackedSettableShift;
    }
  }
  // The type bits (kReal ... kEnumeration) in bits 0-3, then these.
  static constexpr unsigned kPackedComputed = 1u << 4;
  static constexpr unsigned kPackedGroupShift = 8, kPackedSettableShift = 16;
};
const VariableFlags kFlags;

// The reference parameter's items (modelDescription/enumerations.csv, ReferenceSource).
constexpr double kReferenceAuto = 0.0;
constexpr double kReferenceDemo = 2.0;
constexpr int kCompensationDynamic = 3;  // the CompensationMode item "dynamic"

bool isDesiredInput(int index) { return kFlags.desired_input[index]; }

bool isFixedParameter(int index) {
  return kVariables[index].causality == table::Causality::Parameter &&
         kVariables[index].variability == table::Variability::Fixed;
}

constexpr bool consecutive(const int (&indices)[table::kDof]) {
  for (int j = 0; j < table::kDof; ++j) {
    if (indices[j] != indices[0] + j) return false;
  }
  return true;
}
static_assert(consecutive(role::q_desired), "doStep and ensureReference copy q_desired as one block of the table");

// to = from, the FMU's kDof joints (every joint vector of the instance has them): a copy of known length,
// unrolled, where Eigen's assignment of a vector of run-time size is a call to memcpy or a loop with checks
// for aliasing (20 to 30 instructions for six values, three copies in every step). The two never overlap
// (__restrict), so that the copy goes two values at a time.
void copyJointValues(const double* __restrict from, double* __restrict to) {
  for (int j = 0; j < table::kDof; ++j) to[j] = from[j];
}
void copyJoints(const JointVector& from, JointVector& to) {
  to.resize(table::kDof);
  copyJointValues(from.data(), to.data());
}

Vector6 wrenchOf(const std::vector<double>& values) {
  Vector6 w;
  for (int k = 0; k < 6; ++k) w[k] = values[role::wrench[k]];
  return w;
}

}  // namespace

// ------------------------------------------------------------------------------------------------

Instance::Instance(std::string name, const std::string& resource_dir, LogSink sink, void* sink_context, bool logging_on)
    : name_(std::move(name)), sink_(sink), sink_context_(sink_context) {
  // The status categories (logStatusWarning, logStatusDiscard, logStatusError) are what FMI lets an FMU
  // report whether or not debug logging is on: the reason of a Discard or an Error reaches every user, and
  // the importer decides what to show. The one debug category, logCalls, is verbose and is switched on
  // only by name (fmi2SetDebugLogging / fmi3SetDebugLogging), whatever loggingOn says; so is a status
  // category switched off.
  for (bool& on : logging_) on = true;
  logging_[kLogCalls] = false;
  (void)logging_on;
  std::string dir = resource_dir;
  if (!dir.empty() && dir.back() != '/') dir += '/';
  auto robot = std::make_shared<const Robot>(loadRobotFile(dir + "robot.json"));
  if (robot->name != table::kRobotName || robot->dof() != table::kDof) {
    throw Error(dir + "robot.json describes robot '" + robot->name + "' with " + std::to_string(robot->dof()) +
                " joints; this FMU's variables are for '" + table::kRobotName + "' with " +
                std::to_string(table::kDof));
  }
  const std::string parameter_path = dir + "parameters.json";
  ParameterSet parameters = loadParameterSet(parameter_path, robot);
  if (!parameters.hasDrives()) {
    throw ParameterError(parameter_path + ": no \"plant\" object (drives and controller gains) for the plant");
  }
  // Binds every parameter of the table to its place in the set; the resources must have them all.
  models_ = std::make_unique<Models>(robot, std::move(parameters), parameter_path);
  state_ = InstanceState::atStart();
}

Instance::~Instance() = default;

// ------------------------------------------------------------------------------------------------
// Logging and the state machine.

void Instance::log(Status status, const char* format, ...) {
  LogCategory category = kLogCalls;
  switch (status) {
    case Status::OK: category = kLogCalls; break;
    case Status::Warning: category = kLogWarning; break;
    case Status::Discard: category = kLogDiscard; break;
    case Status::Error:
    case Status::Fatal: category = kLogError; break;
  }
  const bool always = status == Status::Error || status == Status::Fatal;
  if (!sink_ || (!always && !logging_[category])) return;
  char buffer[1024];
  va_list args;
  va_start(args, format);
  const int length = std::vsnprintf(buffer, sizeof buffer, format, args);
  va_end(args);
  std::string message;
  if (length >= 0 && static_cast<std::size_t>(length) >= sizeof buffer) {
    message.resize(static_cast<std::size_t>(length) + 1);
    va_start(args, format);
    std::vsnprintf(message.data(), message.size(), format, args);
    va_end(args);
    message.pop_back();
  } else {
    message = length >= 0 ? buffer : "(message could not be formatted)";
  }
  sink_(sink_context_, status, kCategoryNames[category], message.c_str());
}

void Instance::refuse(const char* function, unsigned phases) {
  std::string list;
  for (unsigned bit = 1; bit < kAnyPhase; bit <<= 1) {
    if (phases & bit) list += std::string(list.empty() ? "" : ", ") + phaseName(bit);
  }
  log(Status::Error, "%s: not allowed in state %s (allowed in: %s)", function, phaseName(state_.phase),
      list.empty() ? "no state of this FMU" : list.c_str());
}

Status Instance::fail(Status status, const char* function, const std::string& what) {
  log(status, "%s: %s", function, what.c_str());
  return status;
}

Status Instance::nullArgument(const char* function, const char* argument) {
  return fail(Status::Error, function, std::string("argument ") + argument + " is a null pointer");
}

Status Instance::internalError(const char* function, const char* what) {
  state_.phase = kErrorState;
  return fail(Status::Error, function, std::string("failed: ") + what + " (the instance must be reset or freed)");
}

Status Instance::unsupported(const char* function, const char* why) { return fail(Status::Error, function, why); }

Status Instance::badArgument(const char* function, const char* why) { return fail(Status::Error, function, why); }

Status Instance::setDebugLogging(const char* function, bool on, std::size_t count, const char* const categories[]) {
  if (count == 0) {
    for (bool& flag : logging_) flag = on;
    return Status::OK;
  }
  if (!categories) return nullArgument(function, "categories");
  bool chosen[kLogCategoryCount] = {};
  for (std::size_t i = 0; i < count; ++i) {
    if (!categories[i]) return nullArgument(function, "categories[i]");
    int found = -1;
    for (int c = 0; c < kLogCategoryCount; ++c) {
      if (std::strcmp(categories[i], kCategoryNames[c]) == 0) found = c;
    }
    if (found < 0) {
      return fail(Status::Error, function,
                  std::string("unknown log category '") + categories[i] +
                      "' (known: logStatusWarning, logStatusDiscard, logStatusError, logCalls)");
    }
    chosen[found] = true;
  }
  for (int c = 0; c < kLogCategoryCount; ++c) {
    if (chosen[c]) logging_[c] = on;
  }
  return Status::OK;
}

// ------------------------------------------------------------------------------------------------
// Models, reference, outputs.

bool Instance::fixedParametersDiffer(const std::vector<double>& values) const {
  const Models& m = *models_;
  if (!m.built) return true;
  for (int i = 0; i < table::kCount; ++i) {
    if (isFixedParameter(i) && !sameBits(values[i], m.built_values[i])) return true;
  }
  return false;
}

void Instance::ensureModels() {
  Models& m = *models_;
  if (!fixedParametersDiffer(state_.values)) {
    ensureCompensator();
    return;
  }
  VariableBinding::Models built = m.binding.apply(m.base, *m.robot, state_.values);
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
  Models& m = *models_;
  const int mode = static_cast<int>(state_.values[role::compensation]);
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
  Models& m = *models_;
  JointVector& q = planned_;
  JointVector velocity = JointVector::Zero(table::kDof);
  JointVector acceleration = JointVector::Zero(table::kDof);
  copyJointValues(&state_.values[role::q_desired[0]], q.data());
  const bool estimated = state_.has_last_step && state_.time > state_.last_step_time;
  if (state_.demo) {
    demoMove(*m.robot, state_.time - state_.start_time, q, velocity);
    // The demo's acceleration by a central difference of its velocity (it is smooth; 1e-4 s is far below
    // its 10 s period).
    constexpr double kHalfSpan = 1e-4;
    JointVector q_unused(table::kDof), before(table::kDof), after(table::kDof);
    demoMove(*m.robot, state_.time - state_.start_time - kHalfSpan, q_unused, before);
    demoMove(*m.robot, state_.time - state_.start_time + kHalfSpan, q_unused, after);
    acceleration = (after - before) / (2 * kHalfSpan);
  } else if (state_.values[role::use_velocity_inputs] != 0.0) {
    for (int j = 0; j < table::kDof; ++j) {
      velocity[j] = state_.values[role::qd_desired[j]];
      acceleration[j] = state_.values[role::qdd_desired[j]];
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
    const Vector6 wrench = state_.values[role::compensate_wrench] != 0.0 ? wrenchOf(state_.values) : Vector6::Zero();
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
    if (state_.values[role::compensate_wrench] != 0.0) {
      ctx.tool_wrench = wrenchOf(state_.values);
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
  const double source = state_.values[role::reference];
  state_.demo = source == kReferenceDemo || (source == kReferenceAuto && !state_.desired_inputs_set);
  reference_valid_ = false;
  if (ensureReference("initialization") != Status::OK) {
    throw SolverError("the compensation of the initial inputs did not converge");
  }
  Models& m = *models_;
  state_.applied_wrench = wrenchOf(state_.values);
  m.plant->setToolWrench(state_.applied_wrench);
  m.plant->reset(reference_, state_.start_time);
  state_.initialized = true;
  outputs_valid_ = 0;
}

Status Instance::updateOutputs(const char* function, unsigned groups) {
  Models& m = *models_;
  const unsigned missing = groups & ~outputs_valid_;
  if (missing == 0) return Status::OK;
  if (missing & kReferenceOutputs) {
    const Status status = ensureReference(function);
    if (status != Status::OK) return status;
    for (int j = 0; j < table::kDof; ++j) {
      state_.values[role::q_ref[j]] = reference_[j];
      state_.values[role::q_planned[j]] = planned_[j];
    }
  }
  const FlexibleJointPlant& plant = *m.plant;
  if (missing & (kLinkOutputs | kLinkVelocityOutputs | kMotorOutputs | kToolOutputs | kPredictedOutputs)) {
    constexpr int n = table::kDof;
    const double* y = plant.state();
    const Eigen::Map<const Eigen::VectorXd> q(y, n), qd(y + n, n), p(y + 2 * n, n), pd(y + 3 * n, n);
    if (missing & kLinkOutputs) {
      for (int j = 0; j < table::kDof; ++j) state_.values[role::q_link[j]] = q[j];
    }
    if (missing & kLinkVelocityOutputs) {
      for (int j = 0; j < table::kDof; ++j) state_.values[role::qd_link[j]] = qd[j];
    }
    if (missing & kMotorOutputs) {
      for (int j = 0; j < table::kDof; ++j) {
        state_.values[role::q_motor[j]] = p[j];
        state_.values[role::qd_motor[j]] = pd[j];
        state_.values[role::dq_actual[j]] = q[j] - p[j];
      }
    }
    if (missing & kToolOutputs) {
      const Eigen::Vector3d tool = toolPosition(*m.robot, q);
      for (int k = 0; k < 3; ++k) state_.values[role::tool_position[k]] = tool[k];
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
      JointVector dq = JointVector::Zero(table::kDof);
      addSelectedJointErrors(*m.nominal, all, ctx, dq);
      for (int j = 0; j < table::kDof; ++j) state_.values[role::dq_predicted[j]] = dq[j];
    }
  }
  outputs_valid_ |= missing;
  return Status::OK;
}

// ------------------------------------------------------------------------------------------------
// Lifecycle.

Status Instance::setupExperiment(const char* function, bool tolerance_defined, double tolerance, double start_time,
                                 bool stop_time_defined, double stop_time) {
  if (!std::isfinite(start_time)) return fail(Status::Error, function, "startTime is not finite");
  if (stop_time_defined && !(std::isfinite(stop_time) && stop_time >= start_time)) {
    return fail(Status::Error, function, "stopTime must be finite and not before startTime");
  }
  if (tolerance_defined) {
    if (!(std::isfinite(tolerance) && tolerance > 0.0)) {
      return fail(Status::Error, function, "the tolerance must be positive and finite");
    }
    // The importer's tolerance becomes the integrator's relative tolerance (and its parameter's value).
    for (int i = 0; i < table::kCount; ++i) {
      const PlantOptionByName* option = models_->binding.option(i);
      if (option && std::strcmp(option->name, "relative_tolerance") == 0) state_.values[i] = tolerance;
    }
  }
  state_.start_time = start_time;
  state_.time = start_time;
  state_.stop_time_defined = stop_time_defined;
  state_.stop_time = stop_time;
  return Status::OK;
}

Status Instance::enterInitializationMode(const char*) {
  state_.phase = kInitializationMode;
  state_.initialized = false;
  state_.time = state_.start_time;
  return Status::OK;
}

Status Instance::exitInitializationMode(const char* function) {
  try {
    ensureInitialized();
  } catch (const std::exception& error) {
    state_.phase = kErrorState;
    return fail(Status::Error, function, std::string("cannot initialise: ") + error.what());
  }
  state_.has_last_step = false;
  state_.has_earlier_step = false;
  state_.has_earliest_step = false;
  state_.phase = kStepMode;
  return Status::OK;
}

Status Instance::internalErrorOfCurrentException(const char* function) noexcept {
  try {
    throw;
  } catch (const std::exception& error) {
    return internalError(function, error.what());
  } catch (...) {
    return internalError(function, "unknown exception");
  }
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
  Models& m = *models_;
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
    wrench_bits_differ |= bitsOf(state_.values[role::wrench[k]]) ^ bitsOf(state_.applied_wrench[k]);
  if (wrench_bits_differ != 0) {
    state_.applied_wrench = wrenchOf(state_.values);
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
  copyJointValues(state_.earlier_q_desired.data(), state_.earliest_q_desired.data());
  copyJointValues(state_.last_q_desired.data(), state_.earlier_q_desired.data());
  copyJointValues(&state_.values[role::q_desired[0]], state_.last_q_desired.data());
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

Status Instance::terminate(const char*) {
  state_.phase = kTerminated;
  return Status::OK;
}

Status Instance::reset(const char*) {
  state_ = InstanceState::atStart();
  reference_valid_ = false;
  outputs_valid_ = 0;
  return Status::OK;
}

// ------------------------------------------------------------------------------------------------
// Values.

namespace {
// Every get and set looks its value references up (twice): a table by value reference, built at compile
// time (no guard of a function-local static, no heap), instead of a binary search.
constexpr std::uint32_t largestValueReference() {
  std::uint32_t largest = 0;
  for (const table::Variable& v : kVariables) largest = v.vr > largest ? v.vr : largest;
  return largest;
}
constexpr std::size_t kIndexTableSize = static_cast<std::size_t>(largestValueReference()) + 1;
static_assert(kIndexTableSize <= 65536 && table::kCount < 32768, "the index table holds 16-bit indices");
constexpr std::array<std::int16_t, kIndexTableSize> kIndexByValueReference = [] {
  std::array<std::int16_t, kIndexTableSize> table{};
  for (std::int16_t& index : table) index = -1;
  for (int i = 0; i < table::kCount; ++i) table[kVariables[i].vr] = static_cast<std::int16_t>(i);
  return table;
}();
}  // namespace

int Instance::indexOf(std::uint32_t vr) { return vr < kIndexTableSize ? kIndexByValueReference[vr] : -1; }

Status Instance::checkValue(const char* function, int index, double value) {
  const table::Variable& v = kVariables[index];
  char text[256];
  switch (v.type) {
    case table::Type::Real:
      if (!std::isfinite(value)) {
        std::snprintf(text, sizeof text, "value %g for %s is not finite", value, describeVariable(index).c_str());
        return fail(Status::Error, function, text);
      }
      break;
    case table::Type::Integer:
    case table::Type::Enumeration:
      if (value != std::floor(value) || value < -2147483648.0 || value > 9.2e18) {
        std::snprintf(text, sizeof text, "value %.17g for %s is not an integer in range", value,
                      describeVariable(index).c_str());
        return fail(Status::Error, function, text);
      }
      if (v.type == table::Type::Enumeration && (value < v.min || value > v.max)) {
        std::snprintf(text, sizeof text, "value %.17g for %s is not an item of its enumeration (%g to %g)", value,
                      describeVariable(index).c_str(), v.min, v.max);
        return fail(Status::Error, function, text);
      }
      break;
    case table::Type::Boolean: break;
  }
  if (value < v.min || value > v.max) {
    std::snprintf(text, sizeof text, "value %.17g for %s is outside [%g, %g]; not set", value,
                  describeVariable(index).c_str(), v.min, v.max);
    return fail(Status::Discard, function, text);
  }
  return Status::OK;
}

template <typename T>
Status Instance::get(const char* function, unsigned types, const std::uint32_t vrs[], std::size_t count,
                     T values[]) noexcept {
  try {
    return getUnguarded(function, types, vrs, count, values);
  } catch (...) {
    return internalErrorOfCurrentException(function);
  }
}

template <typename T>
[[gnu::always_inline]] inline Status Instance::getUnguarded(const char* function, unsigned types,
                                                            const std::uint32_t vrs[], std::size_t count, T values[]) {
  if (count == 0) return Status::OK;
  if (!vrs) return nullArgument(function, "vr[]");
  if (!values) return nullArgument(function, "value[]");
  // From the end of initialisation on, whether a list may be read depends only on the function's types.
  const bool stepping = state_.phase != kInstantiated && state_.phase != kInitializationMode;
  // One packed word per value: the computed ones' bits (kPackedComputed and their groups) are or-ed.
  unsigned computed = 0;
  const bool planned = stepping && get_plan_.matches(vrs, count, types);
  if (planned) {
    computed = get_plan_.computed;
  } else {
    for (std::size_t i = 0; i < count; ++i) {
      const int index = indexOf(vrs[i]);
      if (index < 0)
        return fail(Status::Error, function, "vr " + std::to_string(vrs[i]) + " is not a variable of this FMU");
      const unsigned flags = kFlags.packed[index];
      if (!(flags & types)) {
        return fail(
            Status::Error, function,
            describeVariable(index) + " is of type " + typeName(kVariables[index].type) + "; use its own function");
      }
      if (flags & VariableFlags::kPackedComputed) {
        if (state_.phase == kInstantiated) {
          return fail(Status::Error, function, describeVariable(index) + " is computed from initialization mode on");
        }
        computed |= flags;
      }
    }
    if (stepping && count <= ValuePlan::kCapacity) {
      get_plan_.count = count;
      get_plan_.key = types;
      get_plan_.computed = computed;
      for (std::size_t i = 0; i < count; ++i) {
        get_plan_.vrs[i] = vrs[i];
        get_plan_.index[i] = kIndexByValueReference[vrs[i]];  // checked above
      }
    }
  }
  if (computed & VariableFlags::kPackedComputed) {
    const unsigned groups = (computed >> VariableFlags::kPackedGroupShift) & 0xFFu;
    if (state_.phase == kInitializationMode) {
      try {
        ensureInitialized();
      } catch (const std::exception& error) {
        return fail(Status::Error, function, std::string("cannot compute the initial outputs: ") + error.what());
      }
    }
    if (state_.initialized) {
      const Status status = updateOutputs(function, groups);
      if (status != Status::OK) return status;
    }
    state_.values[role::time] = state_.time;
  }
  // The table holds a Boolean as 0 or 1 (its start values, set's tableValue, a deserialised state's check), so
  // every value converts as it is.
  const double* table_values = state_.values.data();
  if (planned) {
    // Unrolled: the loop's own add, compare and branch were half of its six instructions a value.
#pragma GCC unroll 4
    for (std::size_t i = 0; i < count; ++i) values[i] = static_cast<T>(table_values[get_plan_.index[i]]);
  } else {
    for (std::size_t i = 0; i < count; ++i) values[i] = static_cast<T>(table_values[kIndexByValueReference[vrs[i]]]);
  }
  return Status::OK;
}

Status Instance::checkSettable(const char* function, unsigned types, std::uint32_t vr, int index, double value,
                               bool before_step) {
  if (index < 0) return fail(Status::Error, function, "vr " + std::to_string(vr) + " is not a variable of this FMU");
  const table::Variable& v = kVariables[index];
  if (!(kFlags.type_bit[index] & types)) {
    return fail(Status::Error, function,
                describeVariable(index) + " is of type " + typeName(v.type) + "; use its own function");
  }
  switch (v.causality) {
    case table::Causality::Output:
      return fail(Status::Error, function, describeVariable(index) + " is an output; it cannot be set");
    case table::Causality::Independent:
      return fail(Status::Error, function, describeVariable(index) + " is the independent variable; it cannot be set");
    case table::Causality::Parameter:
      if (!before_step && v.variability != table::Variability::Tunable) {
        return fail(
            Status::Error, function,
            describeVariable(index) + " is a fixed parameter; it can be set only before exitInitializationMode");
      }
      break;
    case table::Causality::Input:
      if (!before_step && state_.demo && isDesiredInput(index)) {
        return fail(Status::Error, function,
                    describeVariable(index) + ": the robot follows the built-in demo move (reference = " +
                        (state_.values[role::reference] == kReferenceDemo
                             ? std::string("demo")
                             : std::string("auto, and no q_desired or qd_desired input was set before the end "
                                           "of initialisation")) +
                        "); set reference = inputs, or the inputs during initialisation");
      }
      break;
  }
  return checkValue(function, index, value);
}

// Inlined into set (the compiler chose a call once set grew: 12 more instructions for every planned set).
[[gnu::always_inline]] inline void Instance::storeReals(const double values[], std::size_t count) {
  double* table_values = state_.values.data();
  bool changed = false;
  if (set_plan_.first >= 0) {
    changed = copyChanged(table_values + set_plan_.first, values, count);
  } else {
    for (std::size_t i = 0; i < count; ++i) {
      double& value = table_values[set_plan_.index[i]];
      changed |= !sameBits(value, values[i]);
      value = values[i];
    }
  }
  if (changed) {
    if (state_.phase == kInitializationMode) state_.initialized = false;
    reference_valid_ = false;
    outputs_valid_ &= ~kReferenceOutputs;
  }
}

template <typename T>
Status Instance::set(const char* function, unsigned types, const std::uint32_t vrs[], std::size_t count,
                     const T values[]) noexcept {
  try {
    return setUnguarded(function, types, vrs, count, values);
  } catch (...) {
    return internalErrorOfCurrentException(function);
  }
}

template <typename T>
[[gnu::always_inline]] inline Status Instance::setUnguarded(const char* function, unsigned types,
                                                            const std::uint32_t vrs[], std::size_t count,
                                                            const T values[]) {
  if (count == 0) return Status::OK;
  if (!vrs) return nullArgument(function, "vr[]");
  if (!values) return nullArgument(function, "value[]");
  const bool before_step = state_.phase == kInstantiated || state_.phase == kInitializationMode;
  // Everything is checked before anything is set: a refused call changes nothing. The common case is a list
  // of reals that may all be set now, finite and within their ranges, with the desired inputs already marked
  // (so that storing is all there is to do: no Boolean to convert, no enumeration such as the compensation
  // mode). It passes on one lookup and three compares per value, and a list seen before on two compares per
  // value; anything else goes through the full checks, which name what is wrong.
  const unsigned char settable_now = !(types & kReal) ? 0
                                     : before_step    ? kSettableBeforeSteps
                                     : state_.demo    ? kSettableInDemoSteps
                                                      : kSettableInSteps;
  const unsigned settable_bits = unsigned{settable_now} << VariableFlags::kPackedSettableShift;
  if constexpr (std::is_same_v<T, double>) {
    if (settable_bits != 0 && state_.desired_inputs_set && set_plan_.matches(vrs, count, settable_bits)) {
      if (allWithin(values, set_plan_.lowest, set_plan_.highest, count)) {
        storeReals(values, count);
        return Status::OK;
      }
      // A value out of its range or not finite: the checks below name it.
    }
  }
  bool common = true;  // every value passed the common case's test
  for (std::size_t i = 0; i < count; ++i) {
    const int index = indexOf(vrs[i]);
    if (index < 0) return checkSettable(function, types, vrs[i], index, 0.0, before_step);
    const double x = tableValue(index, values[i]);
    if ((kFlags.packed[index] & settable_bits) && std::isfinite(x) && x >= kVariables[index].min &&
        x <= kVariables[index].max) {
      continue;
    }
    common = false;
    const Status status = checkSettable(function, types, vrs[i], index, x, before_step);
    if (status != Status::OK) return status;
  }
  if constexpr (std::is_same_v<T, double>) {
    if (common && state_.desired_inputs_set && count <= ValuePlan::kCapacity) {
      set_plan_.count = count;
      set_plan_.key = settable_bits;
      set_plan_.first = kIndexByValueReference[vrs[0]];
      for (std::size_t i = 0; i < count; ++i) {
        const int index = kIndexByValueReference[vrs[i]];  // checked above
        set_plan_.vrs[i] = vrs[i];
        set_plan_.index[i] = static_cast<std::int16_t>(index);
        set_plan_.lowest[i] = std::max(kVariables[index].min, std::numeric_limits<double>::lowest());
        set_plan_.highest[i] = std::min(kVariables[index].max, std::numeric_limits<double>::max());
        if (index != set_plan_.first + static_cast<int>(i)) set_plan_.first = -1;
      }
      storeReals(values, count);
      return Status::OK;
    }
  }
  bool changed = false;
  for (std::size_t i = 0; i < count; ++i) {
    const int index = kIndexByValueReference[vrs[i]];  // checked by the first pass
    const double x = tableValue(index, values[i]);
    if (!state_.desired_inputs_set && isDesiredInput(index)) {
      // Setting a desired input, even to its start value, makes reference = auto follow the inputs.
      state_.desired_inputs_set = true;
      if (state_.phase == kInitializationMode) state_.initialized = false;
    }
    if (sameBits(state_.values[index], x)) continue;
    state_.values[index] = x;
    changed = true;
    if (index == role::compensation) {
      // Another compensation mode: the dynamic mode's drive filter starts afresh from the next sample.
      state_.dynamic.started = false;
      if (models_->built && !before_step) ensureCompensator();
    }
  }
  if (changed) {
    if (state_.phase == kInitializationMode) state_.initialized = false;
    reference_valid_ = false;
    outputs_valid_ &= ~kReferenceOutputs;
  }
  return Status::OK;
}

template Status Instance::get<double>(const char*, unsigned, const std::uint32_t[], std::size_t, double[]) noexcept;
template Status Instance::get<int>(const char*, unsigned, const std::uint32_t[], std::size_t, int[]) noexcept;
template Status Instance::get<long>(const char*, unsigned, const std::uint32_t[], std::size_t, long[]) noexcept;
template Status Instance::get<bool>(const char*, unsigned, const std::uint32_t[], std::size_t, bool[]) noexcept;
template Status Instance::set<double>(const char*, unsigned, const std::uint32_t[], std::size_t,
                                      const double[]) noexcept;
template Status Instance::set<int>(const char*, unsigned, const std::uint32_t[], std::size_t, const int[]) noexcept;
template Status Instance::set<long>(const char*, unsigned, const std::uint32_t[], std::size_t, const long[]) noexcept;
template Status Instance::set<bool>(const char*, unsigned, const std::uint32_t[], std::size_t, const bool[]) noexcept;

Status Instance::noVariablesOfType(const char* function, const char* type_name, const std::uint32_t vrs[],
                                   std::size_t count) {
  if (count == 0) return Status::OK;
  if (!vrs) return nullArgument(function, "valueReferences[]");
  const int index = indexOf(vrs[0]);
  if (index < 0)
    return fail(Status::Error, function, "vr " + std::to_string(vrs[0]) + " is not a variable of this FMU");
  return fail(Status::Error, function,
              describeVariable(index) + " is of type " + typeName(kVariables[index].type) + ", not " + type_name +
                  " (this FMU has no " + type_name + " variables)");
}

Status Instance::dependencies(const char* function, std::uint32_t vr, std::vector<std::uint32_t>& inputs) {
  const int index = indexOf(vr);
  if (index < 0) return fail(Status::Error, function, "vr " + std::to_string(vr) + " is not a variable of this FMU");
  inputs.clear();
  for (int k = table::kDependencyStart[index]; k < table::kDependencyStart[index + 1]; ++k) {
    inputs.push_back(kVariables[table::kDependencies[k]].vr);
  }
  return Status::OK;
}

// ------------------------------------------------------------------------------------------------
// FMU state.

bool Instance::ownsState(const Snapshot* state) const {
  return std::any_of(states_.begin(), states_.end(), [&](const auto& s) { return s.get() == state; });
}

Status Instance::getState(const char* function, Snapshot** state) {
  if (!state) return nullArgument(function, "FMUstate");
  Snapshot* target = *state;
  if (target && !ownsState(target)) {
    return fail(Status::Error, function, "*FMUstate is neither null nor a state of this instance");
  }
  if (!target) {
    states_.push_back(std::make_unique<Snapshot>());
    target = states_.back().get();
  }
  InstanceState& s = target->state;
  s = state_;
  if (s.initialized) s.plant = models_->plant->saveState();
  if (!s.has_last_step) s.last_q_desired = JointVector::Zero(table::kDof);  // not used: written as zeros
  if (!s.has_earlier_step) s.earlier_q_desired = JointVector::Zero(table::kDof);
  if (!s.has_earliest_step) s.earliest_q_desired = JointVector::Zero(table::kDof);
  *state = target;
  return Status::OK;
}

Status Instance::setState(const char* function, const Snapshot* state) {
  if (!state) return nullArgument(function, "FMUstate");
  if (!ownsState(state)) return fail(Status::Error, function, "FMUstate is not a state of this instance");
  const InstanceState& s = state->state;
  const std::vector<double> previous = state_.values;
  state_.values = s.values;
  try {
    if (s.initialized) {
      ensureModels();
      models_->plant->restoreState(s.plant);
    } else if (models_->built) {
      ensureCompensator();
    }
  } catch (const std::exception& error) {
    state_.values = previous;
    return fail(Status::Error, function, std::string("cannot restore the state: ") + error.what());
  }
  state_ = s;
  reference_valid_ = false;
  outputs_valid_ = 0;
  return Status::OK;
}

Status Instance::freeState(const char* function, Snapshot** state) {
  if (!state) return nullArgument(function, "FMUstate");
  if (!*state) return Status::OK;  // freeing nothing is allowed
  const auto found = std::find_if(states_.begin(), states_.end(), [&](const auto& s) { return s.get() == *state; });
  if (found == states_.end()) return fail(Status::Error, function, "*FMUstate is not a state of this instance");
  states_.erase(found);
  *state = nullptr;
  return Status::OK;
}

Status Instance::serializedSize(const char* function, const Snapshot* state, std::size_t* size) {
  if (!state) return nullArgument(function, "FMUstate");
  if (!size) return nullArgument(function, "size");
  if (!ownsState(state)) return fail(Status::Error, function, "FMUstate is not a state of this instance");
  *size = serializeState(state->state).size();
  return Status::OK;
}

Status Instance::serialize(const char* function, const Snapshot* state, unsigned char bytes[], std::size_t size) {
  if (!state) return nullArgument(function, "FMUstate");
  if (!bytes) return nullArgument(function, "serializedState");
  if (!ownsState(state)) return fail(Status::Error, function, "FMUstate is not a state of this instance");
  const std::vector<unsigned char> written = serializeState(state->state);
  if (size != written.size()) {
    return fail(Status::Error, function,
                "size is " + std::to_string(size) + " bytes; the state needs " + std::to_string(written.size()));
  }
  std::memcpy(bytes, written.data(), size);
  return Status::OK;
}

Status Instance::deserialize(const char* function, const unsigned char bytes[], std::size_t size, Snapshot** state) {
  if (!bytes) return nullArgument(function, "serializedState");
  if (!state) return nullArgument(function, "FMUstate");
  if (*state && !ownsState(*state)) {
    return fail(Status::Error, function, "*FMUstate is neither null nor a state of this instance");
  }
  auto s = std::make_unique<Snapshot>();
  try {
    s->state = deserializeState(bytes, size);
  } catch (const Error& error) {
    return fail(Status::Error, function, std::string("cannot read the state: ") + error.what());
  }
  if (*state) {
    **state = std::move(*s);
  } else {
    states_.push_back(std::move(s));
    *state = states_.back().get();
  }
  return Status::OK;
}

}  // namespace jointcomp::fmu
