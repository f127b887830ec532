// FMI 3.0 for Co-Simulation: every function of the FMI 3.0 API (declared in fmi3_api.hpp, written from
// the standard document), exported over fmu/core/instance.hpp. What this FMU does not provide (model exchange,
// scheduled execution, event mode, early return, clocks, configuration mode, derivatives, types it has no
// variables of) returns fmi3Error with a message; an importer asking for event mode or early return at
// instantiation is told that they are not used, and the instance works without them.
#include <cctype>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include "fmu/core/instance.hpp"
#include "fmu/fmi3_api.hpp"

// Declared in fmi3_api.hpp with default visibility: the only symbols the binary exports.
#define FMI3_EXPORT extern "C"

namespace {

using jointcomp::fmu::Instance;
using jointcomp::fmu::loadModel;
using jointcomp::fmu::Snapshot;
using jointcomp::fmu::Status;
namespace fmu = jointcomp::fmu;

static_assert(sizeof(fmi3Int64) == sizeof(long), "fmi3Int64 is a long on this platform");

constexpr std::uint64_t kInstanceMagic = 0x6a63666d69334930ULL;  // "jcfmi3I0"
constexpr const char* kCoSimulationOnly = "this FMU is for co-simulation only (no model exchange)";
constexpr const char* kNoEventMode = "this FMU has no event mode (hasEventMode is false)";
constexpr const char* kNoClocks = "this FMU has no clocks";

// Phases in which each group of functions is allowed (FMI 3.0, 4.2, the co-simulation state machine).
constexpr unsigned kGetPhases = fmu::kInstantiated | fmu::kInitializationMode | fmu::kStepMode | fmu::kStepDiscarded |
                                fmu::kTerminated | fmu::kErrorState;
constexpr unsigned kSetPhases = fmu::kInstantiated | fmu::kInitializationMode | fmu::kStepMode;
constexpr unsigned kStatePhases = fmu::kAnyPhase & ~fmu::kErrorState;

struct Component {
  std::uint64_t magic = kInstanceMagic;
  fmi3InstanceEnvironment environment = nullptr;
  fmi3LogMessageCallback log = nullptr;  // may be null: then nothing is logged
  std::unique_ptr<Instance> instance;
  ~Component() { magic = 0; }
};

void logToImporter(void* context, Status status, const char* category, const char* message) {
  const auto* component = static_cast<const Component*>(context);
  if (component->log) component->log(component->environment, static_cast<fmi3Status>(status), category, message);
}

fmi3Status to3(Status status) { return static_cast<fmi3Status>(status); }

Component* componentOf(fmi3Instance c) {
  auto* component = static_cast<Component*>(c);
  return component && component->magic == kInstanceMagic ? component : nullptr;
}

bool blank(const char* text) {
  for (const char* p = text; *p; ++p) {
    if (!std::isspace(static_cast<unsigned char>(*p))) return false;
  }
  return true;
}

fmi3Instance refuse(fmi3InstanceEnvironment environment, fmi3LogMessageCallback log, const char* function,
                    const std::string& why) {
  if (log) log(environment, fmi3Error, "logStatusError", (std::string(function) + ": " + why).c_str());
  return nullptr;
}

}  // namespace

#define FMI3_BEGIN(function, phases)                     \
  Component* component = componentOf(instance);          \
  if (!component) return fmi3Error;                      \
  Instance& self = *component->instance;                 \
  if (!self.allowed(function, phases)) return fmi3Error; \
  try {
#define FMI3_END(function)                                         \
  }                                                                \
  catch (const std::exception& error) {                            \
    return to3(self.internalError(function, error.what()));        \
  }                                                                \
  catch (...) {                                                    \
    return to3(self.internalError(function, "unknown exception")); \
  }
#define FMI3_UNSUPPORTED(function, why)         \
  Component* component = componentOf(instance); \
  if (!component) return fmi3Error;             \
  return to3(component->instance->unsupported(function, why));
