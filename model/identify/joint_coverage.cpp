#include "model/identify/joint_coverage.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>

#include "model/common/errors.hpp"
#include "model/common/median.hpp"

namespace jointcomp {

JointCoverage jointCoverage(const std::vector<JointVector>& rows, double half_width) {
  if (rows.empty()) throw InvalidArgument("joint coverage: no rows");
  if (!(half_width > 0.0) || !std::isfinite(half_width))
    throw InvalidArgument("joint coverage: half width must be > 0");
  const Eigen::Index n = rows.front().size();
  JointCoverage coverage;
  coverage.half_width = half_width;
  coverage.visited.resize(static_cast<std::size_t>(n));
  for (Eigen::Index j = 0; j < n; ++j) {
    std::vector<double> angles;
    angles.reserve(rows.size());
    for (std::size_t k = 0; k < rows.size(); ++k) {
      if (rows[k].size() != n) throw InvalidArgument("joint coverage: row " + std::to_string(k) + " has another size");
      if (!std::isfinite(rows[k][j])) {
        throw InvalidArgument("joint coverage: row " + std::to_string(k) + ", joint " + std::to_string(j + 1) +
                              ": angle not finite");
      }
      angles.push_back(rows[k][j]);
    }
    std::sort(angles.begin(), angles.end());
    std::vector<AngleInterval>& out = coverage.visited[static_cast<std::size_t>(j)];
    for (double a : angles) {
      if (!out.empty() && a - half_width <= out.back().high) {
        out.back().high = a + half_width;
      } else {
        out.push_back({a - half_width, a + half_width});
      }
    }
  }
  return coverage;
}

bool JointCoverage::covers(int joint, double angle) const {
  const std::vector<AngleInterval>& intervals = visited.at(static_cast<std::size_t>(joint));
  auto it = std::upper_bound(intervals.begin(), intervals.end(), angle,
                             [](double a, const AngleInterval& i) { return a < i.low; });
  return it != intervals.begin() && angle <= std::prev(it)->high;
}

double JointCoverage::fractionOutside(int joint, const std::vector<JointVector>& rows) const {
  if (rows.empty()) return 0.0;
  std::size_t outside = 0;
  for (const JointVector& q : rows) outside += covers(joint, q[joint]) ? 0 : 1;
  return static_cast<double>(outside) / static_cast<double>(rows.size());
}

std::string JointCoverage::describe(int joint) const {
  std::string text;
  constexpr double kDeg = 180.0 / 3.14159265358979323846;
  for (const AngleInterval& i : visited.at(static_cast<std::size_t>(joint))) {
    char part[64];
    std::snprintf(part, sizeof(part), "%s%.1f..%.1f", text.empty() ? "" : ", ", i.low * kDeg, i.high * kDeg);
    text += part;
  }
  return text;
}

double medianDistanceToNearest(const std::vector<JointVector>& fitted, const std::vector<JointVector>& rows,
                               int max_rows, int max_fitted) {
  if (fitted.empty() || rows.empty() || max_rows < 1 || max_fitted < 1)
    throw InvalidArgument(
        "distance to the nearest fitted pose: no fitted rows, no rows, or max_rows or max_fitted below 1");
  const Eigen::Index n = fitted.front().size();
  const auto check = [n](const std::vector<JointVector>& v, const char* what) {
    for (std::size_t k = 0; k < v.size(); ++k) {
      if (v[k].size() != n || !v[k].allFinite())
        throw InvalidArgument(std::string("distance to the nearest fitted pose: ") + what + " row " +
                              std::to_string(k) + " has another size or a non-finite angle");
    }
  };
  check(fitted, "fitted");
  check(rows, "held-out");
  const std::size_t stride =
      (rows.size() + static_cast<std::size_t>(max_rows) - 1) / static_cast<std::size_t>(max_rows);
  const std::size_t fitted_stride =
      (fitted.size() + static_cast<std::size_t>(max_fitted) - 1) / static_cast<std::size_t>(max_fitted);
  std::vector<double> nearest;
  for (std::size_t i = 0; i < rows.size(); i += stride) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t f = 0; f < fitted.size(); f += fitted_stride) {
      best = std::min(best, (fitted[f] - rows[i]).squaredNorm());
    }
    nearest.push_back(std::sqrt(best));
  }
  return median(std::move(nearest));
}

}  // namespace jointcomp
