// All mutable state of an FMU instance that an FMU state carries, as one value type: getting and setting
// the FMU state is a copy of it (fmi2GetFMUstate, fmi3SetFMUState), and it is written to bytes and read
// back, every field checked, in one place (serializeState, deserializeState). What the instance caches
// (the reference for the current inputs, the outputs computed) is derived from it and not part of it.
#pragma once

#include <cstddef>
#include <vector>

#include "fmu/description/variable_table.hpp"
#include "model/common/types.hpp"
#include "model/plant/dynamic_compensation.hpp"
#include "model/plant/flexible_joint_plant.hpp"

namespace jointcomp::fmu {

// States of the state machine, as bits so that a function can name every state it is allowed in.
enum Phase : unsigned {
  kInstantiated = 1u << 0,
  kInitializationMode = 1u << 1,
  kStepMode = 1u << 2,       // FMI 2: slave initialised, step complete
  kStepDiscarded = 1u << 3,  // the last step was discarded (FMI 2: step failed)
  kTerminated = 1u << 4,
  kErrorState = 1u << 5,  // a call failed in a way that leaves the instance unusable until reset
  kAnyPhase = (1u << 6) - 1,
};
const char* phaseName(unsigned phase);

struct InstanceState {
  unsigned phase = kInstantiated;
  std::vector<double> values;  // every variable, in table order
  double time = 0.0;           // s, the FMU's time
  double start_time = 0.0;
  bool stop_time_defined = false;
  double stop_time = 0.0;
  bool initialized = false;    // the plant holds the state of this instance
  PlantState plant;            // in an FMU state taken after initialisation: the plant's state
  bool has_last_step = false;  // a step was done since initialisation: the velocity can be estimated
  JointVector last_q_desired;  // q_desired and time of that step
  double last_step_time = 0.0;
  bool has_earlier_step = false;  // and a step before that one: the velocity is estimated to second order
  JointVector earlier_q_desired;  // q_desired and time of that earlier step
  double earlier_step_time = 0.0;
  bool has_earliest_step = false;  // and one before that: a step of the inputs shows against the three before
  JointVector earliest_q_desired;  // q_desired and time of that earliest step
  double earliest_step_time = 0.0;
  // compensation = dynamic: the drive inverse filter after the samples of the steps done (not the current one)
  OnlineDynamicState dynamic;
  Vector6 applied_wrench = Vector6::Zero();  // what the plant was last given
  bool desired_inputs_set = false;           // the master set a q_desired or qd_desired input since instantiation
  bool demo = false;                         // the robot follows the built-in demo move (decided at initialisation)

  // An instance as instantiated: the table's start values, time 0.
  static InstanceState atStart(const VariableTable& table);
};

// An FMU state (fmi2FMUstate, fmi3FMUState) is one InstanceState.
struct Snapshot {
  InstanceState state;
};

// The bytes of a state: magic, format, size, the instantiation token and the table's size, the fields,
// and an FNV-1a checksum of everything before it.
std::vector<unsigned char> serializeState(const InstanceState& state, const VariableTable& table);
// Throws jointcomp::Error saying what is wrong: not a jointcomp state, another FMU or format, a wrong
// size or checksum, a value that is not finite or out of its variable's range, bytes after the end.
InstanceState deserializeState(const unsigned char bytes[], std::size_t size, const VariableTable& table);

}  // namespace jointcomp::fmu
