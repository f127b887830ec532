// The statistics the identifications share: weighted linear least squares with a rank check and the
// covariance of its coefficients, and the few distribution functions their intervals and tests need
// (Student t quantiles, the F(2, n) tail). Small and self-contained so that results are the same on
// every platform.
#pragma once

#include <Eigen/Core>

namespace jointcomp {

// Weighted linear least squares y = A x + e, e_k ~ N(0, (s sigma_k)^2) with an unknown common scale s.
struct LinearFit {
  int rank = 0;                  // numerical rank of A; the fit is valid only when rank == A.cols()
  Eigen::VectorXd coefficients;  // x
  // Covariance of x scaled by the residual variance (s^2 estimated as rss / dof), so that intervals
  // stay honest when the stated sigma is off by a common factor.
  Eigen::MatrixXd covariance;
  Eigen::MatrixXd unscaled_covariance;  // (A^T W A)^-1: the covariance if sigma is exactly right
  Eigen::VectorXd residuals;            // y - A x, unweighted
  double rss = 0.0;                     // weighted residual sum of squares, sum (r_k / sigma_k)^2
  int dof = 0;                          // rows - columns
  double scale2 = 0.0;                  // rss / dof: the reduced chi-square (1 when sigma is right)
  // When rank < cols: the direction of coefficient space A cannot see (unit length, original units
  // normalised per column), to name the parameters at fault.
  Eigen::VectorXd null_direction;
};

// `sigma` holds the 1-sigma noise of each row (positive); rows with larger sigma weigh less. Columns
// are scaled to unit norm before the SVD, and a singular value below `rank_tolerance` times the largest
// counts as zero. Throws InvalidArgument for mismatched sizes or non-finite input.
LinearFit weightedLeastSquares(const Eigen::MatrixXd& a, const Eigen::VectorXd& y, const Eigen::VectorXd& sigma,
                               double rank_tolerance = 1e-10);

// Standard normal quantile (inverse CDF) for p in (0, 1).
double normalQuantile(double p);
// Student t distribution: CDF and quantile with `dof` > 0 degrees of freedom.
double studentTCdf(double t, double dof);
double studentTQuantile(double p, double dof);
// Two-sided interval half-width factor: the (1 + confidence) / 2 quantile of Student t.
double tIntervalFactor(double confidence, double dof);
// P(F > f) for F ~ F(2, dof): (1 + 2 f / dof)^(-dof / 2).
double fTail2(double f, double dof);
// Regularised incomplete beta function I_x(a, b).
double incompleteBeta(double x, double a, double b);

}  // namespace jointcomp
