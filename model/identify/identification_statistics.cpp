#include "model/identify/identification_statistics.hpp"

#include <cmath>
#include <limits>

#include <Eigen/SVD>

#include "model/common/errors.hpp"

namespace jointcomp {

LinearFit weightedLeastSquares(const Eigen::MatrixXd& a, const Eigen::VectorXd& y, const Eigen::VectorXd& sigma,
                               double rank_tolerance) {
  const Eigen::Index rows = a.rows();
  const Eigen::Index cols = a.cols();
  if (y.size() != rows || sigma.size() != rows) throw InvalidArgument("least squares: A, y and sigma differ in rows");
  if (cols == 0) throw InvalidArgument("least squares: no unknowns");
  if (!a.allFinite() || !y.allFinite()) throw InvalidArgument("least squares: A or y holds a value that is not finite");
  for (Eigen::Index k = 0; k < rows; ++k) {
    if (!(sigma[k] > 0.0) || !std::isfinite(sigma[k])) {
      throw InvalidArgument("least squares: sigma of row " + std::to_string(k) + " is not positive and finite");
    }
  }
  const Eigen::VectorXd weight = sigma.cwiseInverse();
  Eigen::MatrixXd weighted = weight.asDiagonal() * a;
  const Eigen::VectorXd weighted_y = weight.cwiseProduct(y);
  Eigen::VectorXd column_scale(cols);
  for (Eigen::Index c = 0; c < cols; ++c) {
    const double norm = weighted.col(c).norm();
    column_scale[c] = norm > 0.0 ? 1.0 / norm : 1.0;
  }
  weighted = weighted * column_scale.asDiagonal();

  LinearFit fit;
  const Eigen::BDCSVD<Eigen::MatrixXd> svd(weighted, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd& s = svd.singularValues();
  const double largest = s.size() > 0 ? s[0] : 0.0;
  fit.rank = 0;
  for (Eigen::Index i = 0; i < s.size(); ++i) {
    if (s[i] > rank_tolerance * largest && s[i] > 0.0) ++fit.rank;
  }
  fit.dof = static_cast<int>(rows - cols);
  if (fit.rank < cols) {
    // The column of V for the smallest singular value (or beyond the row count) spans what A misses.
    Eigen::VectorXd direction;
    if (rows < cols) {
      const Eigen::JacobiSVD<Eigen::MatrixXd> full(weighted, Eigen::ComputeFullV);
      direction = full.matrixV().col(cols - 1);
    } else {
      direction = svd.matrixV().col(cols - 1);
    }
    fit.null_direction = direction.normalized();
    return fit;
  }
  const Eigen::VectorXd inverse_s = s.cwiseInverse();
  const Eigen::VectorXd scaled_x = svd.matrixV() * (inverse_s.asDiagonal() * (svd.matrixU().transpose() * weighted_y));
  fit.coefficients = column_scale.cwiseProduct(scaled_x);
  const Eigen::MatrixXd v_scaled = column_scale.asDiagonal() * svd.matrixV() * inverse_s.asDiagonal();
  fit.unscaled_covariance = v_scaled * v_scaled.transpose();
  fit.residuals = y - a * fit.coefficients;
  fit.rss = weight.cwiseProduct(fit.residuals).squaredNorm();
  fit.scale2 = fit.dof > 0 ? fit.rss / fit.dof : std::numeric_limits<double>::quiet_NaN();
  fit.covariance = fit.unscaled_covariance * fit.scale2;
  return fit;
}

double normalQuantile(double p) {
  if (!(p > 0.0 && p < 1.0)) throw InvalidArgument("normal quantile: p must lie in (0, 1)");
  // Bisection on the CDF 0.5 erfc(-x / sqrt 2): slow but exact to the last bits, and rarely called.
  double low = -40.0;
  double high = 40.0;
  for (int i = 0; i < 200 && high - low > 1e-15 * std::max(1.0, std::abs(low)); ++i) {
    const double middle = 0.5 * (low + high);
    const double cdf = 0.5 * std::erfc(-middle / std::sqrt(2.0));
    (cdf < p ? low : high) = middle;
  }
  return 0.5 * (low + high);
}

double incompleteBeta(double x, double a, double b) {
  if (!(a > 0.0 && b > 0.0)) throw InvalidArgument("incomplete beta: a and b must be positive");
  if (!(x >= 0.0 && x <= 1.0)) throw InvalidArgument("incomplete beta: x must lie in [0, 1]");
  if (x == 0.0 || x == 1.0) return x;
  const double log_front = std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x);
  // The continued fraction converges fast for x < (a + 1) / (a + b + 2); use the symmetry otherwise.
  if (x > (a + 1.0) / (a + b + 2.0)) return 1.0 - incompleteBeta(1.0 - x, b, a);
  // Modified Lentz evaluation of the continued fraction (Numerical Recipes 6.4).
  constexpr double kTiny = 1e-300;
  double c = 1.0;
  double d = 1.0 - (a + b) * x / (a + 1.0);
  if (std::abs(d) < kTiny) d = kTiny;
  d = 1.0 / d;
  double h = d;
  for (int m = 1; m <= 500; ++m) {
    const double m2 = 2.0 * m;
    double numerator = m * (b - m) * x / ((a + m2 - 1.0) * (a + m2));
    d = 1.0 + numerator * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1.0 + numerator / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    h *= d * c;
    numerator = -(a + m) * (a + b + m) * x / ((a + m2) * (a + m2 + 1.0));
    d = 1.0 + numerator * d;
    if (std::abs(d) < kTiny) d = kTiny;
    c = 1.0 + numerator / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1.0) < 1e-15) break;
  }
  return std::exp(log_front) * h / a;
}

double studentTCdf(double t, double dof) {
  if (!(dof > 0.0)) throw InvalidArgument("Student t: degrees of freedom must be positive");
  if (std::isinf(t)) return t > 0.0 ? 1.0 : 0.0;
  const double tail = 0.5 * incompleteBeta(dof / (dof + t * t), 0.5 * dof, 0.5);
  return t >= 0.0 ? 1.0 - tail : tail;
}

double studentTQuantile(double p, double dof) {
  if (!(p > 0.0 && p < 1.0)) throw InvalidArgument("Student t quantile: p must lie in (0, 1)");
  if (!(dof > 0.0)) throw InvalidArgument("Student t quantile: degrees of freedom must be positive");
  if (dof > 1e7) return normalQuantile(p);
  if (p < 0.5) return -studentTQuantile(1.0 - p, dof);
  double low = 0.0;
  double high = 1.0;
  while (studentTCdf(high, dof) < p && high < 1e300) high *= 2.0;
  for (int i = 0; i < 300 && high - low > 1e-14 * std::max(1.0, low); ++i) {
    const double middle = 0.5 * (low + high);
    (studentTCdf(middle, dof) < p ? low : high) = middle;
  }
  return 0.5 * (low + high);
}

double tIntervalFactor(double confidence, double dof) {
  if (!(confidence > 0.0 && confidence < 1.0)) throw InvalidArgument("confidence must lie in (0, 1)");
  return studentTQuantile(0.5 * (1.0 + confidence), dof);
}

double fTail2(double f, double dof) {
  if (!(dof > 0.0)) throw InvalidArgument("F test: degrees of freedom must be positive");
  if (!(f > 0.0)) return 1.0;
  return std::exp(-0.5 * dof * std::log1p(2.0 * f / dof));
}

}  // namespace jointcomp