// Scalars only: one value per value reference.
#define FMI3_CHECK_COUNT(function)                                                                             \
  if (nValues != nValueReferences) {                                                                           \
    return to3(self.badArgument(function, "nValues must equal nValueReferences (all variables are scalars)")); \
  }

// Typed access for the types the FMU has variables of, and refusal for the others.
#define FMI3_GET(Name, Type, types)                                                                       \
  FMI3_EXPORT fmi3Status fmi3Get##Name(fmi3Instance instance, const fmi3ValueReference valueReferences[], \
                                       size_t nValueReferences, Type values[], size_t nValues) {          \
    FMI3_BEGIN("fmi3Get" #Name, kGetPhases)                                                               \
    FMI3_CHECK_COUNT("fmi3Get" #Name)                                                                     \
    return to3(self.get("fmi3Get" #Name, types, valueReferences, nValueReferences, values));              \
    FMI3_END("fmi3Get" #Name)                                                                             \
  }
#define FMI3_SET(Name, Type, types)                                                                       \
  FMI3_EXPORT fmi3Status fmi3Set##Name(fmi3Instance instance, const fmi3ValueReference valueReferences[], \
                                       size_t nValueReferences, const Type values[], size_t nValues) {    \
    FMI3_BEGIN("fmi3Set" #Name, kSetPhases)                                                               \
    FMI3_CHECK_COUNT("fmi3Set" #Name)                                                                     \
    return to3(self.set("fmi3Set" #Name, types, valueReferences, nValueReferences, values));              \
    FMI3_END("fmi3Set" #Name)                                                                             \
  }
#define FMI3_NO_GET(Name, Type)                                                                           \
  FMI3_EXPORT fmi3Status fmi3Get##Name(fmi3Instance instance, const fmi3ValueReference valueReferences[], \
                                       size_t nValueReferences, Type values[], size_t nValues) {          \
    FMI3_BEGIN("fmi3Get" #Name, kGetPhases)                                                               \
    FMI3_CHECK_COUNT("fmi3Get" #Name)                                                                     \
    if (nValueReferences > 0 && !values) return to3(self.nullArgument("fmi3Get" #Name, "values[]"));      \
    return to3(self.noVariablesOfType("fmi3Get" #Name, #Name, valueReferences, nValueReferences));        \
    FMI3_END("fmi3Get" #Name)                                                                             \
  }
#define FMI3_NO_SET(Name, Type)                                                                           \
  FMI3_EXPORT fmi3Status fmi3Set##Name(fmi3Instance instance, const fmi3ValueReference valueReferences[], \
                                       size_t nValueReferences, const Type values[], size_t nValues) {    \
    FMI3_BEGIN("fmi3Set" #Name, kSetPhases)                                                               \
    FMI3_CHECK_COUNT("fmi3Set" #Name)                                                                     \
    if (nValueReferences > 0 && !values) return to3(self.nullArgument("fmi3Set" #Name, "values[]"));      \
    return to3(self.noVariablesOfType("fmi3Set" #Name, #Name, valueReferences, nValueReferences));        \
    FMI3_END("fmi3Set" #Name)                                                                             \
  }

// ---- Common functions ------------------------------------------------------------------------------

FMI3_EXPORT const char* fmi3GetVersion(void) { return "3.0"; }

FMI3_EXPORT fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                                           const fmi3String categories[]) {
  FMI3_BEGIN("fmi3SetDebugLogging", fmu::kAnyPhase)
  return to3(self.setDebugLogging("fmi3SetDebugLogging", loggingOn, nCategories, categories));
  FMI3_END("fmi3SetDebugLogging")
}

FMI3_EXPORT fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                                      fmi3String resourcePath, fmi3Boolean visible,
                                                      fmi3Boolean loggingOn,
                                                      fmi3InstanceEnvironment instanceEnvironment,
                                                      fmi3LogMessageCallback logMessage) {
  (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
  return refuse(instanceEnvironment, logMessage, "fmi3InstantiateModelExchange", kCoSimulationOnly);
}

FMI3_EXPORT fmi3Instance
fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
                            fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                            fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
                            size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
                            fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate) {
  (void)visible, (void)requiredIntermediateVariables;
  (void)intermediateUpdate;  // never called: the FMU provides no intermediate update
  const char* function = "fmi3InstantiateCoSimulation";
  if (!instanceName || blank(instanceName)) {
    return refuse(instanceEnvironment, logMessage, function, "instanceName must be a non-empty string");
  }
  if (!instantiationToken) {
    return refuse(instanceEnvironment, logMessage, function,
                  "instantiationToken is null; it is the instantiationToken of modelDescription.xml");
  }
  if (!resourcePath) {
    return refuse(instanceEnvironment, logMessage, function,
                  "resourcePath is null; the FMU needs its resources/ folder");
  }
  try {
    auto component = std::make_unique<Component>();
    component->environment = instanceEnvironment;
    component->log = logMessage;
    component->instance = std::make_unique<Instance>(instanceName, loadModel(resourcePath, instantiationToken),
                                                     logToImporter, component.get(), loggingOn);
    Instance& self = *component->instance;
    // Declined, gracefully: the instance works without them.
    if (eventModeUsed) {
      self.log(Status::Warning, "%s: eventModeUsed is true but %s; fmi3DoStep never asks for event handling", function,
               kNoEventMode);
    }
    if (earlyReturnAllowed) {
      self.log(Status::Warning, "%s: earlyReturnAllowed is true but this FMU never returns early from fmi3DoStep",
               function);
    }
    if (nRequiredIntermediateVariables > 0) {
      self.log(Status::Warning,
               "%s: %zu intermediate variables requested but this FMU provides no intermediate "
               "update (providesIntermediateUpdate is false); they are ignored",
               function, nRequiredIntermediateVariables);
    }
    return component.release();
  } catch (const std::exception& error) {
    return refuse(instanceEnvironment, logMessage, function, error.what());
  } catch (...) {
    return refuse(instanceEnvironment, logMessage, function, "unknown exception");
  }
}

FMI3_EXPORT fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible,
    fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage,
    fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption,
    fmi3UnlockPreemptionCallback unlockPreemption) {
  (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
  (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
  return refuse(instanceEnvironment, logMessage, "fmi3InstantiateScheduledExecution",
                "this FMU is for co-simulation only (no scheduled execution)");
}

FMI3_EXPORT void fmi3FreeInstance(fmi3Instance instance) { delete componentOf(instance); }

FMI3_EXPORT fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                                   fmi3Float64 tolerance, fmi3Float64 startTime,
                                                   fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
  const char* function = "fmi3EnterInitializationMode";
  FMI3_BEGIN(function, fmu::kInstantiated)
  const Status status =
      self.setupExperiment(function, toleranceDefined, tolerance, startTime, stopTimeDefined, stopTime);
  if (status != Status::OK) return to3(status);
  return to3(self.enterInitializationMode(function));
  FMI3_END(function)
}

FMI3_EXPORT fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
  FMI3_BEGIN("fmi3ExitInitializationMode", fmu::kInitializationMode)
  return to3(self.exitInitializationMode("fmi3ExitInitializationMode"));
  FMI3_END("fmi3ExitInitializationMode")
}

FMI3_EXPORT fmi3Status fmi3EnterEventMode(fmi3Instance instance){FMI3_UNSUPPORTED("fmi3EnterEventMode", kNoEventMode)}

FMI3_EXPORT fmi3Status fmi3Terminate(fmi3Instance instance) {
  FMI3_BEGIN("fmi3Terminate", fmu::kStepMode | fmu::kStepDiscarded)
  return to3(self.terminate("fmi3Terminate"));
  FMI3_END("fmi3Terminate")
}

FMI3_EXPORT fmi3Status fmi3Reset(fmi3Instance instance) {
  FMI3_BEGIN("fmi3Reset", fmu::kAnyPhase)
  return to3(self.reset("fmi3Reset"));
  FMI3_END("fmi3Reset")
}

FMI3_NO_GET(Float32, fmi3Float32)
FMI3_GET(Float64, fmi3Float64, fmu::kReal)
FMI3_NO_GET(Int8, fmi3Int8)
FMI3_NO_GET(UInt8, fmi3UInt8)
FMI3_NO_GET(Int16, fmi3Int16)
FMI3_NO_GET(UInt16, fmi3UInt16)
FMI3_GET(Int32, fmi3Int32, fmu::kInteger)
FMI3_NO_GET(UInt32, fmi3UInt32)
FMI3_GET(Int64, fmi3Int64, fmu::kEnumeration)
FMI3_NO_GET(UInt64, fmi3UInt64)
FMI3_GET(Boolean, fmi3Boolean, fmu::kBoolean)
FMI3_NO_GET(String, fmi3String)

FMI3_EXPORT fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                     size_t nValueReferences, size_t valueSizes[], fmi3Binary values[],
                                     size_t nValues) {
  FMI3_BEGIN("fmi3GetBinary", kGetPhases)
  FMI3_CHECK_COUNT("fmi3GetBinary")
  if (nValueReferences > 0 && (!values || !valueSizes)) return to3(self.nullArgument("fmi3GetBinary", "values[]"));
  return to3(self.noVariablesOfType("fmi3GetBinary", "Binary", valueReferences, nValueReferences));
  FMI3_END("fmi3GetBinary")
}

FMI3_EXPORT fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, fmi3Clock values[]) {
  (void)valueReferences, (void)nValueReferences, (void)values;
  FMI3_UNSUPPORTED("fmi3GetClock", kNoClocks)
}

FMI3_NO_SET(Float32, fmi3Float32)
FMI3_SET(Float64, fmi3Float64, fmu::kReal)
FMI3_NO_SET(Int8, fmi3Int8)
FMI3_NO_SET(UInt8, fmi3UInt8)
FMI3_NO_SET(Int16, fmi3Int16)
FMI3_NO_SET(UInt16, fmi3UInt16)
FMI3_SET(Int32, fmi3Int32, fmu::kInteger)
FMI3_NO_SET(UInt32, fmi3UInt32)
FMI3_SET(Int64, fmi3Int64, fmu::kEnumeration)
FMI3_NO_SET(UInt64, fmi3UInt64)
FMI3_SET(Boolean, fmi3Boolean, fmu::kBoolean)
FMI3_NO_SET(String, fmi3String)

FMI3_EXPORT fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                     size_t nValueReferences, const size_t valueSizes[], const fmi3Binary values[],
                                     size_t nValues) {
  FMI3_BEGIN("fmi3SetBinary", kSetPhases)
  FMI3_CHECK_COUNT("fmi3SetBinary")
  if (nValueReferences > 0 && (!values || !valueSizes)) return to3(self.nullArgument("fmi3SetBinary", "values[]"));
  return to3(self.noVariablesOfType("fmi3SetBinary", "Binary", valueReferences, nValueReferences));
  FMI3_END("fmi3SetBinary")
}

FMI3_EXPORT fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Clock values[]) {
  (void)valueReferences, (void)nValueReferences, (void)values;
  FMI3_UNSUPPORTED("fmi3SetClock", kNoClocks)
}

FMI3_EXPORT fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference,
                                                           size_t* nDependencies) {
  FMI3_BEGIN("fmi3GetNumberOfVariableDependencies", fmu::kAnyPhase)
  if (!nDependencies) return to3(self.nullArgument("fmi3GetNumberOfVariableDependencies", "nDependencies"));
  std::vector<std::uint32_t> inputs;
  const Status status = self.dependencies("fmi3GetNumberOfVariableDependencies", valueReference, inputs);
  if (status == Status::OK) *nDependencies = inputs.size();
  return to3(status);
  FMI3_END("fmi3GetNumberOfVariableDependencies")
}

FMI3_EXPORT fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                                   size_t elementIndicesOfDependent[],
                                                   fmi3ValueReference independents[],
                                                   size_t elementIndicesOfIndependents[],
                                                   fmi3DependencyKind dependencyKinds[], size_t nDependencies) {
  const char* function = "fmi3GetVariableDependencies";
  FMI3_BEGIN(function, fmu::kAnyPhase)
  std::vector<std::uint32_t> inputs;
  const Status status = self.dependencies(function, dependent, inputs);
  if (status != Status::OK) return to3(status);
  if (nDependencies != inputs.size()) {
    return to3(self.badArgument(function, "nDependencies must be what fmi3GetNumberOfVariableDependencies returned"));
  }
  if (nDependencies > 0 &&
      (!elementIndicesOfDependent || !independents || !elementIndicesOfIndependents || !dependencyKinds)) {
    return to3(self.nullArgument(function, "an output array"));
  }
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    elementIndicesOfDependent[k] = 0;  // scalars
    independents[k] = inputs[k];
    elementIndicesOfIndependents[k] = 0;
    dependencyKinds[k] = fmi3Dependent;
  }
  return fmi3OK;
  FMI3_END(function)
}

FMI3_EXPORT fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState* FMUState) {
  FMI3_BEGIN("fmi3GetFMUState", kStatePhases)
  return to3(self.getState("fmi3GetFMUState", reinterpret_cast<Snapshot**>(FMUState)));
  FMI3_END("fmi3GetFMUState")
}

FMI3_EXPORT fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
  FMI3_BEGIN("fmi3SetFMUState", fmu::kAnyPhase)
  return to3(self.setState("fmi3SetFMUState", static_cast<const Snapshot*>(FMUState)));
  FMI3_END("fmi3SetFMUState")
}

FMI3_EXPORT fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState* FMUState) {
  FMI3_BEGIN("fmi3FreeFMUState", fmu::kAnyPhase)
  return to3(self.freeState("fmi3FreeFMUState", reinterpret_cast<Snapshot**>(FMUState)));
  FMI3_END("fmi3FreeFMUState")
}

FMI3_EXPORT fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t* size) {
  FMI3_BEGIN("fmi3SerializedFMUStateSize", fmu::kAnyPhase)
  return to3(self.serializedSize("fmi3SerializedFMUStateSize", static_cast<const Snapshot*>(FMUState), size));
  FMI3_END("fmi3SerializedFMUStateSize")
}

FMI3_EXPORT fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                             size_t size) {
  FMI3_BEGIN("fmi3SerializeFMUState", fmu::kAnyPhase)
  return to3(self.serialize("fmi3SerializeFMUState", static_cast<const Snapshot*>(FMUState), serializedState, size));
  FMI3_END("fmi3SerializeFMUState")
}

FMI3_EXPORT fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                               fmi3FMUState* FMUState) {
  FMI3_BEGIN("fmi3DeserializeFMUState", fmu::kAnyPhase)
  return to3(
      self.deserialize("fmi3DeserializeFMUState", serializedState, size, reinterpret_cast<Snapshot**>(FMUState)));
  FMI3_END("fmi3DeserializeFMUState")
}

FMI3_EXPORT fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                                    size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns,
                                                    const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
                                                    size_t nSensitivity) {
  (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed, (void)sensitivity,
      (void)nSensitivity;
  FMI3_UNSUPPORTED("fmi3GetDirectionalDerivative", "directional derivatives are not provided")
}

FMI3_EXPORT fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                                size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns,
                                                const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[],
                                                size_t nSensitivity) {
  (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed, (void)sensitivity,
      (void)nSensitivity;
  FMI3_UNSUPPORTED("fmi3GetAdjointDerivative", "adjoint derivatives are not provided")
}

FMI3_EXPORT fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance){
    FMI3_UNSUPPORTED("fmi3EnterConfigurationMode", "this FMU has no structural parameters")}

FMI3_EXPORT fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance){
    FMI3_UNSUPPORTED("fmi3ExitConfigurationMode", "this FMU has no structural parameters")}

FMI3_EXPORT fmi3Status
    fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                           fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[]) {
  (void)valueReferences, (void)nValueReferences, (void)intervals, (void)qualifiers;
  FMI3_UNSUPPORTED("fmi3GetIntervalDecimal", kNoClocks)
}

FMI3_EXPORT fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                               size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                               fmi3IntervalQualifier qualifiers[]) {
  (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions, (void)qualifiers;
  FMI3_UNSUPPORTED("fmi3GetIntervalFraction", kNoClocks)
}

FMI3_EXPORT fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                           size_t nValueReferences, fmi3Float64 shifts[]) {
  (void)valueReferences, (void)nValueReferences, (void)shifts;
  FMI3_UNSUPPORTED("fmi3GetShiftDecimal", kNoClocks)
}

FMI3_EXPORT fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                            size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
  (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
  FMI3_UNSUPPORTED("fmi3GetShiftFraction", kNoClocks)
}

FMI3_EXPORT fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                              size_t nValueReferences, const fmi3Float64 intervals[]) {
  (void)valueReferences, (void)nValueReferences, (void)intervals;
  FMI3_UNSUPPORTED("fmi3SetIntervalDecimal", kNoClocks)
}

