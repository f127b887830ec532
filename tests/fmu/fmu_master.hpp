// A master over either FMI version, as the FMU tests use it: the binary loaded with dlopen from the unzipped
// FMU (in a folder whose path has a space), value references read from its modelDescription.xml, every
// message of the FMU's logger kept. Shared by the importer tests (test_fmu_importer.cpp) and the tests of
// the step semantics (test_fmu_step_semantics.cpp).
#pragma once

#include <dlfcn.h>
#include <algorithm>

#include <cctype>
#include <cmath>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "fmu/fmi2_api.hpp"
#include "fmu/fmi3_api.hpp"
#include "model/io/atomic_file.hpp"

namespace jointcomp::fmutest {

inline constexpr int kOK = 0, kDiscard = 2, kError = 3;  // FMI status values (fmi2Status, fmi3Status)
inline constexpr int kDof = 6;
inline constexpr double kDegree = 3.14159265358979323846 / 180.0;

inline std::string unzipped(int version) {
  return std::string(JOINTCOMP_FMU_UNZIPPED_DIR) + "/fmi" + std::to_string(version);
}

inline std::string readFile(const std::string& path) { return readTextFile(path, "file"); }

// What a master reads from modelDescription.xml: the token and the value reference of every name.
struct ModelDescription {
  std::string token;
  std::map<std::string, std::uint32_t> vr;
  std::vector<std::uint32_t> outputs;  // in file order
};

// The text of attribute `name` in the element text [begin, end), "" if it has none.
inline std::string attribute(const std::string& xml, std::size_t begin, std::size_t end, const std::string& name) {
  const std::string key = " " + name + "=\"";
  const std::size_t at = xml.find(key, begin);
  if (at == std::string::npos || at >= end) return "";
  const std::size_t value = at + key.size();
  return xml.substr(value, xml.find('"', value) - value);
}

inline ModelDescription readModelDescription(int version, const std::string& folder) {
  const std::string xml = readFile(folder + "/modelDescription.xml");
  ModelDescription md;
  md.token =
      attribute(xml, 0, xml.find('>', xml.find("<fmiModelDescription")), version == 2 ? "guid" : "instantiationToken");
  // Every element with a valueReference inside ModelVariables is a variable.
  const std::size_t variables_end = xml.find("</ModelVariables>");
  for (std::size_t at = xml.find("<ModelVariables>"); (at = xml.find('<', at + 1)) < variables_end;) {
    const std::size_t end = xml.find('>', at);
    const std::string vr = attribute(xml, at, end, "valueReference");
    if (vr.empty()) continue;
    md.vr[attribute(xml, at, end, "name")] = static_cast<std::uint32_t>(std::stoul(vr));
    if (attribute(xml, at, end, "causality") == "output")
      md.outputs.push_back(static_cast<std::uint32_t>(std::stoul(vr)));
  }
  return md;
}

inline std::string percentEncoded(const std::string& path) {
  std::string uri;
  for (unsigned char ch : path) {
    if (std::isalnum(ch) || ch == '/' || ch == '-' || ch == '_' || ch == '.' || ch == '~') {
      uri += static_cast<char>(ch);
    } else {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", ch);
      uri += hex;
    }
  }
  return uri;
}

// ---- A master over either FMI version -------------------------------------------------------------------

class Master {
public:
  virtual ~Master() = default;
  virtual int version() const = 0;
  // resources: "" for the FMU's own resources/ folder; otherwise a folder (FMI 3) or a URI (FMI 2) as given.
  bool instantiate(const std::string& name = "robot", const std::string& resources = "", const std::string& token = "",
                   bool logging = true) {
    return instantiateAs(name, resources, token, logging);
  }
  int enterInitialization(double start = 0.0, bool stop_defined = false, double stop = 0.0) {
    return enterInitializationAt(start, stop_defined, stop);
  }
  virtual bool instantiateAs(const std::string& name, const std::string& resources, const std::string& token,
                             bool logging) = 0;
  virtual int enterInitializationAt(double start, bool stop_defined, double stop) = 0;
  virtual int exitInitialization() = 0;
  virtual int setReals(const std::vector<std::uint32_t>& vrs, const std::vector<double>& values) = 0;
  virtual int getReals(const std::vector<std::uint32_t>& vrs, std::vector<double>& values) = 0;
  virtual int setInteger(std::uint32_t vr, int value) = 0;
  virtual int setEnumeration(std::uint32_t vr, long value) = 0;
  virtual int getEnumeration(std::uint32_t vr, long& value) = 0;
  virtual int setBoolean(std::uint32_t vr, bool value) = 0;
  virtual int getBoolean(std::uint32_t vr, bool& value) = 0;
  virtual int doStep(double t, double h) = 0;
  virtual double lastSuccessfulTime() = 0;
  // FMI 2: fmi2GetBooleanStatus(fmi2Terminated); FMI 3: the last fmi3DoStep's terminateSimulation.
  virtual bool terminateRequested() = 0;
  virtual int getState(void** state) = 0;
  virtual int setState(void* state) = 0;
  virtual int freeState(void** state) = 0;
  virtual int serialize(void* state, std::vector<unsigned char>& bytes) = 0;
  virtual int deserialize(const std::vector<unsigned char>& bytes, void** state) = 0;
  virtual int terminate() = 0;
  virtual int reset() = 0;
  virtual void freeInstance() = 0;
  virtual void* handle() const = 0;

