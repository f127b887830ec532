// Time and memory of residual discovery (discoverEffects) on Series A of the IPA UR10 laser-tracker data
// (shared/data/ipa-ur10, about 12,000 rows), one core: the whole call as `jointcomp discover` makes it (the
// textbook base, every candidate family: offset, compliance, geometric, instrument scale, nonlinear
// compliance, harmonics of orders 1..4 and those the spectrum scan proposes, periodic tables of 16 to 128
// knots with their priors, pairs, backlash, hysteresis, payload, thermal and time drift, link bending) and
// Series B held out, with A's and B's RMS after it and the process's peak resident memory; and how the time
// grows with the rows (the first 1/4, 1/2 and all rows) and with the candidates (harmonic orders 1, 4 and 8).
// Without the data the benchmarks are skipped with a message.
#include <algorithm>
#include <fstream>
#include <memory>
#include <string>

#include <sys/resource.h>

#include <benchmark/benchmark.h>

#include "bench/ipa_ur10_data.hpp"

#include "model/identify/discovery.hpp"
#include "model/io/ipa_ur10_import.hpp"
#include "model/robot/load_urdf.hpp"

namespace {

using namespace jointcomp;

using namespace bench_ipa;

MeasurementCampaign firstRows(const MeasurementCampaign& c, std::size_t rows) {
  MeasurementCampaign out = c;
  rows = std::min(rows, c.size());
  out.time.resize(rows);
  out.command.resize(rows);
  out.position.resize(rows);
  out.temperature.resize(rows);
  out.wrench.resize(rows);
  out.payload.resize(rows);
  if (out.has_measured_angles) out.measured_angles.resize(rows);
  return out;
}

// range(0): rows in quarters of Series A (4 = all); range(1): maximum harmonic order.
void BM_DiscoverSeriesA(benchmark::State& state) {
  if (!haveData()) {
    state.SkipWithError(("skipped: the IPA UR10 data not found at " + ipa("Series_A/measurements_grid.csv")).c_str());
    return;
  }
  const MeasurementCampaign a = firstRows(seriesA(), seriesA().size() * static_cast<std::size_t>(state.range(0)) / 4);
  DiscoveryOptions options;
  options.base_geometry = true;
  options.max_harmonic_order = static_cast<int>(state.range(1));
  int steps = 0, candidates = 0;
  double fitted_mm = 0.0, heldout_mm = 0.0;
  for (auto _ : state) {
    const DiscoveryResult result = discoverEffects(prior(), {a}, {seriesB()}, options);
    steps = static_cast<int>(result.steps.size());
    candidates = result.candidates;
    fitted_mm = result.final_state.fitted.rms * 1e3;
    heldout_mm = result.final_state.heldout.front().rms * 1e3;
    benchmark::DoNotOptimize(result.final_state.fitted.rms);
  }
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  state.counters["rows"] = static_cast<double>(a.size());
  state.counters["candidates"] = candidates;
  state.counters["steps"] = steps;
  state.counters["A_rms_mm"] = fitted_mm;
  state.counters["B_rms_mm"] = heldout_mm;
  state.counters["peak_rss_MB"] = static_cast<double>(usage.ru_maxrss) / 1024.0;  // of the process so far
}
BENCHMARK(BM_DiscoverSeriesA)
    ->Args({4, 4})
    ->Args({1, 4})
    ->Args({2, 4})
    ->Args({4, 1})
    ->Args({4, 8})
    ->Unit(benchmark::kSecond)
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