FMI3_EXPORT fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                               size_t nValueReferences, const fmi3UInt64 counters[],
                                               const fmi3UInt64 resolutions[]) {
  (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
  FMI3_UNSUPPORTED("fmi3SetIntervalFraction", kNoClocks)
}

FMI3_EXPORT fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                           size_t nValueReferences, const fmi3Float64 shifts[]) {
  (void)valueReferences, (void)nValueReferences, (void)shifts;
  FMI3_UNSUPPORTED("fmi3SetShiftDecimal", kNoClocks)
}

FMI3_EXPORT fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                            size_t nValueReferences, const fmi3UInt64 counters[],
                                            const fmi3UInt64 resolutions[]) {
  (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
  FMI3_UNSUPPORTED("fmi3SetShiftFraction", kNoClocks)
}

FMI3_EXPORT fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance){
    FMI3_UNSUPPORTED("fmi3EvaluateDiscreteStates", kNoEventMode)}

FMI3_EXPORT fmi3Status
    fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean* discreteStatesNeedUpdate,
                             fmi3Boolean* terminateSimulation, fmi3Boolean* nominalsOfContinuousStatesChanged,
                             fmi3Boolean* valuesOfContinuousStatesChanged, fmi3Boolean* nextEventTimeDefined,
                             fmi3Float64* nextEventTime) {
  (void)discreteStatesNeedUpdate, (void)terminateSimulation, (void)nominalsOfContinuousStatesChanged,
      (void)valuesOfContinuousStatesChanged, (void)nextEventTimeDefined, (void)nextEventTime;
  FMI3_UNSUPPORTED("fmi3UpdateDiscreteStates", kNoEventMode)
}