  std::uint32_t vr(const std::string& name) const {
    const auto found = md.vr.find(name);
    if (found == md.vr.end()) throw std::runtime_error("no variable " + name);
    return found->second;
  }
  // The variables of a per-joint role ("q_desired" or "q_desired_": q_desired.<joint> for every joint), in the
  // order of their value references, which is the chain's joint order.
  std::vector<std::uint32_t> vrs(const std::string& role, int count) const {
    const std::vector<std::uint32_t> list = roleVrs(role);
    if (static_cast<int>(list.size()) != count) {
      throw std::runtime_error(role + ": " + std::to_string(list.size()) + " variables, expected " +
                               std::to_string(count));
    }
    return list;
  }
  // Every variable of a per-joint role, whatever the number of joints.
  std::vector<std::uint32_t> roleVrs(std::string role) const {
    if (!role.empty() && role.back() == '_') role.pop_back();
    std::vector<std::uint32_t> list;
    for (const auto& [name, reference] : md.vr) {
      if (name.rfind(role + ".", 0) == 0) list.push_back(reference);
    }
    std::sort(list.begin(), list.end());
    return list;
  }
  bool logged(const std::string& fragment) const {
    for (const std::string& m : messages) {
      if (m.find(fragment) != std::string::npos) return true;
    }
    return false;
  }
  std::string log() const {
    std::string all;
    for (const std::string& m : messages) all += m + "\n";
    return all;
  }

  ModelDescription md;
  std::vector<std::string> messages;
};

class Library {
public:
  explicit Library(const std::string& path) : handle_(dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL)) {
    if (!handle_) throw std::runtime_error(std::string("dlopen: ") + dlerror());
  }
  ~Library() { dlclose(handle_); }
  Library(const Library&) = delete;
  Library& operator=(const Library&) = delete;
  template <typename F>
  void load(F& function, const char* name) {
    function = reinterpret_cast<F>(dlsym(handle_, name));
    if (!function) throw std::runtime_error(std::string("dlsym ") + name);
  }

private:
  void* handle_;
};

#define LOAD(name) library.load(name, #name)

