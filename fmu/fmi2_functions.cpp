// FMI 2.0 for Co-Simulation: every function of the FMI 2.0 API (declared in fmi2_api.hpp, written from
// the standard document), exported over fmu/core/instance.hpp. Functions of model exchange, and co-simulation
// functions this FMU does not provide (canInterpolateInputs, maxOutputDerivativeOrder and asynchronous
// steps are declared false / 0), return fmi2Error with a message, as the standard asks.
#include <cctype>
#include <cstddef>
#include <cstring>
#include <exception>
#include <memory>
#include <string>

#include "fmu/core/instance.hpp"
#include "fmu/fmi2_api.hpp"

// Declared in fmi2_api.hpp with default visibility: the only symbols the binary exports.
#define FMI2_EXPORT extern "C"

namespace {

using jointcomp::fmu::Instance;
using jointcomp::fmu::loadModel;
using jointcomp::fmu::Snapshot;
using jointcomp::fmu::Status;
namespace fmu = jointcomp::fmu;

static_assert(sizeof(fmi2ValueReference) == sizeof(std::uint32_t), "value references are 32 bits");
static_assert(sizeof(fmi2Integer) == sizeof(int), "fmi2Integer is an int");

constexpr std::uint64_t kComponentMagic = 0x6a63666d69324330ULL;  // "jcfmi2C0"
constexpr const char* kCoSimulationOnly = "this FMU is for co-simulation only (no model exchange)";

// Phases in which each group of functions is allowed (FMI 2.0, 4.2.4, the co-simulation state machine).
constexpr unsigned kGetPhases =
    fmu::kInitializationMode | fmu::kStepMode | fmu::kStepDiscarded | fmu::kTerminated | fmu::kErrorState;
constexpr unsigned kSetPhases = fmu::kInstantiated | fmu::kInitializationMode | fmu::kStepMode;
constexpr unsigned kStatePhases = fmu::kAnyPhase & ~fmu::kErrorState;
constexpr unsigned kStatusPhases = fmu::kStepMode | fmu::kStepDiscarded | fmu::kTerminated;

struct Component {
  std::uint64_t magic = kComponentMagic;
  fmi2CallbackFunctions callbacks{};
  std::string name;
  std::unique_ptr<Instance> instance;
  ~Component() { magic = 0; }
};

// The FMI 2 logger formats the message like printf and expands #<type><vr># references: escape both.
std::string escaped(const char* message) {
  std::string text;
  for (const char* p = message; *p; ++p) {
    if (*p == '%') text += '%';
    if (*p == '#') text += '#';
    text += *p;
  }
  return text;
}

void logToImporter(void* context, Status status, const char* category, const char* message) {
  const auto* component = static_cast<const Component*>(context);
  if (!component->callbacks.logger) return;
  component->callbacks.logger(component->callbacks.componentEnvironment, component->name.c_str(),
                              static_cast<fmi2Status>(status), category, escaped(message).c_str());
}

fmi2Status to2(Status status) { return static_cast<fmi2Status>(status); }

Component* componentOf(fmi2Component c) {
  auto* component = static_cast<Component*>(c);
  return component && component->magic == kComponentMagic ? component : nullptr;
}

// "file:///path", "file:/path" or "file://localhost/path", percent-encoded, to a file-system path.
bool pathFromUri(const char* uri, std::string& path, std::string& why) {
  std::string text = uri;
  if (text.size() < 5 || std::strncmp(text.c_str(), "file:", 5) != 0) {
    // Scheme names are case-insensitive.
    std::string scheme = text.substr(0, 5);
    for (char& ch : scheme) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    if (scheme != "file:") {
      why = "only file: URIs are supported";
      return false;
    }
  }
  std::string rest = text.substr(5);
  if (rest.rfind("//", 0) == 0) {
    const std::size_t slash = rest.find('/', 2);
    const std::string host = rest.substr(2, slash == std::string::npos ? std::string::npos : slash - 2);
    if (!host.empty() && host != "localhost") {
      why = "the resources are on another host ('" + host + "')";
      return false;
    }
    rest = slash == std::string::npos ? "/" : rest.substr(slash);
  }
  if (rest.empty() || rest[0] != '/') {
    why = "the path is not absolute";
    return false;
  }
  path.clear();
  for (std::size_t i = 0; i < rest.size(); ++i) {
    if (rest[i] != '%') {
      path += rest[i];
      continue;
    }
    auto hex = [](char ch) -> int {
      if (ch >= '0' && ch <= '9') return ch - '0';
      if (ch >= 'a' && ch <= 'f') return ch - 'a' + 10;
      if (ch >= 'A' && ch <= 'F') return ch - 'A' + 10;
      return -1;
    };
    if (i + 2 >= rest.size() || hex(rest[i + 1]) < 0 || hex(rest[i + 2]) < 0) {
      why = "a '%' is not followed by two hexadecimal digits";
      return false;
    }
    const int byte = hex(rest[i + 1]) * 16 + hex(rest[i + 2]);
    if (byte == 0) {
      why = "the path contains %00";
      return false;
    }
    path += static_cast<char>(byte);
    i += 2;
  }
  return true;
}

bool blank(const char* text) {
  for (const char* p = text; *p; ++p) {
    if (!std::isspace(static_cast<unsigned char>(*p))) return false;
  }
  return true;
}

}  // namespace