// ---- Model exchange: not provided ----------------------------------------------------------------------

FMI3_EXPORT fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance){
    FMI3_UNSUPPORTED("fmi3EnterContinuousTimeMode", kCoSimulationOnly)}

FMI3_EXPORT fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi3Boolean* enterEventMode, fmi3Boolean* terminateSimulation) {
  (void)noSetFMUStatePriorToCurrentPoint, (void)enterEventMode, (void)terminateSimulation;
  FMI3_UNSUPPORTED("fmi3CompletedIntegratorStep", kCoSimulationOnly)
}

FMI3_EXPORT fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
  (void)time;
  FMI3_UNSUPPORTED("fmi3SetTime", kCoSimulationOnly)
}

FMI3_EXPORT fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                               size_t nContinuousStates) {
  (void)continuousStates, (void)nContinuousStates;
  FMI3_UNSUPPORTED("fmi3SetContinuousStates", kCoSimulationOnly)
}

FMI3_EXPORT fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                                         size_t nContinuousStates) {
  (void)derivatives, (void)nContinuousStates;
  FMI3_UNSUPPORTED("fmi3GetContinuousStateDerivatives", kCoSimulationOnly)
}

FMI3_EXPORT fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                              size_t nEventIndicators) {
  (void)eventIndicators, (void)nEventIndicators;
  FMI3_UNSUPPORTED("fmi3GetEventIndicators", kCoSimulationOnly)
}