// The FMI 2 functions, as a master gets them.
struct Fmi2Api {
  explicit Fmi2Api(Library& library) {
    LOAD(fmi2GetTypesPlatform);
    LOAD(fmi2GetVersion);
    LOAD(fmi2SetDebugLogging);
    LOAD(fmi2Instantiate);
    LOAD(fmi2FreeInstance);
    LOAD(fmi2SetupExperiment);
    LOAD(fmi2EnterInitializationMode);
    LOAD(fmi2ExitInitializationMode);
    LOAD(fmi2Terminate);
    LOAD(fmi2Reset);
    LOAD(fmi2GetReal);
    LOAD(fmi2GetInteger);
    LOAD(fmi2GetBoolean);
    LOAD(fmi2GetString);
    LOAD(fmi2SetReal);
    LOAD(fmi2SetInteger);
    LOAD(fmi2SetBoolean);
    LOAD(fmi2SetString);
    LOAD(fmi2GetFMUstate);
    LOAD(fmi2SetFMUstate);
    LOAD(fmi2FreeFMUstate);
    LOAD(fmi2SerializedFMUstateSize);
    LOAD(fmi2SerializeFMUstate);
    LOAD(fmi2DeSerializeFMUstate);
    LOAD(fmi2GetDirectionalDerivative);
    LOAD(fmi2EnterEventMode);
    LOAD(fmi2NewDiscreteStates);
    LOAD(fmi2EnterContinuousTimeMode);
    LOAD(fmi2CompletedIntegratorStep);
    LOAD(fmi2SetTime);
    LOAD(fmi2SetContinuousStates);
    LOAD(fmi2GetDerivatives);
    LOAD(fmi2GetEventIndicators);
    LOAD(fmi2GetContinuousStates);
    LOAD(fmi2GetNominalsOfContinuousStates);
    LOAD(fmi2SetRealInputDerivatives);
    LOAD(fmi2GetRealOutputDerivatives);
    LOAD(fmi2DoStep);
    LOAD(fmi2CancelStep);
    LOAD(fmi2GetStatus);
    LOAD(fmi2GetRealStatus);
    LOAD(fmi2GetIntegerStatus);
    LOAD(fmi2GetBooleanStatus);
    LOAD(fmi2GetStringStatus);
  }
  decltype(&::fmi2GetTypesPlatform) fmi2GetTypesPlatform;
  decltype(&::fmi2GetVersion) fmi2GetVersion;
  decltype(&::fmi2SetDebugLogging) fmi2SetDebugLogging;
  decltype(&::fmi2Instantiate) fmi2Instantiate;
  decltype(&::fmi2FreeInstance) fmi2FreeInstance;
  decltype(&::fmi2SetupExperiment) fmi2SetupExperiment;
  decltype(&::fmi2EnterInitializationMode) fmi2EnterInitializationMode;
  decltype(&::fmi2ExitInitializationMode) fmi2ExitInitializationMode;
  decltype(&::fmi2Terminate) fmi2Terminate;
  decltype(&::fmi2Reset) fmi2Reset;
  decltype(&::fmi2GetReal) fmi2GetReal;
  decltype(&::fmi2GetInteger) fmi2GetInteger;
  decltype(&::fmi2GetBoolean) fmi2GetBoolean;
  decltype(&::fmi2GetString) fmi2GetString;
  decltype(&::fmi2SetReal) fmi2SetReal;
  decltype(&::fmi2SetInteger) fmi2SetInteger;
  decltype(&::fmi2SetBoolean) fmi2SetBoolean;
  decltype(&::fmi2SetString) fmi2SetString;
  decltype(&::fmi2GetFMUstate) fmi2GetFMUstate;
  decltype(&::fmi2SetFMUstate) fmi2SetFMUstate;
  decltype(&::fmi2FreeFMUstate) fmi2FreeFMUstate;
  decltype(&::fmi2SerializedFMUstateSize) fmi2SerializedFMUstateSize;
  decltype(&::fmi2SerializeFMUstate) fmi2SerializeFMUstate;
  decltype(&::fmi2DeSerializeFMUstate) fmi2DeSerializeFMUstate;
  decltype(&::fmi2GetDirectionalDerivative) fmi2GetDirectionalDerivative;
  decltype(&::fmi2EnterEventMode) fmi2EnterEventMode;
  decltype(&::fmi2NewDiscreteStates) fmi2NewDiscreteStates;
  decltype(&::fmi2EnterContinuousTimeMode) fmi2EnterContinuousTimeMode;
  decltype(&::fmi2CompletedIntegratorStep) fmi2CompletedIntegratorStep;
  decltype(&::fmi2SetTime) fmi2SetTime;
  decltype(&::fmi2SetContinuousStates) fmi2SetContinuousStates;
  decltype(&::fmi2GetDerivatives) fmi2GetDerivatives;
  decltype(&::fmi2GetEventIndicators) fmi2GetEventIndicators;
  decltype(&::fmi2GetContinuousStates) fmi2GetContinuousStates;
  decltype(&::fmi2GetNominalsOfContinuousStates) fmi2GetNominalsOfContinuousStates;
  decltype(&::fmi2SetRealInputDerivatives) fmi2SetRealInputDerivatives;
  decltype(&::fmi2GetRealOutputDerivatives) fmi2GetRealOutputDerivatives;
  decltype(&::fmi2DoStep) fmi2DoStep;
  decltype(&::fmi2CancelStep) fmi2CancelStep;
  decltype(&::fmi2GetStatus) fmi2GetStatus;
  decltype(&::fmi2GetRealStatus) fmi2GetRealStatus;
  decltype(&::fmi2GetIntegerStatus) fmi2GetIntegerStatus;
  decltype(&::fmi2GetBooleanStatus) fmi2GetBooleanStatus;
  decltype(&::fmi2GetStringStatus) fmi2GetStringStatus;
};

