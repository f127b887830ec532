// What the generic FMI core (instance.hpp) asks of the model inside an FMU, and nothing more: the core
// knows variables, phases, values, FMU states and logging; the model knows what the variables mean. As in
// Reference-FMUs, where each model is a model.c of a few functions beside shared FMI plumbing, a new model
// is a variable table and a class implementing these functions (the robot's: fmu/robot/robot_model.hpp).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "fmu/core/core_state.hpp"
#include "fmu/description/variables.hpp"

namespace jointcomp::fmu {

// The status values of FMI 2 and FMI 3 agree for these five.
enum class Status : int { OK = 0, Warning = 1, Discard = 2, Error = 3, Fatal = 4 };

class StateWriter;
class StateReader;

// A model's own part of an FMU state, opaque to the core.
struct ModelState {
  virtual ~ModelState() = default;
};

// What the model says of each variable, once (the core packs it with the variable's type and causality).
struct VariableTraits {
  unsigned output_group = 0;          // an output: the bit of the group its model computes together (0: none)
  bool watched = false;               // setting it calls Model::onSet (a real: only while the model watchesReals())
  bool held_when_restricted = false;  // an input refused in steps while the model restrictsInputs()
};

// How the model reports what went wrong (the core's log, in the category of the status).
class ModelLog {
public:
  virtual Status fail(Status status, const char* function, const std::string& what) = 0;

protected:
  ~ModelLog() = default;
};

class Model {
public:
  virtual ~Model() = default;

  virtual const ModelVariables& table() const = 0;
  virtual VariableTraits traits(int index) const = 0;

  // setupExperiment's tolerance, defined and positive: the model's integrator takes it.
  virtual void setTolerance(CoreState& state, double tolerance) = 0;
  // Initialisation from the current values, when not yet initialised (state.initialized, which the model
  // sets): at exitInitializationMode, or lazily for the first outputs read in initialisation mode. Throws
  // jointcomp::Error saying why it cannot.
  virtual void initialize(CoreState& state) = 0;
  // After initialize, as the instance enters step mode.
  virtual void startSteps(CoreState& state) = 0;
  // The outputs of `groups` (OR-ed VariableTraits::output_group bits) into state.values, from an
  // initialised model. Anything but OK is logged through `log` and returned.
  virtual Status computeOutputs(CoreState& state, unsigned groups, const char* function, ModelLog& log) = 0;
  // One communication step from state.time to `end` (> state.time); the core then sets state.time = end on
  // OK. A step the model cannot finish returns Discard (logged, with the reason).
  virtual Status doStep(CoreState& state, double end, const char* function, ModelLog& log) = 0;
  // A watched variable was set (`changed`: to another value); before_step: in initialisation or before.
  virtual void onSet(CoreState& state, int index, bool changed, bool before_step) = 0;
  // Why a held input cannot be set now (restrictsInputs()).
  virtual std::string restriction(const CoreState& state) const = 0;
  // The instance was reset to its start values.
  virtual void reset(const CoreState& state) = 0;

  // FMU states: the model's part, taken, restored, written and read.
  virtual std::unique_ptr<ModelState> newState() const = 0;
  virtual void saveState(const CoreState& state, ModelState& into) const = 0;
  // Throws jointcomp::Error when the state cannot be restored (then nothing changed).
  virtual void restoreState(const CoreState& state, const ModelState& from) = 0;
  // A number the size of the model's state follows from (the robot's joints), in the state's header.
  virtual std::uint32_t stateShape() const = 0;
  virtual void writeState(const CoreState& state, const ModelState& from, StateWriter& writer) const = 0;
  // Throws jointcomp::Error naming the field that is wrong.
  virtual void readState(const CoreState& state, ModelState& into, StateReader& reader) const = 0;

  // Read by the core's fast paths of set, inline.
  bool watchesReals() const { return watches_reals_; }
  bool restrictsInputs() const { return restricts_inputs_; }
  // The core's note that an input or tunable parameter changed value: the model's caches that follow from
  // the values are stale (inline: the fast path of set calls it).
  void valuesChanged() { values_changed_ = true; }

protected:
  bool watches_reals_ = true;
  bool restricts_inputs_ = false;
  bool values_changed_ = true;
};

}  // namespace jointcomp::fmu
