#include "fmu/core/instance.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <limits>
#include <type_traits>
#include <vector>

#include "fmu/core/value_blocks.hpp"
#include "model/common/bits.hpp"
#include "model/common/errors.hpp"

namespace jointcomp::fmu {

namespace {

constexpr const char* kCategoryNames[] = {"logStatusWarning", "logStatusDiscard", "logStatusError", "logCalls"};

const char* typeName(VariableType type) {
  switch (type) {
    case VariableType::Real: return "Real (fmi2Real, fmi3Float64)";
    case VariableType::Integer: return "Integer (fmi2Integer, fmi3Int32)";
    case VariableType::Boolean: return "Boolean";
    case VariableType::Enumeration: return "Enumeration (fmi2Integer, fmi3Int64)";
  }
  return "?";
}

// A value of any FMI type as the table holds it for the variable at `index`: a Boolean's as 0 or 1
// (fmi2Boolean is an int), the others exactly.
template <typename T>
double tableValue(const Variable* variables, int index, T value) {
  // A real is a value of a Real variable, or of no variable set will take (no table look-up per value).
  if constexpr (std::is_floating_point_v<T>) return static_cast<double>(value);
  return variables[index].type == VariableType::Boolean ? (value != T(0) ? 1.0 : 0.0) : static_cast<double>(value);
}

}  // namespace

Instance::Instance(std::string name, std::unique_ptr<Model> model, LogSink sink, void* sink_context, bool logging_on)
    : name_(std::move(name)), model_(std::move(model)), sink_(sink), sink_context_(sink_context) {
  // The status categories (logStatusWarning, logStatusDiscard, logStatusError) are what FMI lets an FMU
  // report whether or not debug logging is on: the reason of a Discard or an Error reaches every user, and
  // the importer decides what to show. The one debug category, logCalls, is verbose and is switched on
  // only by name (fmi2SetDebugLogging / fmi3SetDebugLogging), whatever loggingOn says; so is a status
  // category switched off.
  for (bool& on : logging_) on = true;
  logging_[kLogCalls] = false;
  (void)logging_on;
  table_ = &model_->table();
  variables_ = table_->variables.data();
  count_ = static_cast<std::uint32_t>(table_->variables.size());
  for (std::uint32_t i = 0; i < count_; ++i) {
    if (variables_[i].causality == Causality::Independent) time_index_ = static_cast<int>(i);
  }
  if (time_index_ < 0) throw Error("FMU variables: the table has no independent variable (time)");
  if (count_ > 32767) throw Error("FMU variables: more than 32767 variables");  // ValuePlan's int16 indices
  flags_ = std::make_unique<VariableFlags>(*model_);
  state_ = CoreState::atStart(*table_);
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
    model_->setTolerance(state_, tolerance);
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
    model_->startSteps(state_);
  } catch (const std::exception& error) {
    state_.phase = kErrorState;
    return fail(Status::Error, function, std::string("cannot initialise: ") + error.what());
  }
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

Status Instance::terminate(const char*) {
  state_.phase = kTerminated;
  return Status::OK;
}

Status Instance::reset(const char*) {
  state_ = CoreState::atStart(*table_);
  model_->reset(state_);
  return Status::OK;
}

// ------------------------------------------------------------------------------------------------
// Values.

Status Instance::checkValue(const char* function, int index, double value) {
  const Variable& v = variables_[index];
  char text[256];
  switch (v.type) {
    case VariableType::Real:
      if (!std::isfinite(value)) {
        std::snprintf(text, sizeof text, "value %g for %s is not finite", value,
                      describeVariable(*table_, index).c_str());
        return fail(Status::Error, function, text);
      }
      break;
    case VariableType::Integer:
    case VariableType::Enumeration:
      if (value != std::floor(value) || value < -2147483648.0 || value > 9.2e18) {
        std::snprintf(text, sizeof text, "value %.17g for %s is not an integer in range", value,
                      describeVariable(*table_, index).c_str());
        return fail(Status::Error, function, text);
      }
      if (v.type == VariableType::Enumeration && (value < v.min || value > v.max)) {
        std::snprintf(text, sizeof text, "value %.17g for %s is not an item of its enumeration (%g to %g)", value,
                      describeVariable(*table_, index).c_str(), v.min, v.max);
        return fail(Status::Error, function, text);
      }
      break;
    case VariableType::Boolean: break;
  }
  if (value < v.min || value > v.max) {
    std::snprintf(text, sizeof text, "value %.17g for %s is outside [%g, %g]; not set", value,
                  describeVariable(*table_, index).c_str(), v.min, v.max);
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
      const unsigned flags = flags_->packed[index];
      if (!(flags & types)) {
        return fail(Status::Error, function,
                    describeVariable(*table_, index) + " is of type " + typeName(variables_[index].type) +
                        "; use its own function");
      }
      if (flags & VariableFlags::kPackedComputed) {
        if (state_.phase == kInstantiated) {
          return fail(Status::Error, function,
                      describeVariable(*table_, index) + " is computed from initialization mode on");
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
        get_plan_.index[i] = static_cast<std::int16_t>(vrs[i]);  // checked above
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
      const Status status = model_->computeOutputs(state_, groups, function, *this);
      if (status != Status::OK) return status;
    }
    state_.values[time_index_] = state_.time;
  }
  // The table holds a Boolean as 0 or 1 (its start values, set's tableValue, a deserialised state's check), so
  // every value converts as it is.
  const double* table_values = state_.values.data();
  if (planned) {
    // Unrolled: the loop's own add, compare and branch were half of its six instructions a value.
#pragma GCC unroll 4
    for (std::size_t i = 0; i < count; ++i) values[i] = static_cast<T>(table_values[get_plan_.index[i]]);
  } else {
    for (std::size_t i = 0; i < count; ++i) values[i] = static_cast<T>(table_values[vrs[i]]);
  }
  return Status::OK;
}

Status Instance::checkSettable(const char* function, unsigned types, std::uint32_t vr, int index, double value,
                               bool before_step) {
  if (index < 0) return fail(Status::Error, function, "vr " + std::to_string(vr) + " is not a variable of this FMU");
  const Variable& v = variables_[index];
  if (!((flags_->packed[index] & 0xFu) & types)) {
    return fail(Status::Error, function,
                describeVariable(*table_, index) + " is of type " + typeName(v.type) + "; use its own function");
  }
  switch (v.causality) {
    case Causality::Output:
      return fail(Status::Error, function, describeVariable(*table_, index) + " is an output; it cannot be set");
    case Causality::Independent:
      return fail(Status::Error, function,
                  describeVariable(*table_, index) + " is the independent variable; it cannot be set");
    case Causality::Parameter:
      if (!before_step && v.variability != Variability::Tunable) {
        return fail(Status::Error, function,
                    describeVariable(*table_, index) +
                        " is a fixed parameter; it can be set only before exitInitializationMode");
      }
      break;
    case Causality::Input:
      if (!before_step && model_->restrictsInputs() && flags_->held_when_restricted[index]) {
        return fail(Status::Error, function, describeVariable(*table_, index) + ": " + model_->restriction(state_));
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
    model_->valuesChanged();
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
  // of reals that may all be set now, finite and within their ranges, none of them watched by the model any
  // more (so that storing is all there is to do: no Boolean to convert, no enumeration, nothing to tell the
  // model but that values changed). It passes on one lookup and three compares per value, and a list seen before on two
  // compares per value; anything else goes through the full checks, which name what is wrong.
  const unsigned char settable_now = !(types & kReal)            ? 0
                                     : before_step               ? kSettableBeforeSteps
                                     : model_->restrictsInputs() ? kSettableInRestrictedSteps
                                                                 : kSettableInSteps;
  const unsigned settable_bits = unsigned{settable_now} << VariableFlags::kPackedSettableShift;
  if constexpr (std::is_same_v<T, double>) {
    if (settable_bits != 0 && !model_->watchesReals() && set_plan_.matches(vrs, count, settable_bits)) {
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
    const double x = tableValue(variables_, index, values[i]);
    if ((flags_->packed[index] & settable_bits) && std::isfinite(x) && x >= variables_[index].min &&
        x <= variables_[index].max) {
      continue;
    }
    common = false;
    const Status status = checkSettable(function, types, vrs[i], index, x, before_step);
    if (status != Status::OK) return status;
  }
  if constexpr (std::is_same_v<T, double>) {
    if (common && !model_->watchesReals() && count <= ValuePlan::kCapacity) {
      set_plan_.count = count;
      set_plan_.key = settable_bits;
      set_plan_.first = static_cast<int>(vrs[0]);
      for (std::size_t i = 0; i < count; ++i) {
        const int index = vrs[i];  // checked above
        set_plan_.vrs[i] = vrs[i];
        set_plan_.index[i] = static_cast<std::int16_t>(index);
        set_plan_.lowest[i] = std::max(variables_[index].min, std::numeric_limits<double>::lowest());
        set_plan_.highest[i] = std::min(variables_[index].max, std::numeric_limits<double>::max());
        if (index != set_plan_.first + static_cast<int>(i)) set_plan_.first = -1;
      }
      storeReals(values, count);
      return Status::OK;
    }
  }
  bool changed = false;
  for (std::size_t i = 0; i < count; ++i) {
    const int index = vrs[i];  // checked by the first pass
    const double x = tableValue(variables_, index, values[i]);
    const bool differs = !sameBits(state_.values[index], x);
    state_.values[index] = x;
    changed |= differs;
    // Told even of the same value: setting an input may be what counts (a robot's desired inputs).
    if (flags_->watched[index]) model_->onSet(state_, index, differs, before_step);
  }
  if (changed) {
    if (state_.phase == kInitializationMode) state_.initialized = false;
    model_->valuesChanged();
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
              describeVariable(*table_, index) + " is of type " + typeName(variables_[index].type) + ", not " +
                  type_name + " (this FMU has no " + type_name + " variables)");
}

Status Instance::dependencies(const char* function, std::uint32_t vr, std::vector<std::uint32_t>& inputs) {
  const int index = indexOf(vr);
  if (index < 0) return fail(Status::Error, function, "vr " + std::to_string(vr) + " is not a variable of this FMU");
  inputs.clear();
  for (int input : variables_[index].depends) inputs.push_back(variables_[input].vr);
  return Status::OK;
}

// ------------------------------------------------------------------------------------------------
// Steps.

// Inlined into doStep (its one caller): the checks are a few compares; only a refusal is a call.
[[gnu::always_inline]] inline Status Instance::checkStep(const char* function, double current_time, double step) {
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
  return Status::OK;
}

Status Instance::doStep(const char* function, double current_time, double step, double* last_successful_time) noexcept {
  try {
    return doStepUnguarded(function, current_time, step, last_successful_time);
  } catch (...) {
    return internalErrorOfCurrentException(function);
  }
}

// Inlined into doStep, which is then the only frame between the glue and the model.
[[gnu::always_inline]] inline Status Instance::doStepUnguarded(const char* function, double current_time, double step,
                                                               double* last_successful_time) {
  const Status checked = checkStep(function, current_time, step);
  if (checked != Status::OK) return checked;
  if (!sameBits(current_time, state_.time)) {
    // Within rounding of the FMU's time: the importer's clock is the one to follow.
    state_.time = current_time;
    model_->valuesChanged();
  }
  if (logging_[kLogCalls]) log(Status::OK, "%s(%.17g, %.17g)", function, current_time, step);
  const double end = current_time + step;
  const Status status = model_->doStep(state_, end, function, *this);
  // After a discarded step the FMU's time stays at its start: the end of the last successful one (FMI 2.0,
  // fmi2LastSuccessfulTime), whatever time the model stopped at.
  if (status == Status::OK) {
    state_.time = end;
  } else if (status == Status::Discard) {
    state_.phase = kStepDiscarded;
  }
  if (last_successful_time) *last_successful_time = state_.time;
  return status;
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
  target->core = state_;
  if (!target->model) target->model = model_->newState();
  model_->saveState(state_, *target->model);
  *state = target;
  return Status::OK;
}

Status Instance::setState(const char* function, const Snapshot* state) {
  if (!state) return nullArgument(function, "FMUstate");
  if (!ownsState(state)) return fail(Status::Error, function, "FMUstate is not a state of this instance");
  try {
    model_->restoreState(state->core, *state->model);
  } catch (const std::exception& error) {
    return fail(Status::Error, function, std::string("cannot restore the state: ") + error.what());
  }
  state_ = state->core;
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
  *size = serializeState(*state, *model_).size();
  return Status::OK;
}

Status Instance::serialize(const char* function, const Snapshot* state, unsigned char bytes[], std::size_t size) {
  if (!state) return nullArgument(function, "FMUstate");
  if (!bytes) return nullArgument(function, "serializedState");
  if (!ownsState(state)) return fail(Status::Error, function, "FMUstate is not a state of this instance");
  const std::vector<unsigned char> written = serializeState(*state, *model_);
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
    deserializeState(bytes, size, *model_, *s);
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
