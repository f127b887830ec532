// The FMU's speed: doStep calls per second with a 1 ms and a 10 ms communication step on the paper's
// spiral, the real-time factor, and the overhead of the FMI layer over calling the plant and the
// compensator directly.
// The FMUs' binaries are dlopen-ed from the build tree (JOINTCOMP_FMU_DIR, set by bench/CMakeLists.txt).
//
// Per step, as a master does it: set the 6 desired joint positions, doStep(t, 1 ms), read the 6 link
// positions and the tool position. "Direct" does the same work on FlexibleJointPlant + Compensator
// (the sequence fmu/robot/robot_model.hpp documents). "AllOutputs" reads all 45 outputs per step.
// Targets (issue 17): at least 500x real time through the FMU with a 1 ms step, 1000x with a 10 ms step.
#include <dlfcn.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>

#include "fmu/description/variable_table.hpp"
#include "fmu/fmi2_api.hpp"
#include "fmu/fmi3_api.hpp"
#include "model/compensation/compensator.hpp"
#include "model/compensation/feed_rate.hpp"
#include "model/compensation/joint_trajectory.hpp"
#include "model/compensation/path.hpp"
#include "model/experiment/spiral_experiment.hpp"
#include "model/io/parameter_file.hpp"
#include "model/io/robot_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"
#include "model/robot/kinematics.hpp"

#ifndef JOINTCOMP_FMU_DIR
// bench/CMakeLists.txt sets JOINTCOMP_FMU_DIR when the FMUs are part of the build; without it there is
// nothing to measure, and the build of the other benchmarks must not break.
int main() {
  std::fprintf(stderr, "fmu_bench: built without JOINTCOMP_FMU_DIR (the build folder of fmu/); nothing to run\n");
  return 1;
}
#else

namespace {

using namespace jointcomp;

constexpr double kStep = 0.001;  // s, the communication step of the main cases; step_ms gives the others
constexpr int kDof = 6;
constexpr double kDegree = 3.14159265358979323846 / 180.0;

std::string fmuDir(int version) { return std::string(JOINTCOMP_FMU_DIR) + "/jointcomp_fmi" + std::to_string(version); }

struct Spiral {
  std::shared_ptr<const Robot> robot;
  std::vector<double> time;
  std::vector<JointVector> q;
};

Spiral planSpiral(double step) {
  Spiral result;
  result.robot = std::make_shared<const Robot>(loadRobotFile(fmuDir(2) + "/resources/robot.json"));
  FeedRateSpec feed;
  feed.controller_period = step;
  JointVector seed = JointVector::Zero(kDof);
  seed[1] = seed[2] = seed[4] = 60 * kDegree;
  const JointTrajectory trajectory =
      planJointTrajectory(*result.robot, planFeedRate(logarithmicSpiral(SpiralExperimentSpec::defaultSpiral()), feed),
                          toolPointingDown(), seed);
  result.time = trajectory.time;
  result.q = trajectory.q;
  return result;
}

// The spiral sampled every 1 ms (step_ms 1) or 10 ms (step_ms 10).
const Spiral& spiral(int step_ms = 1) {
  static const Spiral every_ms = planSpiral(kStep);
  static const Spiral every_10_ms = planSpiral(10 * kStep);
  return step_ms == 10 ? every_10_ms : every_ms;
}

// Value references from the FMU's variable table, as its binary builds it from its resources.
const jointcomp::fmu::VariableTable& fmuTable() {
  static const jointcomp::fmu::VariableTable table =
      jointcomp::fmu::loadFmuResources(fmuDir(2) + "/resources", JOINTCOMP_FMU_VERSION).table;
  return table;
}
std::uint32_t vrOf(const char* name) {
  const int index = fmuTable().indexOfName(name);
  if (index < 0) throw std::runtime_error(std::string("the FMU has no variable ") + name);
  return static_cast<std::uint32_t>(index);
}
const std::uint32_t kCompensation = vrOf("compensation");
const std::uint32_t kStepPastUpdates = vrOf("integrator.step_past_updates");
const std::vector<std::uint32_t> kQDesiredList(fmuTable().roles.q_desired.begin(), fmuTable().roles.q_desired.end());
const std::uint32_t* const kQDesired = kQDesiredList.data();
const std::vector<std::uint32_t> kReadBackList = [] {  // q_link, tool
  const jointcomp::fmu::Roles& r = fmuTable().roles;
  std::vector<std::uint32_t> vrs(r.q_link.begin(), r.q_link.end());
  vrs.insert(vrs.end(), r.tool_position.begin(), r.tool_position.end());
  return vrs;
}();
const std::uint32_t* const kReadBack = kReadBackList.data();
std::vector<std::uint32_t> allOutputs() {
  const jointcomp::fmu::Roles& r = fmuTable().roles;
  std::vector<std::uint32_t> vrs;
  for (const std::vector<int>* role :
       {&r.q_motor, &r.qd_motor, &r.q_link, &r.qd_link, &r.dq_predicted, &r.dq_actual, &r.q_ref}) {
    vrs.insert(vrs.end(), role->begin(), role->end());
  }
  vrs.insert(vrs.end(), r.tool_position.begin(), r.tool_position.end());
  return vrs;
}

void* openLibrary(int version) {
  const std::string path =
      fmuDir(version) + (version == 2 ? "/binaries/linux64/jointcomp.so" : "/binaries/x86_64-linux/jointcomp.so");
  void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!handle) throw std::runtime_error(std::string("dlopen: ") + dlerror());
  return handle;
}

