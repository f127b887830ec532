// Load test of the FMUs: an hour of simulated time through each FMU binary (loaded with dlopen, as a
// master does), twice per FMI version. The resident memory is sampled every simulated minute and must
// stay flat after a warm-up; the outputs of every step (their bits, hashed) must be identical between
// the runs and between FMI 2 and FMI 3.
//   fmu_load <unzipped or staging FMU folder of FMI 2> <same of FMI 3> [simulated seconds, default 3600]
#include <dlfcn.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "fmu/description/variable_table.hpp"
#include "fmu/fmi2_api.hpp"
#include "fmu/fmi3_api.hpp"

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kStep = 0.01;  // communication step, s
constexpr double kMinute = 60.0;
constexpr double kWarmUp = 5 * kMinute;   // allocations settle (integrator, caches) before this
constexpr long kAllowedGrowthKiB = 2048;  // RSS may vary this much after the warm-up

[[noreturn]] void die(const std::string& what) {
  std::fprintf(stderr, "fmu_load: %s\n", what.c_str());
  std::exit(1);
}

long residentKiB() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::strtol(line.c_str() + 6, nullptr, 10);
  }
  die("no VmRSS in /proc/self/status");
}

// The desired joint positions at time t: every joint moves on a slow sine of its own period around a
// working posture, so that the compensator and the plant work on every step.
void desired(double t, double q[], int dof) {
  static const double posture[6] = {0.0, -0.3, 0.5, 0.0, 0.6, 0.0};
  for (int j = 0; j < dof; ++j) {
    q[j] = posture[j % 6] + 0.2 * std::sin(2.0 * kPi * t / (7.0 + 3.0 * j));
  }
}

struct Run {
  std::uint64_t digest = 1469598103934665603ULL;  // FNV-1a of the bits of every output of every step
  long rss_start_kib = 0, rss_after_warm_up_kib = 0, rss_max_after_warm_up_kib = 0, rss_end_kib = 0;
  double wall_seconds = 0.0;
  void hash(const double* values, std::size_t count) {
    const auto* bytes = reinterpret_cast<const unsigned char*>(values);
    for (std::size_t i = 0; i < count * sizeof(double); ++i) {
      digest ^= bytes[i];
      digest *= 1099511628211ULL;
    }
  }
};

template <typename F>
F symbol(void* library, const char* name) {
  void* address = dlsym(library, name);
  if (!address) die(std::string("no ") + name + " in the FMU binary");
  return reinterpret_cast<F>(address);
}
#define FMI(library, name) symbol<decltype(&name)>(library, #name)

// The FMU's variable table, as its binary builds it from its resources (value references are indices).
jointcomp::fmu::VariableTable tableOf(const std::string& folder) {
  return jointcomp::fmu::loadFmuResources(folder + "/resources", JOINTCOMP_FMU_VERSION).table;
}
std::vector<std::uint32_t> references(const std::vector<int>& roles) { return {roles.begin(), roles.end()}; }

void logNothing(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...) {}
void logNothing3(fmi3InstanceEnvironment, fmi3Status, fmi3String, fmi3String) {}

// Steps an instance for `seconds`, through `step(t, q_desired, outputs)`, sampling the memory.
template <typename Step>
Run simulate(double seconds, int dof, Step step) {
  Run run;
  run.rss_start_kib = residentKiB();
  const auto started = std::chrono::steady_clock::now();
  const long steps = std::lround(seconds / kStep);
  const long steps_per_minute = std::lround(kMinute / kStep);
  std::vector<double> q(static_cast<std::size_t>(dof)), outputs(2 * static_cast<std::size_t>(dof));
  for (long k = 0; k < steps; ++k) {
    const double t = k * kStep;
    desired(t, q.data(), dof);
    step(t, q.data(), outputs.data());
    run.hash(outputs.data(), outputs.size());
    if ((k + 1) % steps_per_minute == 0) {
      const long rss = residentKiB();
      if (t + kStep <= kWarmUp) {
        run.rss_after_warm_up_kib = rss;
      } else if (rss > run.rss_max_after_warm_up_kib) {
        run.rss_max_after_warm_up_kib = rss;
      }
    }
  }
  run.rss_end_kib = residentKiB();
  run.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return run;
}

Run runFmi2(void* library, const std::string& folder, double seconds) {
  const jointcomp::fmu::VariableTable table = tableOf(folder);
  const int dof = table.dof();
  const std::string uri = "file://" + folder + "/resources";
  static const fmi2CallbackFunctions callbacks = {logNothing, nullptr, nullptr, nullptr, nullptr};
  fmi2Component c = FMI(library, fmi2Instantiate)("load", fmi2CoSimulation, table.instantiation_token.c_str(),
                                                  uri.c_str(), &callbacks, 0, 0);
  if (!c) die("fmi2Instantiate failed");
  const auto set = FMI(library, fmi2SetReal);
  const auto get = FMI(library, fmi2GetReal);
  const auto do_step = FMI(library, fmi2DoStep);
  const std::vector<std::uint32_t> q_desired = references(table.roles.q_desired);
  std::vector<std::uint32_t> observed = references(table.roles.q_link);
  for (std::uint32_t vr : references(table.roles.q_ref)) observed.push_back(vr);
  std::vector<double> q0(static_cast<std::size_t>(dof));
  desired(0.0, q0.data(), dof);
  if (FMI(library, fmi2SetupExperiment)(c, 0, 0.0, 0.0, 0, 0.0) != fmi2OK ||
      FMI(library, fmi2EnterInitializationMode)(c) != fmi2OK ||
      set(c, q_desired.data(), q_desired.size(), q0.data()) != fmi2OK ||
      FMI(library, fmi2ExitInitializationMode)(c) != fmi2OK) {
    die("FMI 2 initialisation failed");
  }
  const Run run = simulate(seconds, dof, [&](double t, const double* q, double* outputs) {
    if (set(c, q_desired.data(), q_desired.size(), q) != fmi2OK || do_step(c, t, kStep, 1) != fmi2OK ||
        get(c, observed.data(), observed.size(), outputs) != fmi2OK) {
      die("FMI 2 step failed at t = " + std::to_string(t));
    }
  });
  FMI(library, fmi2Terminate)(c);
  FMI(library, fmi2FreeInstance)(c);
  return run;
}

