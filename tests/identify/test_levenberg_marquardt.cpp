// The dense Levenberg-Marquardt solver (model/identify/levenberg_marquardt.hpp): it converges on
// classic nonlinear problems, its robust losses hold a fit against outliers, and it says when it did not
// converge instead of pretending.
#include <cmath>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/common/random.hpp"
#include "model/identify/levenberg_marquardt.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

// Rosenbrock as least squares: r = (10 (x2 - x1^2), 1 - x1), minimum at (1, 1).
void rosenbrock(const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd* j) {
  r << 10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0];
  if (j) *j << -20.0 * x[0], 10.0, -1.0, 0.0;
}

TEST(LevenbergMarquardt, SolvesRosenbrockFromTheClassicStart) {
  const LevenbergMarquardtResult result = solveLevenbergMarquardt(rosenbrock, Eigen::Vector2d(-1.2, 1.0), 2);
  EXPECT_TRUE(result.converged) << result.stop_reason;
  EXPECT_NEAR(result.x[0], 1.0, 1e-8);
  EXPECT_NEAR(result.x[1], 1.0, 1e-8);
  EXPECT_LT(result.cost, 1e-16);
  EXPECT_GT(result.initial_cost, 1.0);
}

// y = a exp(-b t) + c with noise: the fit agrees with the truth to within a few sigma of the noise.
TEST(LevenbergMarquardt, FitsAnExponentialDecay) {
  DeterministicRandom random(5);
  const int m = 200;
  Eigen::VectorXd t(m), y(m);
  for (int k = 0; k < m; ++k) {
    t[k] = 0.05 * k;
    y[k] = 2.5 * std::exp(-1.3 * t[k]) + 0.4 + 1e-3 * random.normal();
  }
  auto model = [&](const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd* j) {
    for (int k = 0; k < m; ++k) {
      const double e = std::exp(-x[1] * t[k]);
      r[k] = x[0] * e + x[2] - y[k];
      if (j) j->row(k) << e, -x[0] * t[k] * e, 1.0;
    }
  };
  const LevenbergMarquardtResult result = solveLevenbergMarquardt(model, Eigen::Vector3d(1.0, 0.5, 0.0), m);
  ASSERT_TRUE(result.converged) << result.stop_reason;
  EXPECT_NEAR(result.x[0], 2.5, 5e-3);
  EXPECT_NEAR(result.x[1], 1.3, 5e-3);
  EXPECT_NEAR(result.x[2], 0.4, 5e-3);
  EXPECT_EQ(result.block_weight.size(), m);
}

// A straight line through 3-D points with 5 % gross outliers: least squares is pulled, Huber and Cauchy
// are not, and the outliers carry the small weights.
TEST(LevenbergMarquardt, RobustLossesResistOutliersAndWeighThemDown) {
  DeterministicRandom random(9);
  const int m = 200;
  std::vector<Eigen::Vector3d> points;
  std::vector<bool> outlier;
  const Eigen::Vector3d origin(0.1, -0.2, 0.3), direction(1.0, 0.5, -0.25);
  for (int k = 0; k < m; ++k) {
    Eigen::Vector3d p = origin + 0.01 * k * direction;
    for (int a = 0; a < 3; ++a) p[a] += 1e-3 * random.normal();
    outlier.push_back(k % 20 == 7);
    if (outlier.back()) p += Eigen::Vector3d(0.05, 0.05, 0.05);
    points.push_back(p);
  }
  // Parameters: origin (3) and direction (3); residual = origin + s_k direction - p_k.
  auto model = [&](const Eigen::VectorXd& x, Eigen::VectorXd& r, Eigen::MatrixXd* j) {
    for (int k = 0; k < m; ++k) {
      const double s = 0.01 * k;
      r.segment<3>(3 * k) = x.head<3>() + s * x.tail<3>() - points[static_cast<std::size_t>(k)];
      if (j) {
        j->block<3, 3>(3 * k, 0).setIdentity();
        j->block<3, 3>(3 * k, 3) = s * Eigen::Matrix3d::Identity();
      }
    }
  };
  Eigen::VectorXd start = Eigen::VectorXd::Zero(6);
  LevenbergMarquardtOptions options;
  options.block_size = 3;
  const double least_squares_error =
      (solveLevenbergMarquardt(model, start, 3 * m, options).x.head<3>() - origin).norm();
  EXPECT_GT(least_squares_error, 3e-3);  // pulled by the outliers
  for (RobustLoss loss : {RobustLoss::Huber, RobustLoss::Cauchy}) {
    SCOPED_TRACE(robustLossName(loss));
    options.loss = loss;
    options.loss_scale = 3e-3;
    const LevenbergMarquardtResult result = solveLevenbergMarquardt(model, start, 3 * m, options);
    ASSERT_TRUE(result.converged) << result.stop_reason;
    EXPECT_LT((result.x.head<3>() - origin).norm(), 1.5e-3);
    EXPECT_LT((result.x.tail<3>() - direction).norm(), 1.5e-3);
    for (int k = 0; k < m; ++k) {
      if (outlier[static_cast<std::size_t>(k)]) {
        EXPECT_LT(result.block_weight[k], 0.1) << "row " << k;
      }
    }
  }
}

TEST(LevenbergMarquardt, LossFunctionsAreConsistent) {
  for (RobustLoss loss : {RobustLoss::None, RobustLoss::Huber, RobustLoss::Cauchy}) {
    for (double s : {0.0, 0.5, 1.0, 4.0, 100.0}) {
      // rho'(s) by central differences equals the weight.
      const double h = 1e-6;
      const double derivative =
          (robustRho(loss, 1.0, s + h) - robustRho(loss, 1.0, std::max(0.0, s - h))) / (s + h - std::max(0.0, s - h));
      EXPECT_NEAR(derivative, robustWeight(loss, 1.0, s), 1e-5) << robustLossName(loss) << " s " << s;
    }
    EXPECT_EQ(parseRobustLoss(robustLossName(loss)), loss);
  }
  EXPECT_THROW(parseRobustLoss("tukey"), InvalidArgument);
}

TEST(LevenbergMarquardt, SaysWhenItDidNotConverge) {
  LevenbergMarquardtOptions options;
  options.max_iterations = 2;
  const LevenbergMarquardtResult result = solveLevenbergMarquardt(rosenbrock, Eigen::Vector2d(-1.2, 1.0), 2, options);
  EXPECT_FALSE(result.converged);
  EXPECT_THAT(result.stop_reason, HasSubstr("2 iterations"));
}

TEST(LevenbergMarquardt, RejectsInconsistentInput) {
  EXPECT_THROW(solveLevenbergMarquardt(rosenbrock, Eigen::VectorXd(), 2), InvalidArgument);
  LevenbergMarquardtOptions options;
  options.block_size = 3;
  EXPECT_THROW(solveLevenbergMarquardt(rosenbrock, Eigen::Vector2d(0, 0), 2, options), InvalidArgument);
  options.block_size = 1;
  options.loss = RobustLoss::Huber;
  options.loss_scale = 0.0;
  EXPECT_THROW(solveLevenbergMarquardt(rosenbrock, Eigen::Vector2d(0, 0), 2, options), InvalidArgument);
  auto not_finite = [](const Eigen::VectorXd&, Eigen::VectorXd& r, Eigen::MatrixXd* j) {
    r.setConstant(std::numeric_limits<double>::quiet_NaN());
    if (j) j->setZero();
  };
  EXPECT_THROW(solveLevenbergMarquardt(not_finite, Eigen::Vector2d(0, 0), 2), SolverError);
}

}  // namespace
}  // namespace jointcomp