template <typename F>
F symbol(void* library, const char* name) {
  void* p = dlsym(library, name);
  if (!p) throw std::runtime_error(std::string("dlsym ") + name);
  return reinterpret_cast<F>(p);
}

std::string guid(int version) {
  std::FILE* file = std::fopen((fmuDir(version) + "/modelDescription.xml").c_str(), "rb");
  if (!file) throw std::runtime_error("no modelDescription.xml");
  std::string text(1 << 16, '\0');
  text.resize(std::fread(text.data(), 1, text.size(), file));
  std::fclose(file);
  const std::string key = version == 2 ? "guid=\"" : "instantiationToken=\"";
  const std::size_t begin = text.find(key) + key.size();
  return text.substr(begin, text.find('"', begin) - begin);
}

void quiet2(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String, ...) {}
void quiet3(fmi3InstanceEnvironment, fmi3Status, fmi3String, fmi3String) {}

// One FMU instance of either version behind the few calls the benchmark makes.
class Fmu {
public:
  explicit Fmu(int version) : version_(version), library_(openLibrary(version)) {
    if (version == 2) {
      instantiate2_ = symbol<decltype(&fmi2Instantiate)>(library_, "fmi2Instantiate");
      free2_ = symbol<decltype(&fmi2FreeInstance)>(library_, "fmi2FreeInstance");
      setup2_ = symbol<decltype(&fmi2SetupExperiment)>(library_, "fmi2SetupExperiment");
      enter2_ = symbol<decltype(&fmi2EnterInitializationMode)>(library_, "fmi2EnterInitializationMode");
      exit2_ = symbol<decltype(&fmi2ExitInitializationMode)>(library_, "fmi2ExitInitializationMode");
      set2_ = symbol<decltype(&fmi2SetReal)>(library_, "fmi2SetReal");
      get2_ = symbol<decltype(&fmi2GetReal)>(library_, "fmi2GetReal");
      setInteger2_ = symbol<decltype(&fmi2SetInteger)>(library_, "fmi2SetInteger");
      step2_ = symbol<decltype(&fmi2DoStep)>(library_, "fmi2DoStep");
      callbacks_ = {quiet2, nullptr, nullptr, nullptr, nullptr};
      const std::string uri = "file://" + fmuDir(2) + "/resources/";
      instance_ = instantiate2_("bench", fmi2CoSimulation, guid(2).c_str(), uri.c_str(), &callbacks_, 0, 0);
    } else {
      instantiate3_ = symbol<decltype(&fmi3InstantiateCoSimulation)>(library_, "fmi3InstantiateCoSimulation");
      free3_ = symbol<decltype(&fmi3FreeInstance)>(library_, "fmi3FreeInstance");
      enter3_ = symbol<decltype(&fmi3EnterInitializationMode)>(library_, "fmi3EnterInitializationMode");
      exit3_ = symbol<decltype(&fmi3ExitInitializationMode)>(library_, "fmi3ExitInitializationMode");
      set3_ = symbol<decltype(&fmi3SetFloat64)>(library_, "fmi3SetFloat64");
      get3_ = symbol<decltype(&fmi3GetFloat64)>(library_, "fmi3GetFloat64");
      setInt64_3_ = symbol<decltype(&fmi3SetInt64)>(library_, "fmi3SetInt64");
      step3_ = symbol<decltype(&fmi3DoStep)>(library_, "fmi3DoStep");
      const std::string path = fmuDir(3) + "/resources/";
      instance_ = instantiate3_("bench", guid(3).c_str(), path.c_str(), false, false, false, false, nullptr, 0, nullptr,
                                quiet3, nullptr);
    }
    if (!instance_) throw std::runtime_error("instantiation failed");
  }
  ~Fmu() {
    if (version_ == 2)
      free2_(instance_);
    else
      free3_(instance_);
    dlclose(library_);
  }