// The prologue of every function of an instance: a valid component, the call allowed in its state.
#define FMI2_BEGIN(function, phases)                         \
  Component* component = componentOf(c);                     \
  if (!component) return fmi2Error;                          \
  Instance& instance = *component->instance;                 \
  if (!instance.allowed(function, phases)) return fmi2Error; \
  try {
#define FMI2_END(function)                                             \
  }                                                                    \
  catch (const std::exception& error) {                                \
    return to2(instance.internalError(function, error.what()));        \
  }                                                                    \
  catch (...) {                                                        \
    return to2(instance.internalError(function, "unknown exception")); \
  }
#define FMI2_UNSUPPORTED(function, why)  \
  Component* component = componentOf(c); \
  if (!component) return fmi2Error;      \
  return to2(component->instance->unsupported(function, why));

// ---- Common functions ------------------------------------------------------------------------------

FMI2_EXPORT const char* fmi2GetTypesPlatform(void) { return "default"; }

FMI2_EXPORT const char* fmi2GetVersion(void) { return "2.0"; }

FMI2_EXPORT fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                                           const fmi2String categories[]) {
  FMI2_BEGIN("fmi2SetDebugLogging", fmu::kAnyPhase)
  return to2(instance.setDebugLogging("fmi2SetDebugLogging", loggingOn != 0, nCategories, categories));
  FMI2_END("fmi2SetDebugLogging")
}

FMI2_EXPORT fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                          fmi2String fmuResourceLocation, const fmi2CallbackFunctions* functions,
                                          fmi2Boolean visible, fmi2Boolean loggingOn) {
  (void)visible;                   // batch mode either way: the FMU has no user interface
  if (!functions) return nullptr;  // no logger to say why
  const char* name = instanceName && *instanceName ? instanceName : "jointcomp";
  auto refuse = [&](const std::string& why) -> fmi2Component {
    if (functions->logger) {
      functions->logger(functions->componentEnvironment, name, fmi2Error, "logStatusError",
                        escaped(("fmi2Instantiate: " + why).c_str()).c_str());
    }
    return nullptr;
  };
  if (!instanceName || blank(instanceName)) return refuse("instanceName must be a non-empty string");
  if (fmuType != fmi2CoSimulation) return refuse(kCoSimulationOnly);
  if (!fmuGUID) return refuse("fmuGUID is null; it is the guid of modelDescription.xml");
  if (!fmuResourceLocation) return refuse("fmuResourceLocation is null; the FMU needs its resources/ folder");
  std::string path, why;
  if (!pathFromUri(fmuResourceLocation, path, why)) {
    return refuse(std::string("fmuResourceLocation '") + fmuResourceLocation + "': " + why);
  }
  try {
    auto component = std::make_unique<Component>();
    component->callbacks = *functions;
    component->name = instanceName;
    component->instance = std::make_unique<Instance>(instanceName, loadModel(path, fmuGUID), logToImporter,
                                                     component.get(), loggingOn != 0);
    return component.release();
  } catch (const std::exception& error) {
    return refuse(error.what());
  } catch (...) {
    return refuse("unknown exception");
  }
}