FMI3_EXPORT fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                               size_t nContinuousStates) {
  (void)continuousStates, (void)nContinuousStates;
  FMI3_UNSUPPORTED("fmi3GetContinuousStates", kCoSimulationOnly)
}

FMI3_EXPORT fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                                         size_t nContinuousStates) {
  (void)nominals, (void)nContinuousStates;
  FMI3_UNSUPPORTED("fmi3GetNominalsOfContinuousStates", kCoSimulationOnly)
}

FMI3_EXPORT fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t* nEventIndicators) {
  (void)nEventIndicators;
  FMI3_UNSUPPORTED("fmi3GetNumberOfEventIndicators", kCoSimulationOnly)
}

FMI3_EXPORT fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t* nContinuousStates) {
  (void)nContinuousStates;
  FMI3_UNSUPPORTED("fmi3GetNumberOfContinuousStates", kCoSimulationOnly)
}

// ---- Co-simulation -------------------------------------------------------------------------------------

FMI3_EXPORT fmi3Status fmi3EnterStepMode(fmi3Instance instance){
    FMI3_UNSUPPORTED("fmi3EnterStepMode",
                     "there is no event mode to leave (hasEventMode is false): "
                     "fmi3ExitInitializationMode enters step mode")}

FMI3_EXPORT fmi3Status
    fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                             const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues) {
  (void)valueReferences, (void)nValueReferences, (void)orders, (void)values, (void)nValues;
  FMI3_UNSUPPORTED("fmi3GetOutputDerivatives", "output derivatives are not provided (maxOutputDerivativeOrder is 0)")
}

