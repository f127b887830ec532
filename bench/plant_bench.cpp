// The flexible-joint plant: how fast it simulates the paper's spiral, and what one right-hand side costs
// next to forward dynamics (ours and KDL's), on the RX170, in one binary and one run.
//
//   BM_Ours_PlantSpiral/2        the whole experiment (runSpiralExperiment with the drives of
//                                model/params/rx170.json, default PlantOptions: 3 runs of the spiral on the
//                                plant); counters: real_time_factor (motion seconds simulated per wall-clock
//                                second spent simulating, planning and compensation excluded), and per
//                                experiment CVODE's steps, rhs_evaluations (those of its difference-quotient
//                                Jacobians included), jacobian_rhs (those alone), jacobian_evaluations,
//                                newton_iterations and lu_setups (factorisations of I - gamma J).
//   BM_Ours_PlantSpiralSimulation  the simulation alone on CPU time (the three runs replayed from the
//                                references of one experiment); real_time_factor_cpu: motion seconds
//                                simulated per CPU second. Issue 17's target: at least 1000.
//   BM_Ours_PlantSpiral/1, /0    the same with SUNDIALS' dense LU instead of the structured Newton solver
//                                (/1), and also with CVODE's difference-quotient Jacobians (/0: the plant
//                                before issue 17); compare them in one run, e.g. with
//                                --benchmark_repetitions=5 --benchmark_enable_random_interleaving=true
//   BM_Ours_PlantRightHandSide   one FlexibleJointPlant::derivative() (link forward dynamics, transmission
//                                error and its sensitivity, loads, controller)
//   BM_Ours_PlantJacobian/1      one FlexibleJointPlant::jacobian() (what CVODE's Newton iterations use);
//                                /0: with the link dynamics' q and qd columns by forward differences (before)
//   BM_Ours_ForwardDynamics      jointcomp::forwardDynamics
//   BM_Kdl_ForwardDynamics       KDL::ChainFdSolver_RNE::CartToJnt on the same URDF chain, base_link -> flange
//
// The per-call benchmarks cycle through 64 seeded states (joints inside their limits, rates up to the
// velocity limits, springs stretched by up to 1 mrad); the torques for forward dynamics come from inverse
// dynamics of seeded accelerations. Before timing, ours and KDL's forward dynamics are compared on every
// state (exit 2 if they differ by more than 1e-9 relative). "allocs_per_call" counts heap allocations in
// the timed loop (bench/support/allocation_counting.cpp).
#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <kdl/chain.hpp>
#include <kdl/chainfdsolver_recursive_newton_euler.hpp>
#include <kdl/jntarray.hpp>
#include <kdl/tree.hpp>
#include <kdl_parser/kdl_parser.hpp>

#include "bench/support/allocation_counting.hpp"
#include "model/effects/perturbation.hpp"
#include "model/experiment/spiral_experiment.hpp"
#include "model/io/parameter_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/load_urdf.hpp"