FMI2_EXPORT void fmi2FreeInstance(fmi2Component c) {
  Component* component = componentOf(c);
  delete component;
}

FMI2_EXPORT fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                                           fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
  FMI2_BEGIN("fmi2SetupExperiment", fmu::kInstantiated)
  return to2(instance.setupExperiment("fmi2SetupExperiment", toleranceDefined != 0, tolerance, startTime,
                                      stopTimeDefined != 0, stopTime));
  FMI2_END("fmi2SetupExperiment")
}

FMI2_EXPORT fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
  FMI2_BEGIN("fmi2EnterInitializationMode", fmu::kInstantiated)
  return to2(instance.enterInitializationMode("fmi2EnterInitializationMode"));
  FMI2_END("fmi2EnterInitializationMode")
}

FMI2_EXPORT fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
  FMI2_BEGIN("fmi2ExitInitializationMode", fmu::kInitializationMode)
  return to2(instance.exitInitializationMode("fmi2ExitInitializationMode"));
  FMI2_END("fmi2ExitInitializationMode")
}

FMI2_EXPORT fmi2Status fmi2Terminate(fmi2Component c) {
  FMI2_BEGIN("fmi2Terminate", fmu::kStepMode | fmu::kStepDiscarded)
  return to2(instance.terminate("fmi2Terminate"));
  FMI2_END("fmi2Terminate")
}

FMI2_EXPORT fmi2Status fmi2Reset(fmi2Component c) {
  FMI2_BEGIN("fmi2Reset", fmu::kAnyPhase)
  return to2(instance.reset("fmi2Reset"));
  FMI2_END("fmi2Reset")
}

FMI2_EXPORT fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
  FMI2_BEGIN("fmi2GetReal", kGetPhases)
  return to2(instance.get("fmi2GetReal", fmu::kReal, vr, nvr, value));
  FMI2_END("fmi2GetReal")
}

FMI2_EXPORT fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
  FMI2_BEGIN("fmi2GetInteger", kGetPhases)
  return to2(instance.get("fmi2GetInteger", fmu::kInteger | fmu::kEnumeration, vr, nvr, value));
  FMI2_END("fmi2GetInteger")
}

FMI2_EXPORT fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
  FMI2_BEGIN("fmi2GetBoolean", kGetPhases)
  return to2(instance.get("fmi2GetBoolean", fmu::kBoolean, vr, nvr, value));
  FMI2_END("fmi2GetBoolean")
}

FMI2_EXPORT fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
  FMI2_BEGIN("fmi2GetString", kGetPhases)
  if (nvr > 0 && !value) return to2(instance.nullArgument("fmi2GetString", "value[]"));
  return to2(instance.noVariablesOfType("fmi2GetString", "String", vr, nvr));
  FMI2_END("fmi2GetString")
}

FMI2_EXPORT fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
  FMI2_BEGIN("fmi2SetReal", kSetPhases)
  return to2(instance.set("fmi2SetReal", fmu::kReal, vr, nvr, value));
  FMI2_END("fmi2SetReal")
}

FMI2_EXPORT fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                      const fmi2Integer value[]) {
  FMI2_BEGIN("fmi2SetInteger", kSetPhases)
  return to2(instance.set("fmi2SetInteger", fmu::kInteger | fmu::kEnumeration, vr, nvr, value));
  FMI2_END("fmi2SetInteger")
}

FMI2_EXPORT fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                      const fmi2Boolean value[]) {
  FMI2_BEGIN("fmi2SetBoolean", kSetPhases)
  return to2(instance.set("fmi2SetBoolean", fmu::kBoolean, vr, nvr, value));
  FMI2_END("fmi2SetBoolean")
}

