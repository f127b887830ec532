// The FMU's instance, generic over its model and independent of the FMI version: the state machine of the
// calling sequence, logging, every variable's value by value reference (with plans for the lists importers
// repeat), and FMU states with their bytes. What the variables mean is the model's (model.hpp; the robot's
// is fmu/robot/robot_model.hpp). fmi2_functions.cpp and fmi3_functions.cpp are thin glue over it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "fmu/core/core_state.hpp"
#include "fmu/core/model.hpp"
#include "fmu/core/state_bytes.hpp"
#include "fmu/core/variable_flags.hpp"
#include "fmu/description/variables.hpp"

namespace jointcomp::fmu {

// The log channel to the importer: the FMI glue turns these into its logger's calls.
using LogSink = void (*)(void* context, Status status, const char* category, const char* message);

// The model of the FMU from its resources folder (the robot's: robot_model.cpp). Throws jointcomp::Error with
// a message naming what is at fault: missing or malformed resources, resources that are not those
// `instantiation_token` was made for (another export's modelDescription.xml), a model the FMU cannot run.
std::unique_ptr<Model> loadModel(const std::string& resource_dir, const std::string& instantiation_token);

class Instance final : private ModelLog {
public:
  // The instance of `model` (loadModel).
  Instance(std::string name, std::unique_ptr<Model> model, LogSink sink, void* sink_context, bool logging_on);
  ~Instance();
  Instance(const Instance&) = delete;
  Instance& operator=(const Instance&) = delete;

  const std::string& name() const { return name_; }
  unsigned phase() const { return state_.phase; }
  double time() const { return state_.time; }

  // State machine: true when the call is allowed in the current phase; otherwise logs why (naming the
  // function, the phase and the phases it is allowed in) and returns false. Every FMI function starts here,
  // so the test is inline and only the refusal is a call.
  bool allowed(const char* function, unsigned phases) {
    if ((state_.phase & phases) != 0) return true;
    refuse(function, phases);  // known to be false here, so the glue keeps no registers for after it
    return false;
  }

  // Logging, in the category of the status (logStatusError, logStatusDiscard, logStatusWarning; OK goes
  // to logCalls). Errors are always reported; the others when logging is on for their category.
  void log(Status status, const char* format, ...) __attribute__((format(printf, 3, 4)));
  bool logsCalls() const { return logging_[kLogCalls]; }
  // Log an error naming the function and return Status::Error: for what the FMU does not provide, and
  // for arguments the glue checks itself.
  Status unsupported(const char* function, const char* why);
  Status badArgument(const char* function, const char* why);
  // For typed functions of types the FMU has no variables of (fmi3GetFloat32, ...): OK for no value
  // references, otherwise an error naming the first one and its real type.
  Status noVariablesOfType(const char* function, const char* type_name, const std::uint32_t vrs[], std::size_t count);
  // Inputs the variable depends on directly (fmi3GetVariableDependencies), by value reference.
  Status dependencies(const char* function, std::uint32_t vr, std::vector<std::uint32_t>& inputs);
  Status setDebugLogging(const char* function, bool on, std::size_t count, const char* const categories[]);
  // Logs an error naming the function and the argument and returns Status::Error.
  Status nullArgument(const char* function, const char* argument);
  // For exceptions that reach the FMI boundary: logs, enters the error state, returns Status::Error.
  Status internalError(const char* function, const char* what);

  // Lifecycle.
  Status setupExperiment(const char* function, bool tolerance_defined, double tolerance, double start_time,
                         bool stop_time_defined, double stop_time);
  Status enterInitializationMode(const char* function);
  Status exitInitializationMode(const char* function);
  // doStep, get and set never throw: an exception inside becomes internalError's Error, as in the FMI glue's
  // catch. Declared noexcept, so that the glue's call to them needs no exception region and is a jump.
  Status doStep(const char* function, double current_time, double step, double* last_successful_time) noexcept;
  Status terminate(const char* function);
  Status reset(const char* function);

  // Values by value reference. `types` lists the variable types the calling function may access
  // (fmi2GetInteger: Integer and Enumeration; fmi3GetInt64: Enumeration; ...). Values are converted
  // exactly (all integers of the table fit a double).
  template <typename T>
  Status get(const char* function, unsigned types, const std::uint32_t vrs[], std::size_t count, T values[]) noexcept;
  template <typename T>
  Status set(const char* function, unsigned types, const std::uint32_t vrs[], std::size_t count,
             const T values[]) noexcept;
  // Index into the table of a value reference, -1 if unknown (value references are the table's indices).
  int indexOf(std::uint32_t vr) const { return vr < count_ ? static_cast<int>(vr) : -1; }
  const ModelVariables& table() const { return *table_; }

