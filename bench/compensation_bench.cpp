// Compensation throughput: trajectory points per second per core over the paper's spiral, all effects
// on, iterated to 1e-12 rad; next to the same computation with KDL's gravity solver, in the same run.
#include <benchmark/benchmark.h>

#include <kdl/chaindynparam.hpp>
#include <kdl_parser/kdl_parser.hpp>

#include <memory>
#include <stdexcept>

#include "bench/support/allocation_counting.hpp"
#include "model/compensation/compensator.hpp"
#include "model/experiment/spiral_experiment.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/load_urdf.hpp"

namespace {

using namespace jointcomp;

struct Fixture {
  std::shared_ptr<const Robot> robot;
  std::unique_ptr<JointErrorModel> model;
  JointTrajectory trajectory;
  KDL::Chain chain;

  Fixture() {
    const std::string urdf = JOINTCOMP_DATA_DIR "/robots/rx170.urdf";
    robot = std::make_shared<const Robot>(loadRobotFromUrdfFile(urdf));
    model = std::make_unique<JointErrorModel>(loadParameterFile(JOINTCOMP_DATA_DIR "/params/rx170.json", robot));
    const SpiralExperimentSpec spec;
    const std::vector<FeedRateSample> samples = planFeedRate(logarithmicSpiral(spec.spiral), spec.feed_rate);
    JointVector seed = JointVector::Zero(6);
    seed << 0.0, 1.05, 1.05, 0.0, 1.05, 0.0;
    trajectory = planJointTrajectory(*robot, samples, toolPointingDown(), seed);
    KDL::Tree tree;
    if (!kdl_parser::treeFromFile(urdf, tree) || !tree.getChain("base_link", "flange", chain)) {
      throw std::runtime_error("KDL could not read " + urdf);
    }
  }
};

const Fixture& fixture() {
  static const Fixture instance;
  return instance;
}

// Compensates the spiral's points in path order, one per benchmark iteration, with `compensate_point`
// (compensator, ctx, index, reference) -> FixedPointReport; counts allocations (0 per call, issue 17) and
// the fixed-point iterations per point.
template <typename CompensatePoint>
void compensateSpiralPoints(benchmark::State& state, CompensatePoint compensate_point) {
  const Fixture& f = fixture();
  Compensator compensator(*f.model, f.model->allEffects(), FixedPointOptions{1e-12, 50});
  JointContext ctx(6);
  JointVector reference;
  std::size_t k = 0;
  int iterations = 0;
  const jointcomp::bench::AllocationCounter allocations;
  for (auto _ : state) {
    ctx.q = f.trajectory.q[k];
    ctx.velocity = f.trajectory.qd[k];
    iterations += compensate_point(compensator, ctx, k, reference).iterations;
    benchmark::DoNotOptimize(reference.data());
    if (++k == f.trajectory.size()) k = 0;
  }
  allocations.report(state);
  state.SetItemsProcessed(state.iterations());
  state.counters["fixed_point_iterations"] =
      benchmark::Counter(static_cast<double>(iterations) / static_cast<double>(state.iterations()));
}

// Each point on its own (compensate, as compensateTrajectory and the C API do).
void BM_Ours_CompensateSpiralPoint(benchmark::State& state) {
  compensateSpiralPoints(state, [](Compensator& compensator, JointContext& ctx, std::size_t, JointVector& reference) {
    return compensator.compensate(ctx, reference);
  });
}
BENCHMARK(BM_Ours_CompensateSpiralPoint);

// The same points in path order, each started from the previous point's correction (compensateFrom; a
// caller's own loop over a path may, compensateTrajectory keeps compensate() per point so that its references
// equal its points' bit for bit): the throughput of compensating a whole trajectory in order.
void BM_Ours_CompensateSpiralPath(benchmark::State& state) {
  JointVector correction = JointVector::Zero(6);
  compensateSpiralPoints(
      state, [&correction](Compensator& compensator, JointContext& ctx, std::size_t k, JointVector& reference) {
        // The path's first point has no predecessor (nor has the first after the wrap-around).
        const FixedPointReport report =
            k == 0 ? compensator.compensate(ctx, reference) : compensator.compensateFrom(ctx, correction, reference);
        for (int j = 0; j < 6; ++j) correction[j] = ctx.q[j] - reference[j];
        return report;
      });
}
BENCHMARK(BM_Ours_CompensateSpiralPath);

// The dynamic compensation (model/dynamic_compensation/dynamic_compensation.hpp) of the whole 30 s spiral at the
// paper's feed rate and at ten times it, with the parameter file's drives: closed form and refinement against the
// nominal plant, one core (target: under 1 s at the paper's feed rate).
void BM_Ours_DynamicCompensationSpiral(benchmark::State& state) {
  const Fixture& f = fixture();
  const std::vector<DriveParameters> drives = loadParameterSet(JOINTCOMP_DATA_DIR "/params/rx170.json", f.robot).drives;
  SpiralExperimentSpec spec;
  const double speed_up = static_cast<double>(state.range(0));
  spec.feed_rate.speed *= speed_up;
  spec.feed_rate.acceleration *= speed_up;
  spec.feed_rate.jerk *= speed_up;
  const JointTrajectory planned = planSpiralTrajectory(*f.robot, spec.spiral, spec.feed_rate);
  std::vector<JointVector> reference, velocity;
  int runs = 0;
  for (auto _ : state) {
    runs = compensateDynamically(*f.model, drives, planned, reference, velocity).iterations;
    benchmark::DoNotOptimize(reference.data());
  }
  state.counters["plant_runs"] = runs;
  state.counters["samples"] = static_cast<double>(planned.size());
  state.counters["motion_s"] = planned.time.back();
}
BENCHMARK(BM_Ours_DynamicCompensationSpiral)->Arg(1)->Arg(10)->Unit(benchmark::kMillisecond);

// The same fixed point, with the load torque from KDL's gravity solver (plus the same spring balancer).
void BM_Kdl_CompensateSpiralPoint(benchmark::State& state) {
  const Fixture& f = fixture();
  const JointErrorModel& model = *f.model;
  const EffectMask mask = model.allEffects();
  KDL::ChainDynParam dynamics(f.chain, KDL::Vector(0.0, 0.0, -9.81));
  KDL::JntArray q_kdl(6), gravity(6);
  RobotWorkspace ws(model.robot());
  JointContext ctx(6);
  JointVector reference, dq;
  std::size_t k = 0;
  for (auto _ : state) {
    ctx.q = f.trajectory.q[k];
    ctx.velocity = f.trajectory.qd[k];
    for (int j = 0; j < 6; ++j) q_kdl(j) = ctx.q[j];
    dynamics.JntToGravity(q_kdl, gravity);
    // KDL's G(q) of tau = M qdd + C qd + G is the torque the joints carry, as ours.
    for (int j = 0; j < 6; ++j) ctx.load_torque[j] = gravity(j);
    for (int i = 0; i < model.effectCount(); ++i) {
      if (((mask >> i) & 1U) && model.effect(i).role() == EffectRole::Load) {
        model.effect(i).addLoadTorque(model.robot(), ws, ctx);
      }
    }
    ctx.command = ctx.q;
    for (int iteration = 0; iteration < 50; ++iteration) {
      updateMotorAngles(model, ctx);
      dq.setZero(6);
      addSelectedJointErrors(model, mask, ctx, dq);
      reference = ctx.q - dq;
      const double change = (reference - ctx.command).cwiseAbs().maxCoeff();
      ctx.command = reference;
      if (change <= 1e-12) break;
    }
    benchmark::DoNotOptimize(reference.data());
    if (++k == f.trajectory.size()) k = 0;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Kdl_CompensateSpiralPoint);

}  // namespace

BENCHMARK_MAIN();