// The FMI 3 functions, as a master gets them (those the tests call).
struct Fmi3Api {
  explicit Fmi3Api(Library& library) {
    LOAD(fmi3GetVersion);
    LOAD(fmi3SetDebugLogging);
    LOAD(fmi3InstantiateModelExchange);
    LOAD(fmi3InstantiateCoSimulation);
    LOAD(fmi3InstantiateScheduledExecution);
    LOAD(fmi3FreeInstance);
    LOAD(fmi3EnterInitializationMode);
    LOAD(fmi3ExitInitializationMode);
    LOAD(fmi3EnterEventMode);
    LOAD(fmi3Terminate);
    LOAD(fmi3Reset);
    LOAD(fmi3GetFloat32);
    LOAD(fmi3GetFloat64);
    LOAD(fmi3GetInt32);
    LOAD(fmi3GetInt64);
    LOAD(fmi3GetBoolean);
    LOAD(fmi3GetString);
    LOAD(fmi3GetBinary);
    LOAD(fmi3GetClock);
    LOAD(fmi3SetFloat64);
    LOAD(fmi3SetInt32);
    LOAD(fmi3SetInt64);
    LOAD(fmi3SetBoolean);
    LOAD(fmi3SetUInt8);
    LOAD(fmi3GetNumberOfVariableDependencies);
    LOAD(fmi3GetVariableDependencies);
    LOAD(fmi3GetFMUState);
    LOAD(fmi3SetFMUState);
    LOAD(fmi3FreeFMUState);
    LOAD(fmi3SerializedFMUStateSize);
    LOAD(fmi3SerializeFMUState);
    LOAD(fmi3DeserializeFMUState);
    LOAD(fmi3GetDirectionalDerivative);
    LOAD(fmi3EnterConfigurationMode);
    LOAD(fmi3UpdateDiscreteStates);
    LOAD(fmi3EnterContinuousTimeMode);
    LOAD(fmi3GetNumberOfContinuousStates);
    LOAD(fmi3EnterStepMode);
    LOAD(fmi3GetOutputDerivatives);
    LOAD(fmi3DoStep);
    LOAD(fmi3ActivateModelPartition);
  }
  decltype(&::fmi3GetVersion) fmi3GetVersion;
  decltype(&::fmi3SetDebugLogging) fmi3SetDebugLogging;
  decltype(&::fmi3InstantiateModelExchange) fmi3InstantiateModelExchange;
  decltype(&::fmi3InstantiateCoSimulation) fmi3InstantiateCoSimulation;
  decltype(&::fmi3InstantiateScheduledExecution) fmi3InstantiateScheduledExecution;
  decltype(&::fmi3FreeInstance) fmi3FreeInstance;
  decltype(&::fmi3EnterInitializationMode) fmi3EnterInitializationMode;
  decltype(&::fmi3ExitInitializationMode) fmi3ExitInitializationMode;
  decltype(&::fmi3EnterEventMode) fmi3EnterEventMode;
  decltype(&::fmi3Terminate) fmi3Terminate;
  decltype(&::fmi3Reset) fmi3Reset;
  decltype(&::fmi3GetFloat32) fmi3GetFloat32;
  decltype(&::fmi3GetFloat64) fmi3GetFloat64;
  decltype(&::fmi3GetInt32) fmi3GetInt32;
  decltype(&::fmi3GetInt64) fmi3GetInt64;
  decltype(&::fmi3GetBoolean) fmi3GetBoolean;
  decltype(&::fmi3GetString) fmi3GetString;
  decltype(&::fmi3GetBinary) fmi3GetBinary;
  decltype(&::fmi3GetClock) fmi3GetClock;
  decltype(&::fmi3SetFloat64) fmi3SetFloat64;
  decltype(&::fmi3SetInt32) fmi3SetInt32;
  decltype(&::fmi3SetInt64) fmi3SetInt64;
  decltype(&::fmi3SetBoolean) fmi3SetBoolean;
  decltype(&::fmi3SetUInt8) fmi3SetUInt8;
  decltype(&::fmi3GetNumberOfVariableDependencies) fmi3GetNumberOfVariableDependencies;
  decltype(&::fmi3GetVariableDependencies) fmi3GetVariableDependencies;
  decltype(&::fmi3GetFMUState) fmi3GetFMUState;
  decltype(&::fmi3SetFMUState) fmi3SetFMUState;
  decltype(&::fmi3FreeFMUState) fmi3FreeFMUState;
  decltype(&::fmi3SerializedFMUStateSize) fmi3SerializedFMUStateSize;
  decltype(&::fmi3SerializeFMUState) fmi3SerializeFMUState;
  decltype(&::fmi3DeserializeFMUState) fmi3DeserializeFMUState;
  decltype(&::fmi3GetDirectionalDerivative) fmi3GetDirectionalDerivative;
  decltype(&::fmi3EnterConfigurationMode) fmi3EnterConfigurationMode;
  decltype(&::fmi3UpdateDiscreteStates) fmi3UpdateDiscreteStates;
  decltype(&::fmi3EnterContinuousTimeMode) fmi3EnterContinuousTimeMode;
  decltype(&::fmi3GetNumberOfContinuousStates) fmi3GetNumberOfContinuousStates;
  decltype(&::fmi3EnterStepMode) fmi3EnterStepMode;
  decltype(&::fmi3GetOutputDerivatives) fmi3GetOutputDerivatives;
  decltype(&::fmi3DoStep) fmi3DoStep;
  decltype(&::fmi3ActivateModelPartition) fmi3ActivateModelPartition;
};

