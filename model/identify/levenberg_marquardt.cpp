#include "model/identify/levenberg_marquardt.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

#include "model/common/errors.hpp"

namespace jointcomp {
namespace {

struct Weighted {
  Eigen::VectorXd block_weight;
  double cost = 0.0;
  double weighted_norm = 0.0;  // sqrt(sum w |r_b|^2)
};

Weighted weigh(const Eigen::VectorXd& r, const LevenbergMarquardtOptions& options) {
  const int blocks = static_cast<int>(r.size()) / options.block_size;
  Weighted out;
  out.block_weight.resize(blocks);
  double squared = 0.0;
  for (int b = 0; b < blocks; ++b) {
    const double s = r.segment(b * options.block_size, options.block_size).squaredNorm();
    const double w = robustWeight(options.loss, options.loss_scale, s);
    out.block_weight[b] = w;
    out.cost += 0.5 * robustRho(options.loss, options.loss_scale, s);
    squared += w * s;
  }
  out.weighted_norm = std::sqrt(squared);
  return out;
}

// Normal equations of the IRLS model at the current point: A = J^T W J, g = J^T W r.
void normalEquations(const Eigen::MatrixXd& jacobian, const Eigen::VectorXd& r, const Eigen::VectorXd& block_weight,
                     int block_size, Eigen::MatrixXd& a, Eigen::VectorXd& g) {
  const Eigen::Index n = jacobian.cols();
  Eigen::MatrixXd weighted = jacobian;
  Eigen::VectorXd weighted_r = r;
  for (Eigen::Index row = 0; row < r.size(); ++row) {
    const double root = std::sqrt(block_weight[row / block_size]);
    weighted.row(row) *= root;
    weighted_r[row] *= root;
  }
  a.setZero(n, n);
  a.selfadjointView<Eigen::Lower>().rankUpdate(weighted.transpose());
  a = a.selfadjointView<Eigen::Lower>();
  g.noalias() = weighted.transpose() * weighted_r;
}

}  // namespace

const char* robustLossName(RobustLoss loss) {
  switch (loss) {
    case RobustLoss::None: return "none";
    case RobustLoss::Huber: return "huber";
    case RobustLoss::Cauchy: return "cauchy";
  }
  return "none";
}

RobustLoss parseRobustLoss(const std::string& name) {
  if (name == "none") return RobustLoss::None;
  if (name == "huber") return RobustLoss::Huber;
  if (name == "cauchy") return RobustLoss::Cauchy;
  throw InvalidArgument("robust loss '" + name + "' is not one of none, huber, cauchy");
}

double robustRho(RobustLoss loss, double scale, double s) {
  switch (loss) {
    case RobustLoss::None: return s;
    case RobustLoss::Huber: {
      const double norm = std::sqrt(s);
      return norm <= scale ? s : 2.0 * scale * norm - scale * scale;
    }
    case RobustLoss::Cauchy: return scale * scale * std::log1p(s / (scale * scale));
  }
  return s;
}

double robustWeight(RobustLoss loss, double scale, double s) {
  switch (loss) {
    case RobustLoss::None: return 1.0;
    case RobustLoss::Huber: {
      const double norm = std::sqrt(s);
      return norm <= scale ? 1.0 : scale / norm;
    }
    case RobustLoss::Cauchy: return 1.0 / (1.0 + s / (scale * scale));
  }
  return 1.0;
}

namespace {

// The problem is one the solver can start on; throws InvalidArgument saying what is wrong.
void checkProblem(const Eigen::VectorXd& x0, int residual_count, const LevenbergMarquardtOptions& options) {
  if (x0.size() < 1) throw InvalidArgument("Levenberg-Marquardt: no parameters to solve for");
  if (options.block_size < 1 || residual_count < 1 || residual_count % options.block_size != 0) {
    throw InvalidArgument("Levenberg-Marquardt: " + std::to_string(residual_count) +
                          " residuals do not make whole blocks of " + std::to_string(options.block_size));
  }
  if (options.loss != RobustLoss::None && !(options.loss_scale > 0.0 && std::isfinite(options.loss_scale))) {
    throw InvalidArgument("Levenberg-Marquardt: the robust loss scale must be positive and finite, is " +
                          std::to_string(options.loss_scale));
  }
  if (!x0.allFinite()) throw InvalidArgument("Levenberg-Marquardt: the start point is not finite");
  if (options.max_iterations < 1) throw InvalidArgument("Levenberg-Marquardt: max_iterations must be at least 1");
}

}  // namespace

LevenbergMarquardtResult solveLevenbergMarquardt(const ResidualFunction& function, const Eigen::VectorXd& x0,
                                                 int residual_count, const LevenbergMarquardtOptions& options) {
  checkProblem(x0, residual_count, options);
  const Eigen::Index n = x0.size();

  LevenbergMarquardtResult result;
  result.x = x0;
  result.residual.resize(residual_count);
  result.jacobian.resize(residual_count, n);
  function(result.x, result.residual, &result.jacobian);
  result.evaluations = 1;
  if (!result.residual.allFinite())
    throw SolverError("Levenberg-Marquardt: the residuals are not finite at the start point");
  if (!result.jacobian.allFinite())
    throw SolverError("Levenberg-Marquardt: the Jacobian is not finite at the start point");
  Weighted current = weigh(result.residual, options);
  result.initial_cost = current.cost;

  Eigen::MatrixXd a;
  Eigen::VectorXd g;
  normalEquations(result.jacobian, result.residual, current.block_weight, options.block_size, a, g);
  Eigen::VectorXd trial_residual(residual_count);
  Eigen::MatrixXd trial_jacobian(residual_count, n);
  double lambda = options.initial_lambda;
  double nu = 2.0;

  auto finish = [&](bool converged, const std::string& reason) {
    result.converged = converged;
    result.stop_reason = reason;
    result.cost = current.cost;
    result.block_weight = current.block_weight;
    return result;
  };
  auto gradientCosine = [&](const Eigen::VectorXd& d) {
    double worst = 0.0;
    for (Eigen::Index j = 0; j < n; ++j) {
      if (d[j] > 0.0) worst = std::max(worst, std::abs(g[j]) / (d[j] * current.weighted_norm));
    }
    return worst;
  };

  while (true) {
    // Marquardt scaling: the normal matrix with a unit diagonal (zero columns left alone).
    Eigen::VectorXd d = a.diagonal().cwiseMax(0.0).cwiseSqrt();
    if (current.weighted_norm == 0.0) return finish(true, "zero residual");
    if (gradientCosine(d) <= options.gradient_tolerance) return finish(true, "gradient below tolerance");
    Eigen::VectorXd d_inverse(n);
    for (Eigen::Index j = 0; j < n; ++j) d_inverse[j] = d[j] > 0.0 ? 1.0 / d[j] : 1.0;
    const Eigen::MatrixXd scaled = d_inverse.asDiagonal() * a * d_inverse.asDiagonal();
    const Eigen::VectorXd rhs = -(d_inverse.asDiagonal() * g);
    const double x_scale = (d.asDiagonal() * result.x).norm();

    bool accepted = false;
    while (!accepted) {
      if (result.iterations >= options.max_iterations) {
        return finish(false, "no convergence within " + std::to_string(options.max_iterations) + " iterations");
      }
      ++result.iterations;
      Eigen::MatrixXd damped = scaled;
      damped.diagonal().array() += lambda;
      const Eigen::LDLT<Eigen::MatrixXd> solver(damped);
      const Eigen::VectorXd y = solver.solve(rhs);
      if (solver.info() != Eigen::Success || !y.allFinite()) {
        lambda *= nu;
        nu *= 2.0;
        continue;
      }
      if (y.norm() <= options.step_tolerance * (x_scale + options.step_tolerance)) {
        return finish(true, "step below tolerance");
      }
      const Eigen::VectorXd dx = d_inverse.asDiagonal() * y;
      const Eigen::VectorXd trial_x = result.x + dx;
      function(trial_x, trial_residual, &trial_jacobian);
      ++result.evaluations;
      Weighted trial;
      const bool finite = trial_residual.allFinite() && trial_jacobian.allFinite();
      if (finite) trial = weigh(trial_residual, options);
      const double actual = current.cost - trial.cost;
      if (finite && actual > 0.0) {
        const double predicted = -g.dot(dx) - 0.5 * dx.dot(a * dx);
        const double ratio = predicted > 0.0 ? actual / predicted : 0.0;
        lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * ratio - 1.0, 3));
        lambda = std::max(lambda, 1e-15);
        nu = 2.0;
        const double previous_cost = current.cost;
        result.x = trial_x;
        result.residual.swap(trial_residual);
        result.jacobian.swap(trial_jacobian);
        current = trial;
        normalEquations(result.jacobian, result.residual, current.block_weight, options.block_size, a, g);
        accepted = true;
        if (options.on_accepted_step) options.on_accepted_step(result.iterations, current.cost);
        if (actual <= options.function_tolerance * previous_cost) return finish(true, "cost change below tolerance");
      } else {
        lambda *= nu;
        nu *= 2.0;
        if (lambda > 1e16) {
          // No step lowers the cost any more: at a minimum to rounding error, or stuck.
          const bool stationary = gradientCosine(d) <= 1e-6;
          return finish(stationary, stationary ? "no further decrease (at a minimum to rounding error)"
                                               : "no further decrease although the gradient is not small");
        }
      }
    }
  }
}

}  // namespace jointcomp
