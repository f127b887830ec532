// The spiral experiment's results as jc_spiral_experiment and jc_spiral_experiment_truth hand them out:
// metrics (3 runs x Ra, Rz, RMS, max, mean) and, when asked for, the errors (3 runs x m samples x 3).
#pragma once

#include <cstdint>
#include <vector>

#include "model/experiment/spiral_experiment.hpp"

namespace jointcomp::capi {

// Run r's metrics into metrics[5r..5r+4] and, when errors is not null, its errors into errors[3rm..].
inline void writeSpiralRun(int r, const AccuracyMetrics& run, const std::vector<Eigen::Vector3d>& error, std::int64_t m,
                           double* metrics, double* errors) {
  const double values[5] = {run.ra, run.rz, run.rms, run.max, run.mean};
  for (int i = 0; i < 5; ++i) metrics[5 * r + i] = values[i];
  if (!errors) return;
  for (std::int64_t k = 0; k < m; ++k) {
    for (int i = 0; i < 3; ++i) errors[(r * m + k) * 3 + i] = error[static_cast<std::size_t>(k)][i];
  }
}

inline void writeSpiralRuns(const SpiralExperimentResult& result, std::int64_t m, double* metrics, double* errors) {
  for (int r = 0; r < 3; ++r) writeSpiralRun(r, result.runs[r].metrics, result.runs[r].error, m, metrics, errors);
}

inline void writeSpiralRuns(const SpiralDraw& draw, std::int64_t m, double* metrics, double* errors) {
  for (int r = 0; r < 3; ++r) writeSpiralRun(r, draw.metrics[r], draw.error[r], m, metrics, errors);
}

}  // namespace jointcomp::capi