namespace {

using namespace jointcomp;

constexpr int kStates = 64;  // a power of two: the loops cycle with a mask
constexpr std::uint64_t kSeed = 20240611;
const char* const kUrdf = JOINTCOMP_DATA_DIR "/robots/rx170.urdf";
const char* const kParameters = JOINTCOMP_DATA_DIR "/params/rx170.json";

using jointcomp::bench::AllocationCounter;

struct Sample {
  std::vector<double> y;   // plant state [q, qd, p, pd, integral]
  JointVector q, qd, tau;  // forward-dynamics inputs
  KDL::JntArray kq, kqd, ktau;
};

struct Fixture {
  std::shared_ptr<const Robot> robot;
  std::unique_ptr<JointErrorModel> model;
  std::vector<DriveParameters> drives;
  KDL::Tree tree;
  KDL::Chain chain;  // KDL's solvers keep a reference: it lives here and never moves
  std::unique_ptr<KDL::ChainFdSolver_RNE> fd;
  KDL::Wrenches no_wrenches;
  std::vector<Sample> samples;
};

[[noreturn]] void fail(const std::string& message) {
  std::cerr << "plant_bench: " << message << std::endl;
  std::exit(2);
}

KDL::JntArray toKdl(const JointVector& v) {
  KDL::JntArray a(static_cast<unsigned int>(v.size()));
  for (int i = 0; i < v.size(); ++i) a(i) = v[i];
  return a;
}

std::unique_ptr<Fixture> buildFixture() {
  auto f = std::make_unique<Fixture>();
  try {
    f->robot = std::make_shared<const Robot>(loadRobotFromUrdfFile(kUrdf));
    ParameterSet loaded = loadParameterSet(kParameters, f->robot);
    f->model = std::make_unique<JointErrorModel>(std::move(loaded.model));
    f->drives = std::move(loaded.drives);
  } catch (const std::exception& error) {
    fail(std::string("cannot load the RX170: ") + error.what());
  }
  if (!kdl_parser::treeFromFile(kUrdf, f->tree) || !f->tree.getChain("base_link", "flange", f->chain)) {
    fail(std::string("KDL cannot read the chain base_link -> flange of ") + kUrdf);
  }
  const Robot& robot = *f->robot;
  const int n = robot.dof();
  if (static_cast<int>(f->chain.getNrOfJoints()) != n) fail("KDL's chain and ours differ in joint count");
  f->fd = std::make_unique<KDL::ChainFdSolver_RNE>(
      f->chain, KDL::Vector(robot.gravity.x(), robot.gravity.y(), robot.gravity.z()));
  f->no_wrenches.assign(f->chain.getNrOfSegments(), KDL::Wrench::Zero());

  std::mt19937_64 random(kSeed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  RobotWorkspace ws(robot);
  double largest_difference = 0.0;
  for (int k = 0; k < kStates; ++k) {
    Sample s;
    s.q.resize(n);
    s.qd.resize(n);
    JointVector qdd(n);
    s.y.assign(5 * n, 0.0);
    for (int i = 0; i < n; ++i) {
      const Joint& joint = robot.joints[i];
      s.q[i] = 0.5 * (joint.lower + joint.upper) + 0.5 * (joint.upper - joint.lower) * unit(random);
      s.qd[i] = joint.velocity_limit * unit(random);
      qdd[i] = 5.0 * unit(random);
      s.y[i] = s.q[i];
      s.y[n + i] = s.qd[i];
      s.y[2 * n + i] = s.q[i] + 1e-3 * unit(random);
      s.y[3 * n + i] = s.qd[i] + 0.01 * unit(random);
      s.y[4 * n + i] = 1e-5 * unit(random);
    }
    inverseDynamics(robot, ws, s.q, s.qd, qdd, s.tau);
    s.kq = toKdl(s.q);
    s.kqd = toKdl(s.qd);
    s.ktau = toKdl(s.tau);
    // Cross-check ours against KDL (outside timing).
    JointVector ours(n);
    forwardDynamics(robot, ws, s.q, s.qd, s.tau, ours);
    KDL::JntArray theirs(static_cast<unsigned int>(n));
    if (f->fd->CartToJnt(s.kq, s.kqd, s.ktau, f->no_wrenches, theirs) < 0) fail("KDL's forward dynamics failed");
    for (int i = 0; i < n; ++i) {
      largest_difference = std::max(largest_difference, std::abs(ours[i] - theirs(i)) / (1.0 + std::abs(theirs(i))));
      if (std::abs(ours[i] - theirs(i)) > 1e-9 * (1.0 + std::abs(theirs(i)))) {
        fail("forward dynamics differ at state " + std::to_string(k) + ", joint " + std::to_string(i + 1) + ": ours " +
             std::to_string(ours[i]) + ", KDL " + std::to_string(theirs(i)));
      }
    }
    f->samples.push_back(std::move(s));
  }
  std::cerr << "plant_bench: forward dynamics cross-check against KDL passed at " << kStates
            << " states (largest relative difference " << largest_difference << ", tolerance 1e-9)" << std::endl;
  return f;
}

Fixture& fixture() {
  static const std::unique_ptr<Fixture> instance = buildFixture();
  return *instance;
}

// ---------------------------------------------------------------------------------------------------
// The spiral on the plant.

void runSpiralBenchmark(benchmark::State& state, const SpiralExperimentSpec& spec);

void BM_Ours_PlantSpiral(benchmark::State& state) {
  SpiralExperimentSpec spec;
  spec.drives = fixture().drives;
  spec.plant.analytic_jacobian = state.range(0) >= 1;
  spec.plant.structured_linear_solver = state.range(0) >= 2;
  runSpiralBenchmark(state, spec);
}
BENCHMARK(BM_Ours_PlantSpiral)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

void runSpiralBenchmark(benchmark::State& state, const SpiralExperimentSpec& spec) {
  Fixture& f = fixture();
  double motion = 0.0, simulating = 0.0;
  PlantStatistics total;
  for (auto _ : state) {
    const SpiralExperimentResult result = runSpiralExperiment(*f.model, spec);
    motion += 3.0 * (result.planned.time.back() - result.planned.time.front());
    simulating += result.simulation_seconds;
    total.steps += result.plant_statistics.steps;
    total.rhs_evaluations += result.plant_statistics.rhs_evaluations;
    total.jacobian_evaluations += result.plant_statistics.jacobian_evaluations;
    total.jacobian_rhs_evaluations += result.plant_statistics.jacobian_rhs_evaluations;
    total.nonlinear_iterations += result.plant_statistics.nonlinear_iterations;
    total.linear_solver_setups += result.plant_statistics.linear_solver_setups;
    benchmark::DoNotOptimize(result.runs[2].metrics.ra);
  }
  const double experiments = static_cast<double>(state.iterations());
  state.counters["real_time_factor"] = motion / simulating;
  state.counters["motion_s"] = motion / experiments;
  state.counters["simulating_s"] = simulating / experiments;
  state.counters["steps"] = static_cast<double>(total.steps) / experiments;
  state.counters["rhs_evaluations"] = static_cast<double>(total.rhs_evaluations) / experiments;
  state.counters["jacobian_evaluations"] = static_cast<double>(total.jacobian_evaluations) / experiments;
  state.counters["jacobian_rhs"] = static_cast<double>(total.jacobian_rhs_evaluations) / experiments;
  state.counters["newton_iterations"] = static_cast<double>(total.nonlinear_iterations) / experiments;
  state.counters["lu_setups"] = static_cast<double>(total.linear_solver_setups) / experiments;
  state.counters["rhs_per_motion_s"] = static_cast<double>(total.rhs_evaluations) / motion;
}

// The simulation alone, on CPU time: the three runs' references of one experiment (computed before timing)
// replayed on a plant of the experiment's truth, as runSpiralExperiment drives it. Before timing, the
// replay must reproduce the experiment's link positions bit for bit (exit 2 otherwise).
void BM_Ours_PlantSpiralSimulation(benchmark::State& state) {
  Fixture& f = fixture();
  SpiralExperimentSpec spec;
  spec.drives = f.drives;
  spec.plant.jacobian_reuse_steps = state.range(0);
  spec.plant.newton_setup_steps = state.range(1);
  spec.plant.newton_setup_gamma_change = static_cast<double>(state.range(2)) / 100.0;
  const SpiralExperimentResult experiment = runSpiralExperiment(*f.model, spec);
  const JointErrorModel truth = perturbedModel(*f.model, spec.truth);
  FlexibleJointPlant plant(truth, f.drives, spec.plant);
  const JointTrajectory& planned = experiment.planned;
  const std::size_t count = planned.size();
  auto replay = [&](int r, bool compare) {
    const SpiralRun& run = experiment.runs[r];
    plant.reset(run.reference[0], planned.time[0]);
    for (std::size_t k = 0; k < count; ++k) {
      plant.setReference(run.reference[k], planned.qd[k]);
      if (compare && plant.linkPositions() != run.actual[k]) {
        fail("the replay of run " + std::to_string(r) + " differs from the experiment at sample " + std::to_string(k));
      }
      if (k + 1 < count) plant.advance(planned.time[k + 1]);
    }
  };
  for (int r = 0; r < 3; ++r) replay(r, true);
  double motion = 0.0;
  for (auto _ : state) {
    for (int r = 0; r < 3; ++r) replay(r, false);
    benchmark::DoNotOptimize(plant.state());
    motion += 3.0 * (planned.time.back() - planned.time.front());
  }
  // Motion seconds per CPU second (a rate over the benchmark's CPU time).
  state.counters["real_time_factor_cpu"] = benchmark::Counter(motion, benchmark::Counter::kIsRate);
  const PlantStatistics& statistics = experiment.plant_statistics;  // of the whole experiment's three runs
  state.counters["steps"] = static_cast<double>(statistics.steps);
  state.counters["rhs_evaluations"] = static_cast<double>(statistics.rhs_evaluations);
  state.counters["jacobian_evaluations"] = static_cast<double>(statistics.jacobian_evaluations);
  state.counters["newton_iterations"] = static_cast<double>(statistics.nonlinear_iterations);
  state.counters["lu_setups"] = static_cast<double>(statistics.linear_solver_setups);
}
// Arguments: PlantOptions' jacobian_reuse_steps, newton_setup_steps, newton_setup_gamma_change in percent;
// the defaults first, then CVODE's own (51, 20, 30) and the settings they were chosen against.
BENCHMARK(BM_Ours_PlantSpiralSimulation)
    ->Args({200, 40, 60})
    ->Args({51, 20, 30})
    ->Args({20, 20, 30})
    ->Args({1000, 20, 30})
    ->Args({200, 20, 30})
    ->Args({100, 20, 60})
    ->Args({51, 20, 100})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

// ---------------------------------------------------------------------------------------------------
// One right-hand side against forward dynamics.

void BM_Ours_PlantRightHandSide(benchmark::State& state) {
  Fixture& f = fixture();
  FlexibleJointPlant plant(*f.model, f.drives);
  plant.reset(f.samples[0].q);
  std::vector<double> ydot(static_cast<std::size_t>(plant.stateSize()));
  std::size_t k = 0;
  const AllocationCounter allocations;
  for (auto _ : state) {
    plant.derivative(0.0, f.samples[k & (kStates - 1)].y.data(), ydot.data());
    benchmark::DoNotOptimize(ydot.data());
    benchmark::ClobberMemory();
    ++k;
  }
  allocations.report(state);
}
BENCHMARK(BM_Ours_PlantRightHandSide);

void BM_Ours_PlantJacobian(benchmark::State& state) {
  Fixture& f = fixture();
  PlantOptions options;
  options.analytic_link_derivatives = state.range(0) != 0;
  FlexibleJointPlant plant(*f.model, f.drives, options);
  plant.reset(f.samples[0].q);
  std::vector<double> jacobian(static_cast<std::size_t>(plant.stateSize() * plant.stateSize()));
  std::size_t k = 0;
  const AllocationCounter allocations;
  for (auto _ : state) {
    plant.jacobian(0.0, f.samples[k & (kStates - 1)].y.data(), jacobian.data());
    benchmark::DoNotOptimize(jacobian.data());
    benchmark::ClobberMemory();
    ++k;
  }
  allocations.report(state);
}
BENCHMARK(BM_Ours_PlantJacobian)->Arg(0)->Arg(1);

void BM_Ours_ForwardDynamics(benchmark::State& state) {
  Fixture& f = fixture();
  RobotWorkspace ws(*f.robot);
  JointVector qdd(f.robot->dof());
  std::size_t k = 0;
  const AllocationCounter allocations;
  for (auto _ : state) {
    const Sample& s = f.samples[k++ & (kStates - 1)];
    forwardDynamics(*f.robot, ws, s.q, s.qd, s.tau, qdd);
    benchmark::DoNotOptimize(qdd);
  }
  allocations.report(state);
}
BENCHMARK(BM_Ours_ForwardDynamics);

void BM_Kdl_ForwardDynamics(benchmark::State& state) {
  Fixture& f = fixture();
  KDL::JntArray qdd(static_cast<unsigned int>(f.robot->dof()));
  std::size_t k = 0;
  const AllocationCounter allocations;
  for (auto _ : state) {
    const Sample& s = f.samples[k++ & (kStates - 1)];
    benchmark::DoNotOptimize(f.fd->CartToJnt(s.kq, s.kqd, s.ktau, f.no_wrenches, qdd));
    benchmark::DoNotOptimize(qdd.data);
  }
  allocations.report(state);
}
BENCHMARK(BM_Kdl_ForwardDynamics);

}  // namespace

int main(int argc, char** argv) {
  fixture();  // load and cross-check before anything is timed
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