Run runFmi3(void* library, const std::string& folder, double seconds) {
  const jointcomp::fmu::VariableTable table = tableOf(folder);
  const int dof = table.dof();
  const std::string resources = folder + "/resources/";
  fmi3Instance instance =
      FMI(library, fmi3InstantiateCoSimulation)("load", table.instantiation_token.c_str(), resources.c_str(), false,
                                                false, false, false, nullptr, 0, nullptr, logNothing3, nullptr);
  if (!instance) die("fmi3InstantiateCoSimulation failed");
  const auto set = FMI(library, fmi3SetFloat64);
  const auto get = FMI(library, fmi3GetFloat64);
  const auto do_step = FMI(library, fmi3DoStep);
  const std::vector<std::uint32_t> q_desired = references(table.roles.q_desired);
  std::vector<std::uint32_t> observed = references(table.roles.q_link);
  for (std::uint32_t vr : references(table.roles.q_ref)) observed.push_back(vr);
  std::vector<double> q0(static_cast<std::size_t>(dof));
  desired(0.0, q0.data(), dof);
  if (FMI(library, fmi3EnterInitializationMode)(instance, false, 0.0, 0.0, false, 0.0) != fmi3OK ||
      set(instance, q_desired.data(), q_desired.size(), q0.data(), q0.size()) != fmi3OK ||
      FMI(library, fmi3ExitInitializationMode)(instance) != fmi3OK) {
    die("FMI 3 initialisation failed");
  }
  const Run run = simulate(seconds, dof, [&](double t, const double* q, double* outputs) {
    fmi3Boolean event = false, terminate = false, early = false;
    fmi3Float64 last = 0.0;
    if (set(instance, q_desired.data(), q_desired.size(), q, q_desired.size()) != fmi3OK ||
        do_step(instance, t, kStep, true, &event, &terminate, &early, &last) != fmi3OK ||
        get(instance, observed.data(), observed.size(), outputs, observed.size()) != fmi3OK) {
      die("FMI 3 step failed at t = " + std::to_string(t));
    }
  });
  FMI(library, fmi3Terminate)(instance);
  FMI(library, fmi3FreeInstance)(instance);
  return run;
}

void* openBinary(const std::string& folder, const char* platform) {
  const std::string path = folder + "/binaries/" + platform + "/jointcomp.so";
  void* library = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!library) die("cannot load " + path + ": " + dlerror());
  return library;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) die("usage: fmu_load <FMI 2 FMU folder> <FMI 3 FMU folder> [simulated seconds]");
  const double seconds = argc > 3 ? std::atof(argv[3]) : 3600.0;
  if (!(seconds > kWarmUp + kMinute)) die("the run must be longer than the warm-up and a minute");
  void* fmi2 = openBinary(argv[1], "linux64");
  void* fmi3 = openBinary(argv[2], "x86_64-linux");
  bool ok = true;
  std::uint64_t first_digest = 0;
  std::printf("%-6s %-4s %10s %12s %14s %16s %10s  %s\n", "FMI", "run", "wall [s]", "RSS start", "after warm-up",
              "max afterwards", "RSS end", "digest of all outputs");
  for (int version : {2, 3}) {
    for (int repeat = 1; repeat <= 2; ++repeat) {
      const Run run = version == 2 ? runFmi2(fmi2, argv[1], seconds) : runFmi3(fmi3, argv[2], seconds);
      std::printf("%-6d %-4d %10.1f %9ld KiB %10ld KiB %12ld KiB %6ld KiB  %016llx\n", version, repeat,
                  run.wall_seconds, run.rss_start_kib, run.rss_after_warm_up_kib, run.rss_max_after_warm_up_kib,
                  run.rss_end_kib, static_cast<unsigned long long>(run.digest));
      std::fflush(stdout);
      if (run.rss_max_after_warm_up_kib - run.rss_after_warm_up_kib > kAllowedGrowthKiB) {
        std::printf("  FAIL: the resident memory grew by %ld KiB after the warm-up (allowed %ld)\n",
                    run.rss_max_after_warm_up_kib - run.rss_after_warm_up_kib, kAllowedGrowthKiB);
        ok = false;
      }
      if (first_digest == 0) first_digest = run.digest;
      if (run.digest != first_digest) {
        std::printf("  FAIL: the outputs differ from the first run's\n");
        ok = false;
      }
    }
  }
  std::printf("%s: %.0f s of simulated time per run, %s\n", ok ? "PASS" : "FAIL", seconds,
              ok ? "memory flat and outputs identical across runs and FMI versions" : "see above");
  return ok ? 0 : 1;
}
