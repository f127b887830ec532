// Dense Levenberg-Marquardt for nonlinear least squares, with an optional robust loss by iteratively
// reweighted least squares (IRLS).
//
// Why this and not Ceres: the calibration problems of the project are small and dense (about 50
// parameters, tens of thousands of residuals), and the identification needs the dense Jacobian anyway:
// its column-pivoted QR decides which parameters are identifiable, gives the condition number and the
// covariance. A dense Marquardt-scaled normal-equation solver on Eigen does all of that in one place, in
// well under a second for the IPA UR10 data, without adding Ceres (and its glog/gflags) to the library,
// the C API and the FMU that link this code.
//
// Residuals come in blocks of `block_size` (3 for a 3-D point): a robust loss acts on each block's
// squared norm s, cost = 1/2 sum rho(s); the IRLS weight of a block is rho'(s) (1 for small residuals).
#pragma once

#include <functional>
#include <string>

#include <Eigen/Core>

namespace jointcomp {

enum class RobustLoss {
  None,    // rho(s) = s
  Huber,   // rho(s) = s for sqrt(s) <= k, 2 k sqrt(s) - k^2 beyond: weight k / |r|
  Cauchy,  // rho(s) = k^2 log(1 + s / k^2): weight 1 / (1 + s / k^2)
};

// "none", "huber", "cauchy"; parseRobustLoss throws InvalidArgument naming the text for anything else.
const char* robustLossName(RobustLoss loss);
RobustLoss parseRobustLoss(const std::string& name);

// rho(s) and its derivative (the IRLS weight) for a squared block norm s and scale k (k > 0).
double robustRho(RobustLoss loss, double scale, double squared_norm);
double robustWeight(RobustLoss loss, double scale, double squared_norm);

struct LevenbergMarquardtOptions {
  int max_iterations = 100;
  double initial_lambda = 1e-4;       // damping relative to the (unit) diagonal of the scaled normal matrix
  double function_tolerance = 1e-12;  // stop when an accepted step lowers the cost by less than this, relatively
  double step_tolerance = 1e-10;      // stop when |D dx| <= tol (|D x| + tol), D the column norms of J
  double gradient_tolerance = 1e-10;  // stop when every column of J is this close to orthogonal to r (cosine)
  RobustLoss loss = RobustLoss::None;
  double loss_scale = 1.0;  // k, in the units of the residuals
  int block_size = 1;
  // Told after each accepted step: the iterations so far and the cost (1/2 sum rho); may be empty.
  std::function<void(int iterations, double cost)> on_accepted_step;
};

// Fills `residual` (size residual_count) at x and, when `jacobian` is not null, d residual / dx into it
// (residual_count x x.size(), already sized). May throw; the exception passes through.
using ResidualFunction =
    std::function<void(const Eigen::VectorXd& x, Eigen::VectorXd& residual, Eigen::MatrixXd* jacobian)>;

struct LevenbergMarquardtResult {
  Eigen::VectorXd x;
  Eigen::VectorXd residual;      // at x
  Eigen::MatrixXd jacobian;      // at x
  Eigen::VectorXd block_weight;  // IRLS weight of each block at x (1 without a loss)
  double initial_cost = 0.0;     // 1/2 sum rho at the start
  double cost = 0.0;             // at x
  int iterations = 0;            // accepted and rejected steps
  int evaluations = 0;
  bool converged = false;
  std::string stop_reason;
};

// Minimises 1/2 sum rho(|r_b(x)|^2) from x0. Never throws for non-convergence: the result says
// (converged = false and stop_reason); throws InvalidArgument for inconsistent sizes or options and
// SolverError when the residuals or the Jacobian are not finite at the start.
LevenbergMarquardtResult solveLevenbergMarquardt(const ResidualFunction& function, const Eigen::VectorXd& x0,
                                                 int residual_count, const LevenbergMarquardtOptions& options = {});

}  // namespace jointcomp