FMI2_EXPORT fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                     const fmi2String value[]) {
  FMI2_BEGIN("fmi2SetString", kSetPhases)
  if (nvr > 0 && !value) return to2(instance.nullArgument("fmi2SetString", "value[]"));
  return to2(instance.noVariablesOfType("fmi2SetString", "String", vr, nvr));
  FMI2_END("fmi2SetString")
}

FMI2_EXPORT fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
  FMI2_BEGIN("fmi2GetFMUstate", kStatePhases)
  return to2(instance.getState("fmi2GetFMUstate", reinterpret_cast<Snapshot**>(FMUstate)));
  FMI2_END("fmi2GetFMUstate")
}

FMI2_EXPORT fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
  FMI2_BEGIN("fmi2SetFMUstate", fmu::kAnyPhase)
  return to2(instance.setState("fmi2SetFMUstate", static_cast<const Snapshot*>(FMUstate)));
  FMI2_END("fmi2SetFMUstate")
}

FMI2_EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* FMUstate) {
  FMI2_BEGIN("fmi2FreeFMUstate", fmu::kAnyPhase)
  return to2(instance.freeState("fmi2FreeFMUstate", reinterpret_cast<Snapshot**>(FMUstate)));
  FMI2_END("fmi2FreeFMUstate")
}

FMI2_EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t* size) {
  FMI2_BEGIN("fmi2SerializedFMUstateSize", fmu::kAnyPhase)
  return to2(instance.serializedSize("fmi2SerializedFMUstateSize", static_cast<const Snapshot*>(FMUstate), size));
  FMI2_END("fmi2SerializedFMUstateSize")
}

FMI2_EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                             size_t size) {
  FMI2_BEGIN("fmi2SerializeFMUstate", fmu::kAnyPhase)
  return to2(instance.serialize("fmi2SerializeFMUstate", static_cast<const Snapshot*>(FMUstate),
                                reinterpret_cast<unsigned char*>(serializedState), size));
  FMI2_END("fmi2SerializeFMUstate")
}

FMI2_EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                               fmi2FMUstate* FMUstate) {
  FMI2_BEGIN("fmi2DeSerializeFMUstate", fmu::kAnyPhase)
  return to2(instance.deserialize("fmi2DeSerializeFMUstate", reinterpret_cast<const unsigned char*>(serializedState),
                                  size, reinterpret_cast<Snapshot**>(FMUstate)));
  FMI2_END("fmi2DeSerializeFMUstate")
}

FMI2_EXPORT fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                                    size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                                    size_t nKnown, const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
  (void)vUnknown_ref, (void)nUnknown, (void)vKnown_ref, (void)nKnown, (void)dvKnown, (void)dvUnknown;
  FMI2_UNSUPPORTED("fmi2GetDirectionalDerivative",
                   "directional derivatives are not provided "
                   "(providesDirectionalDerivative is false)")
}

// ---- Model exchange: not provided ----------------------------------------------------------------------

FMI2_EXPORT fmi2Status fmi2EnterEventMode(fmi2Component c){FMI2_UNSUPPORTED("fmi2EnterEventMode", kCoSimulationOnly)}

FMI2_EXPORT fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo* fmi2eventInfo) {
  (void)fmi2eventInfo;
  FMI2_UNSUPPORTED("fmi2NewDiscreteStates", kCoSimulationOnly)
}

FMI2_EXPORT fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c){
    FMI2_UNSUPPORTED("fmi2EnterContinuousTimeMode", kCoSimulationOnly)}

FMI2_EXPORT fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi2Boolean* enterEventMode, fmi2Boolean* terminateSimulation) {
  (void)noSetFMUStatePriorToCurrentPoint, (void)enterEventMode, (void)terminateSimulation;
  FMI2_UNSUPPORTED("fmi2CompletedIntegratorStep", kCoSimulationOnly)
}