inline Library& library(int version) {
  // Loaded once per process, as a master loads an FMU's binary once for all its instances.
  static Library fmi2(unzipped(2) + "/binaries/linux64/jointcomp.so");
  static Library fmi3(unzipped(3) + "/binaries/x86_64-linux/jointcomp.so");
  return version == 2 ? fmi2 : fmi3;
}
inline const Fmi2Api& fmi2() {
  static const Fmi2Api api(library(2));
  return api;
}
inline const Fmi3Api& fmi3() {
  static const Fmi3Api api(library(3));
  return api;
}

inline void fmi2Logger(fmi2ComponentEnvironment environment, fmi2String, fmi2Status status, fmi2String category,
                       fmi2String message, ...) {
  char text[2048];
  va_list args;
  va_start(args, message);
  std::vsnprintf(text, sizeof text, message, args);  // the FMI 2 message is a printf format
  va_end(args);
  std::string line = std::string(category) + " [" + std::to_string(status) + "] " + text;
  for (std::size_t at = line.find("##"); at != std::string::npos; at = line.find("##", at + 1)) line.erase(at, 1);
  static_cast<Master*>(environment)->messages.push_back(line);
}

inline void fmi3Logger(fmi3InstanceEnvironment environment, fmi3Status status, fmi3String category,
                       fmi3String message) {
  static_cast<Master*>(environment)
      ->messages.push_back(std::string(category) + " [" + std::to_string(status) + "] " + message);
}

