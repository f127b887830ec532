// Time to calibrate the UR10 kinematics on all of Series A of the IPA laser-tracker data
// (shared/data/ipa-ur10, 11,911 rows): the whole calibrateGeometry call (frame fit of the nominal robot,
// identifiability analysis of 57 candidate parameters, least-squares and robust Levenberg-Marquardt fits,
// covariance), the same on Series A and B together (a tracker frame each), the importer of the raw file,
// and the frame-only re-fit of held-out Series B.
// The data are read from $JOINTCOMP_SHARED/data/ipa-ur10; without them the benchmarks are skipped with a message.
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "bench/ipa_ur10_data.hpp"

#include "model/identify/geometric_calibration.hpp"
#include "model/io/ipa_ur10_import.hpp"
#include "model/robot/load_urdf.hpp"

namespace {

using namespace jointcomp;

using namespace bench_ipa;

void BM_CalibrateSeriesA(benchmark::State& state) {
  if (!haveData()) {
    state.SkipWithError(("skipped: the IPA UR10 data not found at " + ipa("Series_A/measurements_grid.csv")).c_str());
    return;
  }
  const MeasurementCampaign& a = seriesA();
  GeometricCalibrationResult result;
  for (auto _ : state) {
    result = calibrateGeometry(prior(), a);
    benchmark::DoNotOptimize(result.error_after.data());
  }
  state.counters["rows"] = result.used_rows;
  state.counters["parameters"] = static_cast<double>(result.free.size());
  state.counters["lm_iterations"] = result.iterations;
  state.counters["rms_before_mm"] = result.before.rms * 1e3;
  state.counters["rms_after_mm"] = result.after.rms * 1e3;
}
BENCHMARK(BM_CalibrateSeriesA)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// Series A and B in one calibration, each with its own tracker frame (grouping into set-ups included).
void BM_CalibrateSeriesAAndB(benchmark::State& state) {
  if (!haveData()) {
    state.SkipWithError(("skipped: the IPA UR10 data not found at " + ipa("Series_A/measurements_grid.csv")).c_str());
    return;
  }
  const std::vector<MeasurementCampaign> both = {seriesA(), seriesB()};
  GeometricCalibrationResult result;
  for (auto _ : state) {
    result = calibrateGeometry(prior(), both);
    benchmark::DoNotOptimize(result.error_after.data());
  }
  state.counters["rows"] = result.used_rows;
  state.counters["setups"] = result.estimate.setUpCount();
  state.counters["parameters"] = static_cast<double>(result.free.size());
  state.counters["rms_after_mm"] = result.after.rms * 1e3;
}
BENCHMARK(BM_CalibrateSeriesAAndB)->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_ImportSeriesA(benchmark::State& state) {
  if (!haveData()) {
    state.SkipWithError(("skipped: the IPA UR10 data not found at " + ipa("Series_A/measurements_grid.csv")).c_str());
    return;
  }
  for (auto _ : state) {
    MeasurementCampaign campaign =
        importIpaUr10(ipa("Series_A/measurements_grid.csv"), ipa("Series_A/Trafo_TM_F_init.txt"));
    benchmark::DoNotOptimize(campaign.position.data());
  }
}
BENCHMARK(BM_ImportSeriesA)->Unit(benchmark::kMillisecond);

void BM_HoldoutFrameFitSeriesB(benchmark::State& state) {
  if (!haveData()) {
    state.SkipWithError(("skipped: the IPA UR10 data not found at " + ipa("Series_A/measurements_grid.csv")).c_str());
    return;
  }
  const GeometricCalibrationResult calibration = calibrateGeometry(prior(), seriesA());
  HoldoutEvaluation evaluation;
  for (auto _ : state) {
    evaluation = evaluateOnCampaign(prior(), calibration.estimate, seriesB(), true);
    benchmark::DoNotOptimize(evaluation.error.data());
  }
  state.counters["rows"] = evaluation.statistics.rows;
  state.counters["rms_after_mm"] = evaluation.statistics.rms * 1e3;
}
BENCHMARK(BM_HoldoutFrameFitSeriesB)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
