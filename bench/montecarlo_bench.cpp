// One Monte Carlo draw of the paper's spiral (jointcomp montecarlo, jc_spiral_job_run) against its floor, the
// three compensations of the spiral it follows (issue 44: a quasi-static draw at most 3 times their cost).
// Both are timed in the same iterations, alternately, on the thread's CPU clock: a loaded machine slows
// both alike, and the ratio is what the target is about.
//   montecarlo_bench --benchmark_filter=DrawAgainstCompensations
#include <benchmark/benchmark.h>

#include <time.h>

#include <memory>
#include <string>

#include "bench/support/allocation_counting.hpp"
#include "model/experiment/spiral_experiment.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/load_urdf.hpp"

namespace {

using namespace jointcomp;

struct Fixture {
  std::shared_ptr<const Robot> robot;
  std::unique_ptr<JointErrorModel> nominal;
  std::unique_ptr<JointErrorModel> truth;
  SpiralExperimentSpec spec;
  PreparedSpiral prepared;

  Fixture() {
    robot = std::make_shared<const Robot>(loadRobotFromUrdfFile(JOINTCOMP_DATA_DIR "/robots/rx170.urdf"));
    nominal = std::make_unique<JointErrorModel>(loadParameterFile(JOINTCOMP_DATA_DIR "/params/rx170.json", robot));
    truth = std::make_unique<JointErrorModel>(perturbedModel(*nominal, spec.truth));  // the main job's truth
    prepared = prepareSpiralRuns(*nominal, spec);  // quasi-static: the spec has no drives
  }
};

const Fixture& fixture() {
  static const Fixture instance;
  return instance;
}

double threadSeconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

// The spiral's three compensations, as prepareSpiralRuns makes them (done once per job and worker).
void compensateThreeRuns(const Fixture& f, std::vector<JointVector>& reference) {
  for (int r = 0; r < 3; ++r) {
    const TrajectoryCompensationReport report =
        compensateTrajectory(*f.nominal, spiralRunMask(*f.nominal, r), f.prepared.planned.q, f.prepared.planned.qd,
                             reference, f.spec.compensation);
    benchmark::DoNotOptimize(report);
  }
}

// Per iteration one draw (drawSpiralRuns with a kept SpiralDraw and a new tracker seed, as a worker's batch
// does) and the three compensations; counters: the CPU milliseconds of each, their ratio, and the draw's heap
// allocations (a draw reuses its SpiralDraw's vectors: a few small ones only, none of the path's size).
void BM_DrawAgainstCompensations(benchmark::State& state) {
  const Fixture& f = fixture();
  SpiralExperimentSpec spec = f.spec;
  SpiralDraw draw;
  std::vector<JointVector> reference;
  drawSpiralRuns(f.prepared, *f.truth, spec, draw);  // the draw's vectors grow once
  compensateThreeRuns(f, reference);
  double draw_seconds = 0.0, compensation_seconds = 0.0;
  std::uint64_t draw_allocations = 0;
  for (auto _ : state) {
    ++spec.noise_seed;
    const std::uint64_t allocations = bench::allocationCount();
    double started = threadSeconds();
    drawSpiralRuns(f.prepared, *f.truth, spec, draw);
    draw_seconds += threadSeconds() - started;
    draw_allocations += bench::allocationCount() - allocations;
    benchmark::DoNotOptimize(draw.metrics.data());
    started = threadSeconds();
    compensateThreeRuns(f, reference);
    compensation_seconds += threadSeconds() - started;
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["draw_ms"] = 1e3 * draw_seconds / n;
  state.counters["compensations_ms"] = 1e3 * compensation_seconds / n;
  state.counters["draw_over_compensations"] = draw_seconds / compensation_seconds;
  state.counters["draw_allocs"] = static_cast<double>(draw_allocations) / n;
}
BENCHMARK(BM_DrawAgainstCompensations)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// The three compensations alone, and the draw alone below (for callgrind: bench/count-instructions.sh counts
// compensateTrajectory and drawSpiralRuns per call).
void BM_ThreeCompensations(benchmark::State& state) {
  const Fixture& f = fixture();
  std::vector<JointVector> reference;
  for (auto _ : state) compensateThreeRuns(f, reference);
}
BENCHMARK(BM_ThreeCompensations)->Unit(benchmark::kMillisecond);

void BM_Draw(benchmark::State& state) {
  const Fixture& f = fixture();
  SpiralExperimentSpec spec = f.spec;
  SpiralDraw draw;
  for (auto _ : state) {
    ++spec.noise_seed;
    drawSpiralRuns(f.prepared, *f.truth, spec, draw);
    benchmark::DoNotOptimize(draw.metrics.data());
  }
}
BENCHMARK(BM_Draw)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