FMI3_EXPORT fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                                  fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                  fmi3Boolean* eventHandlingNeeded, fmi3Boolean* terminateSimulation,
                                  fmi3Boolean* earlyReturn, fmi3Float64* lastSuccessfulTime) {
  (void)noSetFMUStatePriorToCurrentPoint;
  FMI3_BEGIN("fmi3DoStep", fmu::kStepMode)
  if (!eventHandlingNeeded) return to3(self.nullArgument("fmi3DoStep", "eventHandlingNeeded"));
  if (!terminateSimulation) return to3(self.nullArgument("fmi3DoStep", "terminateSimulation"));
  if (!earlyReturn) return to3(self.nullArgument("fmi3DoStep", "earlyReturn"));
  if (!lastSuccessfulTime) return to3(self.nullArgument("fmi3DoStep", "lastSuccessfulTime"));
  *eventHandlingNeeded = false;
  *earlyReturn = false;
  const Status status = self.doStep("fmi3DoStep", currentCommunicationPoint, communicationStepSize, lastSuccessfulTime);
  *terminateSimulation = self.wantsToTerminate();  // a discarded step: only a reset or an earlier state goes on
  return to3(status);
  FMI3_END("fmi3DoStep")
}

// ---- Scheduled execution: not provided -----------------------------------------------------------------

FMI3_EXPORT fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                                  fmi3Float64 activationTime) {
  (void)clockReference, (void)activationTime;
  FMI3_UNSUPPORTED("fmi3ActivateModelPartition", "this FMU is for co-simulation only (no scheduled execution)")
}
