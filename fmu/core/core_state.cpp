#include "fmu/core/core_state.hpp"

namespace jointcomp::fmu {

const char* phaseName(unsigned phase) {
  switch (phase) {
    case kInstantiated: return "Instantiated";
    case kInitializationMode: return "InitializationMode";
    case kStepMode: return "StepMode";
    case kStepDiscarded: return "StepDiscarded";
    case kTerminated: return "Terminated";
    case kErrorState: return "Error";
    default: return "?";
  }
}

CoreState CoreState::atStart(const ModelVariables& table) {
  CoreState state;
  state.values.reserve(table.variables.size());
  for (const Variable& v : table.variables) state.values.push_back(v.start);
  return state;
}

}  // namespace jointcomp::fmu
