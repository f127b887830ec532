// The spiral experiment's results as jc_spiral_experiment and jc_spiral_experiment_truth hand them out:
// metrics (3 runs x Ra, Rz, RMS, max, mean) and, when asked for, the errors (3 runs x m samples x 3).
#pragma once

#include <cstdint>

#include "model/experiment/spiral_experiment.hpp"

namespace jointcomp::capi {

inline void writeSpiralRuns(const SpiralExperimentResult& result, std::int64_t m, double* metrics, double* errors) {
  for (int r = 0; r < 3; ++r) {
    const AccuracyMetrics& run = result.runs[r].metrics;
    const double values[5] = {run.ra, run.rz, run.rms, run.max, run.mean};
    for (int i = 0; i < 5; ++i) metrics[5 * r + i] = values[i];
    if (!errors) continue;
    for (std::int64_t k = 0; k < m; ++k) {
      for (int i = 0; i < 3; ++i) errors[(r * m + k) * 3 + i] = result.runs[r].error[k][i];
    }
  }
}

}  // namespace jointcomp::capi