  // step_past: the integrator.step_past_updates parameter, s.
  void initialise(long mode, double t0, const JointVector& q0, double step_past = 0.0) {
    if (version_ == 2) check(setup2_(instance_, 0, 0.0, t0, 0, 0.0));
    check(version_ == 2 ? int(enter2_(instance_)) : int(enter3_(instance_, false, 0.0, t0, false, 0.0)));
    setReals(&kStepPastUpdates, 1, &step_past);
    if (version_ == 2) {
      const int m = static_cast<int>(mode);
      check(setInteger2_(instance_, &kCompensation, 1, &m));
    } else {
      const std::int64_t m = mode;
      check(setInt64_3_(instance_, &kCompensation, 1, &m, 1));
    }
    setReals(kQDesired, kDof, q0.data());
    check(version_ == 2 ? int(exit2_(instance_)) : int(exit3_(instance_)));
  }
  void setReals(const std::uint32_t* vrs, std::size_t n, const double* values) {
    check(version_ == 2 ? int(set2_(instance_, vrs, n, values)) : int(set3_(instance_, vrs, n, values, n)));
  }
  void getReals(const std::uint32_t* vrs, std::size_t n, double* values) {
    check(version_ == 2 ? int(get2_(instance_, vrs, n, values)) : int(get3_(instance_, vrs, n, values, n)));
  }
  void doStep(double t, double h) {
    if (version_ == 2) {
      check(step2_(instance_, t, h, 1));
    } else {
      bool event = false, terminate = false, early = false;
      double last = 0.0;
      check(step3_(instance_, t, h, true, &event, &terminate, &early, &last));
    }
  }

private:
  static void check(int status) {
    if (status != 0) throw std::runtime_error("FMI call returned " + std::to_string(status));
  }
  int version_;
  void* library_;
  void* instance_ = nullptr;
  fmi2CallbackFunctions callbacks_{};
  decltype(&fmi2Instantiate) instantiate2_ = nullptr;
  decltype(&fmi2FreeInstance) free2_ = nullptr;
  decltype(&fmi2SetupExperiment) setup2_ = nullptr;
  decltype(&fmi2EnterInitializationMode) enter2_ = nullptr;
  decltype(&fmi2ExitInitializationMode) exit2_ = nullptr;
  decltype(&fmi2SetReal) set2_ = nullptr;
  decltype(&fmi2GetReal) get2_ = nullptr;
  decltype(&fmi2SetInteger) setInteger2_ = nullptr;
  decltype(&fmi2DoStep) step2_ = nullptr;
  decltype(&fmi3InstantiateCoSimulation) instantiate3_ = nullptr;
  decltype(&fmi3FreeInstance) free3_ = nullptr;
  decltype(&fmi3EnterInitializationMode) enter3_ = nullptr;
  decltype(&fmi3ExitInitializationMode) exit3_ = nullptr;
  decltype(&fmi3SetFloat64) set3_ = nullptr;
  decltype(&fmi3GetFloat64) get3_ = nullptr;
  decltype(&fmi3SetInt64) setInt64_3_ = nullptr;
  decltype(&fmi3DoStep) step3_ = nullptr;
};

void reportRates(benchmark::State& state, std::size_t steps, double step) {
  state.SetItemsProcessed(static_cast<std::int64_t>(steps));  // doStep calls per second
  state.counters["realtime_x"] =
      benchmark::Counter(static_cast<double>(steps) * step, benchmark::Counter::kIsRate);  // simulated s per s
}

// One communication step as a master makes it: set the desired joint positions, doStep, read the outputs.
// Not inlined: bench/count-instructions.sh counts the instructions of its calls (--toggle-collect).
[[gnu::noinline]] void fmuStep(Fmu& fmu, const Spiral& s, std::size_t k, const std::vector<std::uint32_t>& outputs,
                               bool all, double* read) {
  fmu.setReals(kQDesired, kDof, s.q[k].data());
  fmu.doStep(s.time[k], s.time[k + 1] - s.time[k]);
  if (all) {
    fmu.getReals(outputs.data(), outputs.size(), read);
  } else {
    fmu.getReals(kReadBack, kDof + 3, read);
  }
}