FMI2_EXPORT fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
  (void)time;
  FMI2_UNSUPPORTED("fmi2SetTime", kCoSimulationOnly)
}

FMI2_EXPORT fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
  (void)x, (void)nx;
  FMI2_UNSUPPORTED("fmi2SetContinuousStates", kCoSimulationOnly)
}

FMI2_EXPORT fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
  (void)derivatives, (void)nx;
  FMI2_UNSUPPORTED("fmi2GetDerivatives", kCoSimulationOnly)
}

FMI2_EXPORT fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
  (void)eventIndicators, (void)ni;
  FMI2_UNSUPPORTED("fmi2GetEventIndicators", kCoSimulationOnly)
}

FMI2_EXPORT fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
  (void)x, (void)nx;
  FMI2_UNSUPPORTED("fmi2GetContinuousStates", kCoSimulationOnly)
}

FMI2_EXPORT fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
  (void)x_nominal, (void)nx;
  FMI2_UNSUPPORTED("fmi2GetNominalsOfContinuousStates", kCoSimulationOnly)
}

// ---- Co-simulation -------------------------------------------------------------------------------------

FMI2_EXPORT fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                                   const fmi2Integer order[], const fmi2Real value[]) {
  (void)vr, (void)nvr, (void)order, (void)value;
  FMI2_UNSUPPORTED("fmi2SetRealInputDerivatives", "input derivatives are not used (canInterpolateInputs is false)")
}

FMI2_EXPORT fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                                    const fmi2Integer order[], fmi2Real value[]) {
  (void)vr, (void)nvr, (void)order, (void)value;
  FMI2_UNSUPPORTED("fmi2GetRealOutputDerivatives",
                   "output derivatives are not provided (maxOutputDerivativeOrder is 0)")
}

FMI2_EXPORT fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                                  fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
  (void)noSetFMUStatePriorToCurrentPoint;  // states are kept by the importer, not by the FMU
  FMI2_BEGIN("fmi2DoStep", fmu::kStepMode)
  return to2(instance.doStep("fmi2DoStep", currentCommunicationPoint, communicationStepSize, nullptr));
  FMI2_END("fmi2DoStep")
}

FMI2_EXPORT fmi2Status fmi2CancelStep(fmi2Component c){
    FMI2_UNSUPPORTED("fmi2CancelStep", "steps are never asynchronous (canRunAsynchronuously is false)")}

FMI2_EXPORT fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status* value) {
  (void)s, (void)value;
  FMI2_UNSUPPORTED("fmi2GetStatus", "no step is ever pending (steps are not asynchronous)")
}

FMI2_EXPORT fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real* value) {
  FMI2_BEGIN("fmi2GetRealStatus", kStatusPhases)
  if (!value) return to2(instance.nullArgument("fmi2GetRealStatus", "value"));
  if (s != fmi2LastSuccessfulTime) {
    return to2(instance.unsupported("fmi2GetRealStatus", "only fmi2LastSuccessfulTime is a real status"));
  }
  *value = instance.lastSuccessfulTime();
  return fmi2OK;
  FMI2_END("fmi2GetRealStatus")
}

FMI2_EXPORT fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer* value) {
  (void)s, (void)value;
  FMI2_UNSUPPORTED("fmi2GetIntegerStatus", "there is no integer status")
}

FMI2_EXPORT fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean* value) {
  FMI2_BEGIN("fmi2GetBooleanStatus", kStatusPhases)
  if (!value) return to2(instance.nullArgument("fmi2GetBooleanStatus", "value"));
  if (s != fmi2Terminated)
    return to2(instance.unsupported("fmi2GetBooleanStatus", "only fmi2Terminated is a boolean status"));
  *value = instance.wantsToTerminate() ? 1 : 0;  // after a discarded step
  return fmi2OK;
  FMI2_END("fmi2GetBooleanStatus")
}

FMI2_EXPORT fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String* value) {
  (void)s, (void)value;
  FMI2_UNSUPPORTED("fmi2GetStringStatus", "no step is ever pending (steps are not asynchronous)")
}
