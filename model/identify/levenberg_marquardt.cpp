#include "model/identify/levenberg_marquardt.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <utility>

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

// Normal equations of the IRLS model at the current point: A = J^T W J, g = J^T W r. `weighted` is scratch of
// J's size (the solver's trial Jacobian, free at this point: no third matrix of J's size).
void normalEquations(const Eigen::MatrixXd& jacobian, const Eigen::VectorXd& r, const Eigen::VectorXd& block_weight,
                     int block_size, Eigen::MatrixXd& weighted, Eigen::MatrixXd& a, Eigen::VectorXd& g) {
  const Eigen::Index n = jacobian.cols();
  weighted = jacobian;
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

namespace {

// One run of the solver: the current point with its weighted normal equations, the damping, and the
// damped steps tried from there (Marquardt's scaling, Nielsen's update of the damping).
class LevenbergMarquardtRun {
public:
  LevenbergMarquardtRun(const ResidualFunction& function, const Eigen::VectorXd& x0, int residual_count,
                        const LevenbergMarquardtOptions& options)
      : function_(function),
        options_(options),
        n_(x0.size()),
        trial_residual_(residual_count),
        trial_jacobian_(residual_count, x0.size()),
        lambda_(options.initial_lambda) {
    result_.x = x0;
    result_.residual.resize(residual_count);
    result_.jacobian.resize(residual_count, n_);
    function_(result_.x, result_.residual, &result_.jacobian);
    result_.evaluations = 1;
    if (!result_.residual.allFinite())
      throw SolverError("Levenberg-Marquardt: the residuals are not finite at the start point");
    if (!result_.jacobian.allFinite())
      throw SolverError("Levenberg-Marquardt: the Jacobian is not finite at the start point");
    current_ = weigh(result_.residual, options_);
    result_.initial_cost = current_.cost;
    normalEquations(result_.jacobian, result_.residual, current_.block_weight, options_.block_size, trial_jacobian_, a_,
                    g_);
  }

  // The result is moved out (a copy was one more matrix of the Jacobian's size): call once.
  LevenbergMarquardtResult solve() {
    while (true) {
      const Scaled scaled = scaledSystem();
      if (current_.weighted_norm == 0.0) {
        finish(true, "zero residual");
        break;
      }
      if (gradientCosine(scaled.d) <= options_.gradient_tolerance) {
        finish(true, "gradient below tolerance");
        break;
      }
      if (!takeStep(scaled)) break;
    }
    trial_jacobian_.resize(0, 0);
    return std::move(result_);
  }

private:
  // The normal matrix with a unit diagonal (zero columns left alone), and the right-hand side to match.
  struct Scaled {
    Eigen::VectorXd d, d_inverse, rhs;
    Eigen::MatrixXd matrix;
    double x_scale = 0.0;
  };

  Scaled scaledSystem() const {
    Scaled s;
    s.d = a_.diagonal().cwiseMax(0.0).cwiseSqrt();
    s.d_inverse.resize(n_);
    for (Eigen::Index j = 0; j < n_; ++j) s.d_inverse[j] = s.d[j] > 0.0 ? 1.0 / s.d[j] : 1.0;
    s.matrix = s.d_inverse.asDiagonal() * a_ * s.d_inverse.asDiagonal();
    s.rhs = -(s.d_inverse.asDiagonal() * g_);
    s.x_scale = (s.d.asDiagonal() * result_.x).norm();
    return s;
  }

  double gradientCosine(const Eigen::VectorXd& d) const {
    double worst = 0.0;
    for (Eigen::Index j = 0; j < n_; ++j) {
      if (d[j] > 0.0) worst = std::max(worst, std::abs(g_[j]) / (d[j] * current_.weighted_norm));
    }
    return worst;
  }

  void finish(bool converged, const std::string& reason) {
    result_.converged = converged;
    result_.stop_reason = reason;
    result_.cost = current_.cost;
    result_.block_weight = current_.block_weight;
  }

  void raiseDamping() {
    lambda_ *= nu_;
    nu_ *= 2.0;
  }

  // Damped steps from the current point until one lowers the cost (true), or the run ends (false, the
  // result finished).
  bool takeStep(const Scaled& s) {
    while (true) {
      if (result_.iterations >= options_.max_iterations) {
        finish(false, "no convergence within " + std::to_string(options_.max_iterations) + " iterations");
        return false;
      }
      ++result_.iterations;
      Eigen::MatrixXd damped = s.matrix;
      damped.diagonal().array() += lambda_;
      const Eigen::LDLT<Eigen::MatrixXd> solver(damped);
      const Eigen::VectorXd y = solver.solve(s.rhs);
      if (solver.info() != Eigen::Success || !y.allFinite()) {
        raiseDamping();
        continue;
      }
      if (y.norm() <= options_.step_tolerance * (s.x_scale + options_.step_tolerance)) {
        finish(true, "step below tolerance");
        return false;
      }
      const Eigen::VectorXd dx = s.d_inverse.asDiagonal() * y;
      const std::optional<bool> outcome = tryStep(dx);
      if (outcome) return *outcome;
      raiseDamping();
      if (lambda_ > 1e16) {
        // No step lowers the cost any more: at a minimum to rounding error, or stuck.
        const bool stationary = gradientCosine(s.d) <= 1e-6;
        finish(stationary, stationary ? "no further decrease (at a minimum to rounding error)"
                                      : "no further decrease although the gradient is not small");
        return false;
      }
    }
  }

  // The point x + dx: taken when it lowers the cost (true; false when that ends the run by the cost
  // tolerance), nothing when it does not.
  std::optional<bool> tryStep(const Eigen::VectorXd& dx) {
    const Eigen::VectorXd trial_x = result_.x + dx;
    function_(trial_x, trial_residual_, &trial_jacobian_);
    ++result_.evaluations;
    Weighted trial;
    const bool finite = trial_residual_.allFinite() && trial_jacobian_.allFinite();
    if (finite) trial = weigh(trial_residual_, options_);
    const double actual = current_.cost - trial.cost;
    if (!finite || !(actual > 0.0)) return std::nullopt;
    const double predicted = -g_.dot(dx) - 0.5 * dx.dot(a_ * dx);
    const double ratio = predicted > 0.0 ? actual / predicted : 0.0;
    lambda_ *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * ratio - 1.0, 3));
    lambda_ = std::max(lambda_, 1e-15);
    nu_ = 2.0;
    const double previous_cost = current_.cost;
    result_.x = trial_x;
    result_.residual.swap(trial_residual_);
    result_.jacobian.swap(trial_jacobian_);
    current_ = trial;
    normalEquations(result_.jacobian, result_.residual, current_.block_weight, options_.block_size, trial_jacobian_, a_,
                    g_);
    if (options_.on_accepted_step) options_.on_accepted_step(result_.iterations, current_.cost);
    if (actual <= options_.function_tolerance * previous_cost) {
      finish(true, "cost change below tolerance");
      return false;
    }
    return true;
  }

  const ResidualFunction& function_;
  const LevenbergMarquardtOptions& options_;
  Eigen::Index n_;
  LevenbergMarquardtResult result_;
  Weighted current_;
  Eigen::MatrixXd a_;
  Eigen::VectorXd g_;
  Eigen::VectorXd trial_residual_;
  Eigen::MatrixXd trial_jacobian_;
  double lambda_;
  double nu_ = 2.0;
};

}  // namespace

LevenbergMarquardtResult solveLevenbergMarquardt(const ResidualFunction& function, const Eigen::VectorXd& x0,
                                                 int residual_count, const LevenbergMarquardtOptions& options) {
  checkProblem(x0, residual_count, options);
  return LevenbergMarquardtRun(function, x0, residual_count, options).solve();
}

}  // namespace jointcomp