// version 2 or 3; range(1): 1 reads all outputs; range(2): the communication step in ms; range(3): how far
// past a communication point CVODE may step, in ms (integrator.step_past_updates, 10 by default; 0: it stops at
// each).
void BM_FmuSpiral(benchmark::State& state) {
  const int version = static_cast<int>(state.range(0));
  const bool all = state.range(1) != 0;
  const int step_ms = static_cast<int>(state.range(2));
  const double step_past = static_cast<double>(state.range(3)) * 1e-3;
  const Spiral& s = spiral(step_ms);
  const std::vector<std::uint32_t> outputs = allOutputs();
  std::vector<double> read(outputs.size());
  std::unique_ptr<Fmu> fmu;
  std::size_t k = s.time.size();  // start a run at the first iteration
  std::size_t steps = 0;
  for (auto _ : state) {
    if (k + 1 >= s.time.size()) {
      state.PauseTiming();
      fmu.reset();
      fmu = std::make_unique<Fmu>(version);
      fmu->initialise(2, s.time[0], s.q[0], step_past);
      k = 0;
      state.ResumeTiming();
    }
    fmuStep(*fmu, s, k, outputs, all, read.data());
    benchmark::DoNotOptimize(read.data());
    ++k;
    ++steps;
  }
  reportRates(state, steps, step_ms * kStep);
}

// The FMI layer alone: a step's set of the inputs and get of the outputs, with nothing to compute (the
// values are those already set, the outputs already up to date). What the layer adds to each step
// beyond the model's own work, without the noise of the plant's timing.
void BM_FmuCallsOnly(benchmark::State& state) {
  const int version = static_cast<int>(state.range(0));
  const Spiral& s = spiral();
  Fmu fmu(version);
  fmu.initialise(2, s.time[0], s.q[0]);
  fmu.doStep(s.time[0], kStep);
  double read[kDof + 3];
  for (auto _ : state) {
    fmu.setReals(kQDesired, kDof, s.q[0].data());
    fmu.getReals(kReadBack, kDof + 3, read);
    benchmark::DoNotOptimize(read);
  }
}
BENCHMARK(BM_FmuCallsOnly)->ArgName("fmi")->Arg(2)->Arg(3)->Unit(benchmark::kNanosecond);

// fmuStep's work without the FMI layer, on the plant and the compensator: the FMU's velocity estimate
// (fmu/robot/held_steps.cpp: the slope now of the parabola through the last three inputs, the difference quotient
// after the first step, zero at the first), compensation, the plant's update and advance, and the outputs.
// Not inlined, for bench/count-instructions.sh.
[[gnu::noinline]] void directStep(FlexibleJointPlant& plant, Compensator& compensator, JointContext& ctx,
                                  JointVector& reference, const Spiral& s, std::size_t k, bool has_last, double* read) {
  const double t = s.time[k];
  JointVector v = JointVector::Zero(kDof);
  if (k >= 2) {
    const double last = t - s.time[k - 1], earlier = s.time[k - 1] - s.time[k - 2], both = last + earlier;
    v = s.q[k] * ((2.0 * last + earlier) / (last * both)) - s.q[k - 1] * (both / (last * earlier)) +
        s.q[k - 2] * (last / (earlier * both));
  } else if (has_last) {
    v = (s.q[k] - s.q[k - 1]) / (t - s.time[k - 1]);
  }
  ctx.q = s.q[k];
  ctx.velocity = v;
  ctx.time = t;
  compensator.compensate(ctx, reference);
  plant.setReference(reference, v);
  plant.advance(t + (s.time[k + 1] - t));
  const JointVector q = plant.linkPositions();
  const Eigen::Vector3d tool = toolPosition(*s.robot, q);
  for (int j = 0; j < kDof; ++j) read[j] = q[j];
  for (int i = 0; i < 3; ++i) read[kDof + i] = tool[i];
}

