// Discovery's linearised problem in Gram form (linearised_problem.hpp, linearised_fit.hpp) against the same
// quantities computed the plain way from the dense design matrix: the sums of every block, the fit on all
// rows, and each leave-one-group-out prediction refitted without the group's rows.
#include <random>

#include <gtest/gtest.h>

#include "model/identify/linearised_fit.hpp"

namespace jointcomp {
namespace {

struct Problem {
  LinearisedProblem problem;
  Eigen::MatrixXd feature_values;  // rows x 5, sparse (two nonzeros a row)
  SparseFeatures features;
  ColumnPiece piece;  // two dense columns and the five features of joint 1
  Eigen::MatrixXd X;  // 3 rows x (base + piece), the dense design matrix
};

Problem makeProblem(int rows, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  Problem p;
  LinearisedProblem& lp = p.problem;
  lp.rows = rows;
  lp.dof = 3;
  lp.r.resize(3 * rows);
  lp.base.resize(3 * rows, 4);
  lp.joint_column.resize(3 * rows, 3);
  for (int i = 0; i < 3 * rows; ++i) {
    lp.r[i] = normal(rng);
    for (int c = 0; c < 4; ++c) lp.base(i, c) = normal(rng);
    for (int j = 0; j < 3; ++j) lp.joint_column(i, j) = normal(rng);
  }
  p.feature_values = Eigen::MatrixXd::Zero(rows, 5);
  std::vector<JointVector> command;
  for (int i = 0; i < rows; ++i) {
    p.feature_values(i, i % 5) = normal(rng);
    p.feature_values(i, (i + 2) % 5) = normal(rng);
    JointVector q = JointVector::Zero(3);
    for (int j = 0; j < 3; ++j) q[j] = normal(rng);
    command.push_back(q);
  }
  p.features = sparseFeatures(p.feature_values);
  p.piece.dense = Eigen::MatrixXd(3 * rows, 2);
  for (int i = 0; i < 3 * rows; ++i)
    for (int c = 0; c < 2; ++c) p.piece.dense(i, c) = normal(rng);
  p.piece.features = &p.features;
  p.piece.joint = 1;
  lp.groupings.push_back(timeBlocks(rows, 4, 3));
  lp.groupings.push_back(jointSpaceParts(command, 3, 0.05, 3));
  lp.groupings.push_back(angleRanges(command, 1, 4, 3));
  accumulateBase(lp);
  // The dense design matrix, built independently: feature column k of row i is v_ik a_i1.
  p.X = Eigen::MatrixXd::Zero(3 * rows, 4 + 2 + 5);
  p.X.leftCols(4) = lp.base;
  p.X.middleCols(4, 2) = p.piece.dense;
  for (int i = 0; i < rows; ++i)
    for (int k = 0; k < 5; ++k)
      p.X.block(3 * i, 6 + k, 3, 1) = p.feature_values(i, k) * lp.joint_column.block(3 * i, 1, 3, 1);
  return p;
}

TEST(LinearisedFit, BlockSumsAddUpToTheDenseGram) {
  const Problem p = makeProblem(90, 1);
  const FitSystem system = assembleSystem(p.problem, {&p.piece}, {0, 1, 2});
  const Eigen::VectorXd s = system.scale;
  const Eigen::MatrixXd gram = s.asDiagonal() * system.total_gram * s.asDiagonal();
  const Eigen::MatrixXd expected = p.X.transpose() * p.X;
  EXPECT_LT((gram - expected).norm(), 1e-10 * expected.norm());
  EXPECT_LT((s.asDiagonal() * system.total_xr - p.X.transpose() * p.problem.r).norm(), 1e-10 * expected.norm());
  EXPECT_NEAR(system.total_rr, p.problem.r.squaredNorm(), 1e-10 * system.total_rr);
  // Every grouping's blocks add up to the same totals.
  for (std::size_t g = 0; g < system.gram.size(); ++g) {
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(gram.rows(), gram.cols());
    for (const Eigen::MatrixXd& block : system.gram[g]) sum += block;
    EXPECT_LT((sum - system.total_gram).norm(), 1e-10 * system.total_gram.norm()) << "grouping " << g;
  }
}

TEST(LinearisedFit, LeaveOneGroupOutEqualsARefitWithoutTheGroup) {
  const Problem p = makeProblem(120, 2);
  const FitSystem system = assembleSystem(p.problem, {&p.piece}, {0, 1, 2});
  const Fit fit = solveSystem(system, Penalty(), false);
  // On all rows: the least-squares residual.
  const Eigen::VectorXd full = p.X.colPivHouseholderQr().solve(-p.problem.r);
  EXPECT_NEAR(fit.rss, (p.problem.r + p.X * full).squaredNorm(), 1e-9 * fit.rss);
  for (std::size_t g = 0; g < system.groupings.size(); ++g) {
    const RowGrouping& grouping = p.problem.groupings[static_cast<std::size_t>(system.groupings[g])];
    double total = 0.0;
    for (int group = 0; group < grouping.groups(); ++group) {
      std::vector<Eigen::Index> kept, left;
      for (int i = 0; i < p.problem.rows; ++i) {
        const bool out =
            grouping.group_of_block[static_cast<std::size_t>(grouping.block_of_row[static_cast<std::size_t>(i)])] ==
            group;
        for (int a = 0; a < 3; ++a) (out ? left : kept).push_back(3 * i + a);
      }
      const Eigen::MatrixXd Xk = p.X(kept, Eigen::all);
      const Eigen::VectorXd d = Xk.colPivHouseholderQr().solve(-Eigen::VectorXd(p.problem.r(kept)));
      const double expected = (Eigen::VectorXd(p.problem.r(left)) + p.X(left, Eigen::all) * d).squaredNorm();
      EXPECT_NEAR(fit.errors[g].group[static_cast<std::size_t>(group)], expected, 1e-8 * expected)
          << grouping.kind << " " << group;
      total += expected;
    }
    double blocks = 0.0;
    for (double e : fit.errors[g].block) blocks += e;
    EXPECT_NEAR(blocks, total, 1e-8 * total);
  }
  EXPECT_NEAR(
      fit.cv,
      [&] {
        double s = 0;
        for (double e : fit.cv_fold) s += e;
        return s;
      }(),
      1e-12);
  EXPECT_EQ(fit.rank, 4 + 2 + 5);
  EXPECT_DOUBLE_EQ(fit.dof, 11.0);
}

TEST(LinearisedFit, ARidgeShrinksTheStepAndLowersTheEffectiveParameters) {
  const Problem p = makeProblem(80, 3);
  const FitSystem system = assembleSystem(p.problem, {&p.piece}, {0});
  Penalty ridge;
  ridge.matrix = Eigen::MatrixXd::Zero(system.columns(), system.columns());
  ridge.held = Eigen::VectorXd::Zero(system.columns());
  for (int c = 6; c < 11; ++c) ridge.matrix(c, c) = 5.0;
  const Fit free = solveSystem(system, Penalty(), false);
  const Fit shrunk = solveSystem(system, ridge, false);
  EXPECT_LT(shrunk.d.tail(5).norm(), free.d.tail(5).norm());
  EXPECT_LT(shrunk.dof, free.dof);
  EXPECT_GT(shrunk.dof, 6.0);
  EXPECT_GT(shrunk.rss, free.rss);
}

TEST(LinearisedFit, GroupsTooSmallToMeasureJoinTheNearestLargeOne) {
  std::vector<JointVector> command;
  for (int i = 0; i < 200; ++i) {
    JointVector q = JointVector::Zero(2);
    q[0] = i < 196 ? (i % 2 ? 1.0 : -1.0) + 0.01 * (i % 7) : 10.0;  // four rows far away
    command.push_back(q);
  }
  const RowGrouping parts = jointSpaceParts(command, 3, 0.05, 4);
  for (int rows : parts.rows_of_group) EXPECT_GE(rows, 10);
  int total = 0;
  for (int rows : parts.rows_of_group) total += rows;
  EXPECT_EQ(total, 200);
}

TEST(LinearisedFit, AngleRangesHoldEqualAnglesTogether) {
  std::vector<JointVector> command;
  for (int i = 0; i < 100; ++i) {
    JointVector q = JointVector::Zero(2);
    q[1] = static_cast<double>(i % 10);
    command.push_back(q);
  }
  const RowGrouping ranges = angleRanges(command, 1, 4, 2);
  for (int a = 0; a < 100; ++a) {
    for (int b = 0; b < 100; ++b) {
      if (command[a][1] != command[b][1]) continue;
      EXPECT_EQ(ranges.group_of_block[ranges.block_of_row[a]], ranges.group_of_block[ranges.block_of_row[b]]);
    }
  }
  EXPECT_EQ(ranges.joint, 1);
}

}  // namespace
}  // namespace jointcomp
