// libFuzzer target: any bytes given to fmi2DeSerializeFMUstate and fmi3DeserializeFMUState of an
// instantiated FMU yield a state or an error, never a crash. A state that reads serialises back to the
// same bytes, can be set, and the instance then steps (or refuses to) without crashing.
//
// The FMI glue and the instance are linked in statically (the same sources as the FMU binaries), so that
// the fuzzer sees their coverage. Each input is tried twice per FMI version: as given, and "repaired"
// (its size field and trailing checksum made consistent), since a random change almost never passes the
// checksum and the fields behind it would otherwise go untested.
//
// Seeds: JOINTCOMP_FUZZ_WRITE_SEEDS=<dir> ./fuzz_fmu_state writes real states (one per phase of the state
// machine) into <dir> and exits; tests/fuzz/corpus/fmu_state holds their output.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "fmu/description/variable_table.hpp"
#include "fmu/fmi2_api.hpp"
#include "fmu/fmi3_api.hpp"

namespace {

// The FMU's own resources/ folder (robot.json and parameters.json), from the build tree.
constexpr const char* kResourceDir = JOINTCOMP_FUZZ_FMU_RESOURCES;

// Offsets in the serialised state (fmu/core/state_bytes.cpp, serializeState): 8 magic bytes, a 4-byte format
// number, the 8-byte total size; the last 8 bytes are the FNV-1a checksum of everything before them.
constexpr std::size_t kSizeOffset = 12;
constexpr std::size_t kChecksumSize = 8;
constexpr std::size_t kHeaderSize = kSizeOffset + 8;

[[noreturn]] void die(const char* what) {
  std::fprintf(stderr, "fuzz_fmu_state: %s\n", what);
  std::abort();
}

std::uint64_t fnv1a(const unsigned char* bytes, std::size_t size) {
  std::uint64_t hash = 1469598103934665603ULL;
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= bytes[i];
    hash *= 1099511628211ULL;
  }
  return hash;
}

// A state with absurd (finite) values can make one step run CVODE to its step limit (200000 steps, two
// seconds in a release build, minutes instrumented) before the step is discarded. So that each input
// costs little, the repaired copy lowers the state's integrator.max_steps to this.
constexpr double kFuzzMaxSteps = 500.0;

// The FMU's variable table, as its binary builds it from the same resources.
const jointcomp::fmu::VariableTable& fmuTable() {
  static const jointcomp::fmu::VariableTable table =
      jointcomp::fmu::loadFmuResources(kResourceDir, JOINTCOMP_FMU_VERSION).table;
  return table;
}

// Where the value of variable `index` lies in a serialised state whose token has the FMU's length
// (header, token, variable count, dof, phase, value count, then the values), 0 if it does not.
std::size_t valueOffset(const std::vector<unsigned char>& bytes, int index) {
  const std::size_t token_length = fmuTable().instantiation_token.size();
  std::uint32_t stored_length = 0;
  if (bytes.size() < kHeaderSize + sizeof stored_length) return 0;
  std::memcpy(&stored_length, bytes.data() + kHeaderSize, sizeof stored_length);
  if (stored_length != token_length) return 0;
  const std::size_t offset = kHeaderSize + 4 + token_length + 4 * 4 + 8 * static_cast<std::size_t>(index);
  return offset + 8 + kChecksumSize <= bytes.size() ? offset : 0;
}

// The input with its size field and checksum made consistent (when it is long enough to have both).
std::vector<unsigned char> repaired(const std::uint8_t* data, std::size_t size) {
  std::vector<unsigned char> bytes(data, data + size);
  if (size < kHeaderSize + kChecksumSize) return bytes;
  static const int max_steps_index = fmuTable().indexOfName("integrator.max_steps");
  if (const std::size_t at = valueOffset(bytes, max_steps_index)) {
    std::memcpy(bytes.data() + at, &kFuzzMaxSteps, sizeof kFuzzMaxSteps);
  }
  const std::uint64_t total = size;
  std::memcpy(bytes.data() + kSizeOffset, &total, sizeof total);
  const std::uint64_t checksum = fnv1a(bytes.data(), size - kChecksumSize);
  std::memcpy(bytes.data() + size - kChecksumSize, &checksum, sizeof checksum);
  return bytes;
}