// The same work without the FMI layer; range(0): 1 with PlantOptions::smooth_reference (not what the FMU
// uses; to compare), range(1): the communication step in ms, range(2): PlantOptions::step_past_updates_s in ms.
void BM_DirectSpiral(benchmark::State& state) {
  PlantOptions options;
  options.smooth_reference = state.range(0) != 0;
  const int step_ms = static_cast<int>(state.range(1));
  options.step_past_updates_s = static_cast<double>(state.range(2)) * 1e-3;
  const Spiral& s = spiral(step_ms);
  const std::string parameters = fmuDir(2) + "/resources/parameters.json";
  const ParameterSet loaded = loadParameterSet(parameters, s.robot);
  const JointErrorModel& nominal = loaded.model;
  const std::vector<DriveParameters>& drives = loaded.drives;
  const EffectMask mask = nominal.loadsAnd({"compliance", "transmission_error"});
  std::unique_ptr<FlexibleJointPlant> plant;
  Compensator compensator(nominal, mask);
  JointContext ctx(kDof);
  JointVector reference;
  bool has_last = false;
  double read[kDof + 3];
  std::size_t k = s.time.size();
  std::size_t steps = 0;
  // CVODE's counts over the whole spirals this run completed: a spiral's start-up (from rest, CVODE's history
  // afresh) costs more steps than its middle, so a partial last spiral would misstate them.
  PlantStatistics whole;
  std::size_t whole_steps = 0, whole_spirals = 0;
  for (auto _ : state) {
    if (k + 1 >= s.time.size()) {
      state.PauseTiming();
      if (plant) {
        const PlantStatistics done = plant->statistics();
        whole.steps += done.steps;
        whole.rhs_evaluations += done.rhs_evaluations;
        whole.nonlinear_iterations += done.nonlinear_iterations;
        whole.linear_solver_setups += done.linear_solver_setups;
        whole.jacobian_evaluations += done.jacobian_evaluations;
        whole.updates_stepped_past += done.updates_stepped_past;
        whole.updates_restarted += done.updates_restarted;
        whole_steps += k;
        ++whole_spirals;
      }
      plant = std::make_unique<FlexibleJointPlant>(nominal, drives, options);
      ctx.q = s.q[0];
      ctx.velocity = JointVector::Zero(kDof);
      ctx.time = s.time[0];
      compensator.compensate(ctx, reference);
      plant->setToolWrench(Vector6::Zero());
      plant->reset(reference, s.time[0]);
      has_last = false;
      k = 0;
      state.ResumeTiming();
    }
    directStep(*plant, compensator, ctx, reference, s, k, has_last, read);
    benchmark::DoNotOptimize(read);
    has_last = true;
    ++k;
    ++steps;
  }
  reportRates(state, steps, step_ms * kStep);
  // Of the whole spirals; of the partial one only when the run completed none.
  const PlantStatistics statistics = whole_spirals > 0 ? whole : plant->statistics();
  const double communication_steps = static_cast<double>(std::max<std::size_t>(whole_spirals > 0 ? whole_steps : k, 1));
  state.counters["whole_spirals_counted"] = static_cast<double>(whole_spirals);
  state.counters["cvode_steps_per_communication_step"] = static_cast<double>(statistics.steps) / communication_steps;
  state.counters["rhs_per_communication_step"] = static_cast<double>(statistics.rhs_evaluations) / communication_steps;
  state.counters["newton_iterations_per_communication_step"] =
      static_cast<double>(statistics.nonlinear_iterations) / communication_steps;
  state.counters["setups_per_communication_step"] =
      static_cast<double>(statistics.linear_solver_setups) / communication_steps;
  state.counters["jacobians_per_communication_step"] =
      static_cast<double>(statistics.jacobian_evaluations) / communication_steps;
  state.counters["updates_stepped_past_fraction"] =
      static_cast<double>(statistics.updates_stepped_past) / communication_steps;
  state.counters["updates_restarted_fraction"] =
      static_cast<double>(statistics.updates_restarted) / communication_steps;
}
// The spirals' benchmarks, per communication step. Each runs for 2 s, or, with whole_spirals > 0, exactly
// that many whole spirals: the same work in every run, for instruction counts (bench/count-instructions.sh).
void registerSpirals(int whole_spirals) {
  for (const int step_ms : {1, 10}) {
    const auto span = [&](benchmark::internal::Benchmark* b) {
      b->Unit(benchmark::kMicrosecond);
      if (whole_spirals > 0) {
        b->Iterations(static_cast<benchmark::IterationCount>(whole_spirals) *
                      static_cast<benchmark::IterationCount>(spiral(step_ms).time.size() - 1));
      } else {
        b->MinTime(2.0);
      }
    };
    benchmark::internal::Benchmark* fmu = benchmark::RegisterBenchmark("BM_FmuSpiral", BM_FmuSpiral);
    fmu->ArgNames({"fmi", "all_outputs", "step_ms", "past_ms"});
    for (const int past_ms : {0, 10}) {
      fmu->Args({2, 0, step_ms, past_ms})->Args({3, 0, step_ms, past_ms});
      if (step_ms == 1 && past_ms == 0) fmu->Args({2, 1, step_ms, past_ms});
    }
    span(fmu);
    benchmark::internal::Benchmark* direct = benchmark::RegisterBenchmark("BM_DirectSpiral", BM_DirectSpiral);
    direct->ArgNames({"smooth", "step_ms", "past_ms"})
        ->Args({0, step_ms, 0})
        ->Args({1, step_ms, 0})
        ->Args({0, step_ms, 10});
    span(direct);
  }
}

