// Accuracy metrics of tracked paths, as scored in the paper.
#include "api_support.hpp"
#include "model/compensation/metrics.hpp"

using namespace jointcomp;
using namespace jointcomp::capi;

namespace {

std::vector<double> deviations(const double* z, int32_t z_len) {
  requirePointer(z, "z");
  if (z_len < 1) invalid("z_len is " + std::to_string(z_len) + ", must be at least 1");
  requireFinite(z, z_len, "z");
  return std::vector<double>(z, z + z_len);
}

}  // namespace

extern "C" {

jc_status jc_accuracy_metrics(const double* errors, int32_t errors_len, double* metrics, int32_t metrics_len) {
  return CAPI_ENTRY({
    requirePointer(errors, "errors");
    if (errors_len < 3 || errors_len % 3 != 0) {
      invalid("errors_len is " + std::to_string(errors_len) + ", must be a positive multiple of 3 (points x 3)");
    }
    requireFinite(errors, errors_len, "errors");
    requireOutput(metrics, metrics_len, 5, "metrics", "Ra, Rz, RMS, max, mean");
    std::vector<Eigen::Vector3d> vectors(static_cast<std::size_t>(errors_len / 3));
    for (std::size_t k = 0; k < vectors.size(); ++k) {
      vectors[k] = Eigen::Vector3d(errors[3 * k], errors[3 * k + 1], errors[3 * k + 2]);
    }
    const AccuracyMetrics result = accuracyMetrics(vectors);
    const double values[5] = {result.ra, result.rz, result.rms, result.max, result.mean};
    std::copy(values, values + 5, metrics);
  });
}

jc_status jc_average_absolute_deviation(const double* z, int32_t z_len, double* ra) {
  return CAPI_ENTRY({
    const std::vector<double> values = deviations(z, z_len);
    requirePointer(ra, "ra");
    *ra = averageAbsoluteDeviation(values);
  });
}

jc_status jc_peak_to_peak_deviation(const double* z, int32_t z_len, double* rz) {
  return CAPI_ENTRY({
    const std::vector<double> values = deviations(z, z_len);
    requirePointer(rz, "rz");
    *rz = peakToPeakDeviation(values);
  });
}

}  // extern "C"
