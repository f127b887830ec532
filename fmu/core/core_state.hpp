// The core's part of an FMU instance's mutable state: the phase of the calling sequence, every variable's
// value, and the time. An FMU state (fmi2GetFMUstate, fmi3GetFMUState) copies it with the model's part.
#pragma once

#include <vector>

#include "fmu/description/variables.hpp"

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

struct CoreState {
  unsigned phase = kInstantiated;
  std::vector<double> values;  // every variable, in table order
  double time = 0.0;           // s, the FMU's time
  double start_time = 0.0;
  bool stop_time_defined = false;
  double stop_time = 0.0;
  bool initialized = false;  // the model holds the state of this instance (Model::initialize)

  // An instance as instantiated: the table's start values, time 0.
  static CoreState atStart(const ModelVariables& table);
};

}  // namespace jointcomp::fmu