// Remembers each benchmark's CPU time per step, to print the FMI layer's overhead at the end. CPU time,
// not wall-clock time: on a shared machine it is what the step costs.
class Reporter : public benchmark::ConsoleReporter {
public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs) {
      // In the benchmark's unit: us for the spirals, ns for the calls alone.
      if (run.run_type == Run::RT_Iteration) per_step[run.benchmark_name()] = run.GetAdjustedCPUTime();
    }
    ConsoleReporter::ReportRuns(runs);
  }
  std::map<std::string, double> per_step;
};

}  // namespace

int main(int argc, char** argv) {
  // --whole_spirals=N (ours, taken out before Google Benchmark reads the rest): see registerSpirals.
  int whole_spirals = 0;
  int kept = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    const std::string flag = "--whole_spirals=";
    if (argument.rfind(flag, 0) != 0) {
      argv[kept++] = argv[i];
      continue;
    }
    const std::string count = argument.substr(flag.size());
    if (count.empty() || count.size() > 3 || count.find_first_not_of("0123456789") != std::string::npos ||
        std::stoi(count) < 1) {
      std::fprintf(stderr, "fmu_bench: --whole_spirals takes a count from 1 to 999, not '%s'\n", count.c_str());
      return 1;
    }
    whole_spirals = std::stoi(count);
  }
  argc = kept;
  argv[argc] = nullptr;
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  spiral(1);  // planned before any timing
  spiral(10);
  registerSpirals(whole_spirals);
  Reporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  // Per communication step: the direct run of that step, then the FMUs against it.
  for (const auto& [step_ms, past_ms] : {std::pair{1, 0}, std::pair{10, 0}, std::pair{1, 10}, std::pair{10, 10}}) {
    const std::string key = "step_ms:" + std::to_string(step_ms) + "/past_ms:" + std::to_string(past_ms);
    auto ofStep = [&](const std::string& name) {  // the key, followed by the end or by "/min_time:..."
      const std::size_t at = name.find(key);
      return at != std::string::npos && (at + key.size() == name.size() || name[at + key.size()] == '/');
    };
    double direct = 0.0;
    for (const auto& [name, us] : reporter.per_step) {
      if (name.rfind("BM_DirectSpiral/smooth:0", 0) == 0 && ofStep(name)) direct = us;
    }
    if (!(direct > 0.0)) continue;
    const double step_us = step_ms * kStep * 1e6;
    std::printf("\nRX170 spiral, %d ms communication step, stiffness + kinematic compensation (CPU time per step)%s\n",
                step_ms,
                past_ms > 0 ? (", CVODE stepping up to " + std::to_string(past_ms) +
                               " ms past the communication points (integrator.step_past_updates, the FMU's default)")
                                  .c_str()
                            : ", CVODE stopping at every communication point (integrator.step_past_updates = 0)");
    std::printf("  %-46s %8.2f us/step %6.0fx real time\n", "direct (plant + compensator)", direct, step_us / direct);
    for (const auto& [name, us] : reporter.per_step) {
      if (name.rfind("BM_FmuSpiral", 0) != 0 || !ofStep(name)) continue;
      std::printf("  %-46s %8.2f us/step %6.0fx real time, FMI layer %+.2f us/step (%+.1f %%)\n", name.c_str(), us,
                  step_us / us, us - direct, 100.0 * (us - direct) / direct);
    }
  }
  for (const auto& [name, us] : reporter.per_step) {
    if (name.rfind("BM_FmuCallsOnly", 0) == 0) {
      std::printf("  %-46s %8.0f ns/step (set 6 inputs, get 9 outputs, nothing to compute)\n", name.c_str(), us);
    }
  }
  std::printf("  targets: at least 500x real time through the FMU at 1 ms, 1000x at 10 ms\n");
  benchmark::Shutdown();
  return 0;
}

#endif  // JOINTCOMP_FMU_DIR