  // FMU state. Snapshots belong to the instance that made them (or deserialised them); a pointer that
  // is not one of this instance's live snapshots is refused without being dereferenced.
  Status getState(const char* function, Snapshot** state);  // *state: nullptr or one to overwrite
  Status setState(const char* function, const Snapshot* state);
  Status freeState(const char* function, Snapshot** state);
  Status serializedSize(const char* function, const Snapshot* state, std::size_t* size);
  Status serialize(const char* function, const Snapshot* state, unsigned char bytes[], std::size_t size);
  Status deserialize(const char* function, const unsigned char bytes[], std::size_t size, Snapshot** state);

  // For FMI 2's fmi2GetRealStatus(fmi2LastSuccessfulTime): after a Discard, the start of the discarded step.
  double lastSuccessfulTime() const { return state_.time; }
  // fmi2GetBooleanStatus(fmi2Terminated), fmi3DoStep's terminateSimulation: after a discarded step the FMU
  // cannot go on (only a reset or an earlier FMU state can), so it asks the importer to terminate.
  bool wantsToTerminate() const { return state_.phase == kStepDiscarded; }

private:
  [[gnu::cold]] void refuse(const char* function, unsigned phases);  // allowed's refusal: logs why
  // The bodies of doStep, get and set, which may throw; the public functions catch.
  Status doStepUnguarded(const char* function, double current_time, double step, double* last_successful_time);
  template <typename T>
  Status getUnguarded(const char* function, unsigned types, const std::uint32_t vrs[], std::size_t count, T values[]);
  template <typename T>
  Status setUnguarded(const char* function, unsigned types, const std::uint32_t vrs[], std::size_t count,
                      const T values[]);
  // internalError for the exception being handled (called in a catch (...) block).
  Status internalErrorOfCurrentException(const char* function) noexcept;
  enum LogCategory { kLogWarning, kLogDiscard, kLogError, kLogCalls, kLogCategoryCount };

  bool ownsState(const Snapshot* state) const;
  // The model initialised from the current values, when it is not (initialisation mode, lazily).
  void ensureInitialized() {
    if (!state_.initialized) model_->initialize(state_);
  }
  Status fail(Status status, const char* function, const std::string& what) override;
  // Checks of doStep's arguments against the FMU's time and stop time: OK, or the refusal naming them.
  Status checkStep(const char* function, double current_time, double step);
  Status checkValue(const char* function, int index, double value);
  // Every check of set for one value (`index`: of `vr`, -1 if unknown): OK, or the refusal naming it.
  Status checkSettable(const char* function, unsigned types, std::uint32_t vr, int index, double value,
                       bool before_step);

  // A list of value references resolved once. Importers pass the same list at every step (the inputs to
  // set, the outputs to read), so get and set look its variables up and check what does not depend on the
  // values (unknown references, types, causality, the phase) at the first call, and reuse that while the
  // list, compared by content, and `key`, what those checks depended on, are the same.
  struct ValuePlan {
    static constexpr std::size_t kCapacity = 64;  // a longer list takes the general path every time
    std::size_t count = 0;                        // 0: no plan
    unsigned key = 0;
    unsigned computed = 0;  // get: the packed flags of its computed variables, or-ed (which outputs to update)
    std::uint32_t vrs[kCapacity];
    std::int16_t index[kCapacity];  // into the table and the instance's values
    int first = -1;                 // set: index[0] when the indices are consecutive (one block), else -1
    // set: each variable's range as finite bounds, so that one pair of compares also refuses NaN and infinity.
    double lowest[kCapacity], highest[kCapacity];
    bool matches(const std::uint32_t list[], std::size_t n, unsigned k) const {
      return n == count && k == key && std::memcmp(list, vrs, n * sizeof vrs[0]) == 0;
    }
  };

  // Stores the reals of set_plan_'s list, which passed set's checks, and drops what depended on them.
  void storeReals(const double values[], std::size_t count);

  std::string name_;
  std::unique_ptr<Model> model_;
  const ModelVariables* table_ = nullptr;  // the model's variables
  const Variable* variables_ = nullptr;    // table_->variables.data()
  std::uint32_t count_ = 0;                // variables
  int time_index_ = -1;                    // the independent variable
  std::unique_ptr<VariableFlags> flags_;
  LogSink sink_;
  void* sink_context_;
  bool logging_[kLogCategoryCount];

  CoreState state_;                // the core's part of what an FMU state carries (the model holds its own)
  ValuePlan get_plan_, set_plan_;  // the last lists of get and of set (of reals)

  std::vector<std::unique_ptr<Snapshot>> states_;
};

}  // namespace jointcomp::fmu