constexpr fmi2Boolean kFmi2False = 0, kFmi2True = 1;

void ignoreFmi2Log(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...) {}
void ignoreFmi3Log(fmi3InstanceEnvironment, fmi3Status, fmi3String, fmi3String) {}

fmi2Component instantiateFmi2() {
  static const fmi2CallbackFunctions callbacks = {ignoreFmi2Log, nullptr, nullptr, nullptr, nullptr};
  const std::string uri = std::string("file://") + kResourceDir;
  fmi2Component c = fmi2Instantiate("fuzz2", fmi2CoSimulation, fmuTable().instantiation_token.c_str(), uri.c_str(),
                                    &callbacks, kFmi2False, kFmi2False);
  if (!c) die("fmi2Instantiate failed (are the FMU resources built?)");
  return c;
}

fmi3Instance instantiateFmi3() {
  fmi3Instance instance =
      fmi3InstantiateCoSimulation("fuzz3", fmuTable().instantiation_token.c_str(), kResourceDir, false, false, false,
                                  false, nullptr, 0, nullptr, ignoreFmi3Log, nullptr);
  if (!instance) die("fmi3InstantiateCoSimulation failed (are the FMU resources built?)");
  return instance;
}

// A state that reads must serialise to exactly the bytes it was read from.
template <typename SizeFn, typename SerializeFn>
void expectSameBytes(const std::vector<unsigned char>& bytes, SizeFn sizeOf, SerializeFn serialize) {
  std::size_t size = 0;
  if (sizeOf(&size) != 0 || size != bytes.size()) die("a deserialised state has another serialised size");
  std::vector<unsigned char> again(size);
  if (serialize(again.data(), size) != 0 || again != bytes) die("a deserialised state serialises to other bytes");
}

void tryFmi2(fmi2Component c, const std::vector<unsigned char>& bytes) {
  fmi2FMUstate state = nullptr;
  const auto* serialized = reinterpret_cast<const fmi2Byte*>(bytes.data());
  if (fmi2DeSerializeFMUstate(c, serialized, bytes.size(), &state) != fmi2OK) {
    if (state) die("fmi2DeSerializeFMUstate failed but returned a state");
    return;
  }
  expectSameBytes(
      bytes, [&](std::size_t* size) { return fmi2SerializedFMUstateSize(c, state, size); },
      [&](unsigned char* out, std::size_t size) {
        return fmi2SerializeFMUstate(c, state, reinterpret_cast<fmi2Byte*>(out), size);
      });
  if (fmi2SetFMUstate(c, state) == fmi2OK) {
    fmi2Real time = 0.0;
    if (fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &time) == fmi2OK) (void)fmi2DoStep(c, time, 1e-3, kFmi2True);
  }
  if (fmi2FreeFMUstate(c, &state) != fmi2OK || state) die("fmi2FreeFMUstate failed");
  // Whatever the state did to the instance, a reset brings it back.
  if (fmi2Reset(c) != fmi2OK) die("fmi2Reset failed after a deserialised state");
}

void tryFmi3(fmi3Instance instance, const std::vector<unsigned char>& bytes) {
  fmi3FMUState state = nullptr;
  if (fmi3DeserializeFMUState(instance, bytes.data(), bytes.size(), &state) != fmi3OK) {
    if (state) die("fmi3DeserializeFMUState failed but returned a state");
    return;
  }
  expectSameBytes(
      bytes, [&](std::size_t* size) { return fmi3SerializedFMUStateSize(instance, state, size); },
      [&](unsigned char* out, std::size_t size) { return fmi3SerializeFMUState(instance, state, out, size); });
  if (fmi3SetFMUState(instance, state) == fmi3OK) {
    fmi3Float64 time = 0.0;
    const auto time_vr = static_cast<fmi3ValueReference>(fmuTable().roles.time);  // the independent variable
    if (fmi3GetFloat64(instance, &time_vr, 1, &time, 1) == fmi3OK) {
      fmi3Boolean event = false, terminate = false, early = false;
      fmi3Float64 last = 0.0;
      (void)fmi3DoStep(instance, time, 1e-3, true, &event, &terminate, &early, &last);
    }
  }
  if (fmi3FreeFMUState(instance, &state) != fmi3OK || state) die("fmi3FreeFMUState failed");
  if (fmi3Reset(instance) != fmi3OK) die("fmi3Reset failed after a deserialised state");
}

