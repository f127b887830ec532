#include "model/compensation/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "model/common/errors.hpp"

namespace jointcomp {

namespace {

void requireValidDeviations(const std::vector<double>& z_deviations, const char* function) {
  if (z_deviations.empty()) {
    throw InvalidArgument(std::string(function) + ": z_deviations is empty");
  }
  for (std::size_t k = 0; k < z_deviations.size(); ++k) {
    if (!std::isfinite(z_deviations[k])) {
      throw InvalidArgument(std::string(function) + ": z_deviations[" + std::to_string(k) + "] is not finite");
    }
  }
}

}  // namespace

double averageAbsoluteDeviation(const std::vector<double>& z_deviations) {
  requireValidDeviations(z_deviations, "averageAbsoluteDeviation");
  double sum = 0.0;
  for (const double z : z_deviations) sum += std::abs(z);
  return sum / static_cast<double>(z_deviations.size());
}

double peakToPeakDeviation(const std::vector<double>& z_deviations) {
  requireValidDeviations(z_deviations, "peakToPeakDeviation");
  const auto [lowest, highest] = std::minmax_element(z_deviations.begin(), z_deviations.end());
  return *highest - *lowest;
}

AccuracyMetrics accuracyMetrics(const std::vector<Eigen::Vector3d>& errors) {
  if (errors.empty()) {
    throw InvalidArgument("accuracyMetrics: errors is empty");
  }
  for (std::size_t k = 0; k < errors.size(); ++k) {
    if (!errors[k].allFinite()) {
      throw InvalidArgument("accuracyMetrics: errors[" + std::to_string(k) + "] is not finite");
    }
  }

  AccuracyMetrics metrics;
  double sum_abs_z = 0.0;
  double sum_norm = 0.0;
  double sum_squared_norm = 0.0;
  double lowest_z = errors.front().z();
  double highest_z = errors.front().z();
  for (const Eigen::Vector3d& error : errors) {
    const double norm = error.norm();
    sum_abs_z += std::abs(error.z());
    sum_norm += norm;
    sum_squared_norm += error.squaredNorm();
    metrics.max = std::max(metrics.max, norm);
    lowest_z = std::min(lowest_z, error.z());
    highest_z = std::max(highest_z, error.z());
  }
  const auto count = static_cast<double>(errors.size());
  metrics.ra = sum_abs_z / count;
  metrics.rz = highest_z - lowest_z;
  metrics.rms = std::sqrt(sum_squared_norm / count);
  metrics.mean = sum_norm / count;
  return metrics;
}

}  // namespace jointcomp
