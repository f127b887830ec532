// Accuracy metrics of a tracked path, as scored in the paper (Olabi et al., ICIT 2012, Table II):
// Ra and Rz of the Z deviation, plus the usual statistics of the 3-D error norm.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace jointcomp {

struct AccuracyMetrics {
  double ra = 0.0;    // m, mean |z_k| of the Z components
  double rz = 0.0;    // m, max z_k - min z_k of the Z components
  double rms = 0.0;   // m, sqrt(mean |e_k|^2)
  double max = 0.0;   // m, max |e_k|
  double mean = 0.0;  // m, mean |e_k| (of the norms, not of the vectors)
};

// Ra = mean |z_k| of Z deviations z_k (m). Throws InvalidArgument for an empty input or a non-finite
// z_k (naming k).
double averageAbsoluteDeviation(const std::vector<double>& z_deviations);

// Rz = max z_k - min z_k of Z deviations z_k (m). Same errors as averageAbsoluteDeviation.
double peakToPeakDeviation(const std::vector<double>& z_deviations);

// All metrics of a sequence of 3-D error vectors e_k = measured - nominal (m); Ra and Rz use their
// Z components. Throws InvalidArgument for an empty input or a non-finite e_k (naming k).
AccuracyMetrics accuracyMetrics(const std::vector<Eigen::Vector3d>& errors);

}  // namespace jointcomp