// ---- Seeds -------------------------------------------------------------------------------------------------

void writeFile(const std::string& path, const std::vector<unsigned char>& bytes) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file || std::fwrite(bytes.data(), 1, bytes.size(), file) != bytes.size() || std::fclose(file) != 0) {
    die("cannot write a seed");
  }
}

void saveFmi2State(fmi2Component c, const std::string& path) {
  fmi2FMUstate state = nullptr;
  std::size_t size = 0;
  if (fmi2GetFMUstate(c, &state) != fmi2OK || fmi2SerializedFMUstateSize(c, state, &size) != fmi2OK) {
    die("cannot take a state");
  }
  std::vector<unsigned char> bytes(size);
  if (fmi2SerializeFMUstate(c, state, reinterpret_cast<fmi2Byte*>(bytes.data()), size) != fmi2OK) {
    die("cannot serialise a state");
  }
  (void)fmi2FreeFMUstate(c, &state);
  writeFile(path, bytes);
}

// One state per phase a state can be taken in, the later ones after a short motion of every joint.
void writeSeeds(const std::string& dir) {
  fmi2Component c = instantiateFmi2();
  saveFmi2State(c, dir + "/instantiated.bin");
  if (fmi2SetupExperiment(c, kFmi2False, 0.0, 0.0, kFmi2False, 0.0) != fmi2OK ||
      fmi2EnterInitializationMode(c) != fmi2OK) {
    die("cannot initialise");
  }
  // The joints' desired angles at step k (k = 0 during initialisation: an input set then makes the FMU
  // follow its inputs rather than its built-in demo move).
  const auto setDesired = [&](int k) {
    std::vector<fmi2ValueReference> vrs;
    std::vector<fmi2Real> q;
    for (int j = 0; j < fmuTable().dof(); ++j) {
      vrs.push_back(static_cast<fmi2ValueReference>(fmuTable().roles.q_desired[j]));
      q.push_back(0.002 * (j + 1) * k);
    }
    return fmi2SetReal(c, vrs.data(), vrs.size(), q.data()) == fmi2OK;
  };
  if (!setDesired(0)) die("cannot set the desired angles during initialisation");
  saveFmi2State(c, dir + "/initialization_mode.bin");
  if (fmi2ExitInitializationMode(c) != fmi2OK) die("cannot leave initialisation mode");
  const double h = 0.004;
  for (int k = 0; k < 25; ++k) {
    if (!setDesired(k) || fmi2DoStep(c, k * h, h, kFmi2True) != fmi2OK) die("cannot step");
  }
  saveFmi2State(c, dir + "/step_mode.bin");
  if (fmi2Terminate(c) != fmi2OK) die("cannot terminate");
  saveFmi2State(c, dir + "/terminated.bin");
  fmi2FreeInstance(c);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  if (const char* dir = std::getenv("JOINTCOMP_FUZZ_WRITE_SEEDS")) {
    writeSeeds(dir);
    std::exit(0);
  }
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // One instance of each version for the whole run: instantiating loads the robot and the parameters.
  static const fmi2Component fmi2 = instantiateFmi2();
  static const fmi3Instance fmi3 = instantiateFmi3();
  const std::vector<unsigned char> as_given(data, data + size);
  const std::vector<unsigned char> consistent = repaired(data, size);
  for (const auto* bytes : {&as_given, &consistent}) {
    tryFmi2(fmi2, *bytes);
    tryFmi3(fmi3, *bytes);
  }
  return 0;
}