class Master2 : public Master {
public:
  // folder: an unzipped FMU (by default the shipped one); every FMU has the same binary, loaded once.
  explicit Master2(std::string unzipped_fmu = unzipped(2)) : api(fmi2()), folder(std::move(unzipped_fmu)) {
    md = readModelDescription(2, folder);
  }
  ~Master2() override { freeInstance(); }
  int version() const override { return 2; }
  bool instantiateAs(const std::string& name, const std::string& resources, const std::string& token,
                     bool logging) override {
    callbacks = {fmi2Logger, nullptr, nullptr, nullptr, this};
    const std::string uri = resources.empty() ? "file://" + percentEncoded(folder + "/resources/") : resources;
    c = api.fmi2Instantiate(name.c_str(), fmi2CoSimulation, token.empty() ? md.token.c_str() : token.c_str(),
                            uri.c_str(), &callbacks, 0, logging ? 1 : 0);
    return c != nullptr;
  }
  int enterInitializationAt(double start, bool stop_defined, double stop) override {
    const int status = api.fmi2SetupExperiment(c, 0, 0.0, start, stop_defined, stop);
    if (status != kOK) return status;
    return api.fmi2EnterInitializationMode(c);
  }
  int exitInitialization() override { return api.fmi2ExitInitializationMode(c); }
  int setReals(const std::vector<std::uint32_t>& vrs, const std::vector<double>& values) override {
    return api.fmi2SetReal(c, vrs.data(), vrs.size(), values.data());
  }
  int getReals(const std::vector<std::uint32_t>& vrs, std::vector<double>& values) override {
    values.resize(vrs.size());
    return api.fmi2GetReal(c, vrs.data(), vrs.size(), values.data());
  }
  int setInteger(std::uint32_t vr, int value) override { return api.fmi2SetInteger(c, &vr, 1, &value); }
  int setEnumeration(std::uint32_t vr, long value) override {
    const int v = static_cast<int>(value);
    return api.fmi2SetInteger(c, &vr, 1, &v);
  }
  int getEnumeration(std::uint32_t vr, long& value) override {
    int v = 0;
    const int status = api.fmi2GetInteger(c, &vr, 1, &v);
    value = v;
    return status;
  }
  int setBoolean(std::uint32_t vr, bool value) override {
    const int v = value;
    return api.fmi2SetBoolean(c, &vr, 1, &v);
  }
  int getBoolean(std::uint32_t vr, bool& value) override {
    int v = -1;
    const int status = api.fmi2GetBoolean(c, &vr, 1, &v);
    EXPECT_TRUE(status != kOK || v == 0 || v == 1) << "fmi2Boolean " << v;
    value = v != 0;
    return status;
  }
  int doStep(double t, double h) override { return api.fmi2DoStep(c, t, h, 1); }
  double lastSuccessfulTime() override {
    double t = std::nan("");
    EXPECT_EQ(api.fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &t), kOK);
    return t;
  }
  bool terminateRequested() override {
    fmi2Boolean terminated = -1;
    EXPECT_EQ(api.fmi2GetBooleanStatus(c, fmi2Terminated, &terminated), kOK);
    EXPECT_TRUE(terminated == 0 || terminated == 1) << "fmi2Boolean " << terminated;
    return terminated == 1;
  }
  int getState(void** state) override { return api.fmi2GetFMUstate(c, state); }
  int setState(void* state) override { return api.fmi2SetFMUstate(c, state); }
  int freeState(void** state) override { return api.fmi2FreeFMUstate(c, state); }
  int serialize(void* state, std::vector<unsigned char>& bytes) override {
    std::size_t size = 0;
    const int status = api.fmi2SerializedFMUstateSize(c, state, &size);
    if (status != kOK) return status;
    bytes.resize(size);
    return api.fmi2SerializeFMUstate(c, state, reinterpret_cast<fmi2Byte*>(bytes.data()), size);
  }
  int deserialize(const std::vector<unsigned char>& bytes, void** state) override {
    return api.fmi2DeSerializeFMUstate(c, reinterpret_cast<const fmi2Byte*>(bytes.data()), bytes.size(), state);
  }
  int terminate() override { return api.fmi2Terminate(c); }
  int reset() override { return api.fmi2Reset(c); }
  void freeInstance() override {
    if (c) api.fmi2FreeInstance(c);
    c = nullptr;
  }
  void* handle() const override { return c; }

  const Fmi2Api& api;
  fmi2CallbackFunctions callbacks{};
  std::string folder;
  fmi2Component c = nullptr;
};

