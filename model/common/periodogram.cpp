#include "model/common/periodogram.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>

#include "model/common/median.hpp"

namespace jointcomp {

OrderPeak strongestOrder(const std::vector<double>& signal, const std::vector<double>& angle, int first_order,
                         int last_order) {
  OrderPeak best;
  const std::size_t rows = std::min(signal.size(), angle.size());
  if (rows < 8 || first_order < 1 || last_order < first_order) return best;
  std::vector<double> amplitude;
  for (int order = first_order; order <= last_order; ++order) {
    Eigen::Matrix3d gram = Eigen::Matrix3d::Zero();
    Eigen::Vector3d right = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < rows; ++i) {
      const Eigen::Vector3d basis(1.0, std::cos(order * angle[i]), std::sin(order * angle[i]));
      gram += basis * basis.transpose();
      right += basis * signal[i];
    }
    const Eigen::Vector3d solution = gram.completeOrthogonalDecomposition().solve(right);
    amplitude.push_back(std::hypot(solution[1], solution[2]));
    if (amplitude.back() > best.amplitude) {
      best.order = order;
      best.amplitude = amplitude.back();
    }
  }
  // The median needs a few orders to stand for the noise.
  if (amplitude.size() >= 3) {
    best.stands_out = best.amplitude > kOrderStandsOut * median(std::move(amplitude));
  }
  return best;
}

}  // namespace jointcomp