class Master3 : public Master {
public:
  explicit Master3(std::string unzipped_fmu = unzipped(3)) : api(fmi3()), folder(std::move(unzipped_fmu)) {
    md = readModelDescription(3, folder);
  }
  ~Master3() override { freeInstance(); }
  int version() const override { return 3; }
  bool instantiateAs(const std::string& name, const std::string& resources, const std::string& token,
                     bool logging) override {
    const std::string path = resources.empty() ? folder + "/resources/" : resources;
    c = api.fmi3InstantiateCoSimulation(name.c_str(), token.empty() ? md.token.c_str() : token.c_str(), path.c_str(),
                                        false, logging, false, false, nullptr, 0, this, fmi3Logger, nullptr);
    return c != nullptr;
  }
  int enterInitializationAt(double start, bool stop_defined, double stop) override {
    return api.fmi3EnterInitializationMode(c, false, 0.0, start, stop_defined, stop);
  }
  int exitInitialization() override { return api.fmi3ExitInitializationMode(c); }
  int setReals(const std::vector<std::uint32_t>& vrs, const std::vector<double>& values) override {
    return api.fmi3SetFloat64(c, vrs.data(), vrs.size(), values.data(), values.size());
  }
  int getReals(const std::vector<std::uint32_t>& vrs, std::vector<double>& values) override {
    values.resize(vrs.size());
    return api.fmi3GetFloat64(c, vrs.data(), vrs.size(), values.data(), values.size());
  }
  int setInteger(std::uint32_t vr, int value) override {
    const std::int32_t v = value;
    return api.fmi3SetInt32(c, &vr, 1, &v, 1);
  }
  int setEnumeration(std::uint32_t vr, long value) override {
    const std::int64_t v = value;
    return api.fmi3SetInt64(c, &vr, 1, &v, 1);
  }
  int getEnumeration(std::uint32_t vr, long& value) override {
    std::int64_t v = 0;
    const int status = api.fmi3GetInt64(c, &vr, 1, &v, 1);
    value = v;
    return status;
  }
  int setBoolean(std::uint32_t vr, bool value) override { return api.fmi3SetBoolean(c, &vr, 1, &value, 1); }
  int getBoolean(std::uint32_t vr, bool& value) override { return api.fmi3GetBoolean(c, &vr, 1, &value, 1); }
  int doStep(double t, double h) override {
    bool event = true, terminate_now = true, early = true;
    const int status = api.fmi3DoStep(c, t, h, true, &event, &terminate_now, &early, &last_successful_time);
    if (status == kOK || status == kDiscard) {  // after an error the flags are undefined
      EXPECT_FALSE(event);
      EXPECT_EQ(terminate_now, status == kDiscard);  // a discarded step cannot go on
      EXPECT_FALSE(early);
      terminate_requested = terminate_now;
    }
    return status;
  }
  double lastSuccessfulTime() override { return last_successful_time; }
  bool terminateRequested() override { return terminate_requested; }
  int getState(void** state) override { return api.fmi3GetFMUState(c, state); }
  int setState(void* state) override { return api.fmi3SetFMUState(c, state); }
  int freeState(void** state) override { return api.fmi3FreeFMUState(c, state); }
  int serialize(void* state, std::vector<unsigned char>& bytes) override {
    std::size_t size = 0;
    const int status = api.fmi3SerializedFMUStateSize(c, state, &size);
    if (status != kOK) return status;
    bytes.resize(size);
    return api.fmi3SerializeFMUState(c, state, bytes.data(), size);
  }
  int deserialize(const std::vector<unsigned char>& bytes, void** state) override {
    return api.fmi3DeserializeFMUState(c, bytes.data(), bytes.size(), state);
  }
  int terminate() override { return api.fmi3Terminate(c); }
  int reset() override { return api.fmi3Reset(c); }
  void freeInstance() override {
    if (c) api.fmi3FreeInstance(c);
    c = nullptr;
  }
  void* handle() const override { return c; }

  const Fmi3Api& api;
  std::string folder;
  fmi3Instance c = nullptr;
  double last_successful_time = std::nan("");
  bool terminate_requested = false;
};

inline std::unique_ptr<Master> makeMaster(int version) {
  if (version == 2) return std::make_unique<Master2>();
  return std::make_unique<Master3>();
}
// A master of another unzipped FMU (export-fmu's of another robot).
inline std::unique_ptr<Master> makeMaster(int version, const std::string& unzipped_fmu) {
  if (version == 2) return std::make_unique<Master2>(unzipped_fmu);
  return std::make_unique<Master3>(unzipped_fmu);
}

}  // namespace jointcomp::fmutest
