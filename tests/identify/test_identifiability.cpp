// analyseIdentifiability (model/identify/identifiability.hpp) on Jacobians whose redundancies are known.
#include <cmath>

#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/common/random.hpp"
#include "model/identify/identifiability.hpp"

namespace jointcomp {
namespace {

Eigen::MatrixXd randomColumns(int rows, int cols, std::uint64_t seed) {
  DeterministicRandom random(seed);
  Eigen::MatrixXd m(rows, cols);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) m(r, c) = random.normal();
  }
  return m;
}

TEST(Identifiability, FindsExactRedundanciesAndExplainsThem) {
  const Eigen::MatrixXd base = randomColumns(60, 3, 1);
  Eigen::MatrixXd j(60, 6);
  j.col(0) = base.col(0);
  j.col(1) = 1e-3 * base.col(1);  // other units: scaling must not matter
  j.col(2) = base.col(2);
  j.col(3) = 2.0 * base.col(0);                                       // redundant with column 0, ratio 2
  j.col(4) = Eigen::VectorXd::Zero(60);                               // no effect
  j.col(5) = base.col(0) + 1e-3 * base.col(1) + 1e-12 * base.col(2);  // nearly a combination
  const IdentifiabilityResult result = analyseIdentifiability(j);
  EXPECT_EQ(result.kept.size(), 3u);
  EXPECT_TRUE(result.no_effect[4]);
  EXPECT_NEAR(result.pivot[1], 1.0, 0.5);
  // Whichever of 0 and 3 was kept, the other is explained by it with the right ratio.
  const bool kept_zero = std::find(result.kept.begin(), result.kept.end(), 0) != result.kept.end();
  const int fixed = kept_zero ? 3 : 0;
  ASSERT_EQ(result.redundant_with[static_cast<std::size_t>(fixed)].size(), 1u);
  EXPECT_NEAR(result.redundant_with[static_cast<std::size_t>(fixed)][0].ratio, kept_zero ? 2.0 : 0.5, 1e-10);
  EXPECT_LT(result.condition_number, 10.0);
}

TEST(Identifiability, PriorityDecidesWhichOfTwoRedundantColumnsIsKept) {
  const Eigen::MatrixXd base = randomColumns(40, 2, 2);
  Eigen::MatrixXd j(40, 3);
  j.col(0) = base.col(0);
  j.col(1) = base.col(1);
  j.col(2) = -3.0 * base.col(0);
  for (int preferred : {0, 2}) {
    std::vector<int> priority = {1, 1, 1};
    priority[static_cast<std::size_t>(preferred)] = 0;
    const IdentifiabilityResult result = analyseIdentifiability(j, priority);
    const int other = preferred == 0 ? 2 : 0;
    EXPECT_NE(std::find(result.kept.begin(), result.kept.end(), preferred), result.kept.end());
    EXPECT_EQ(result.fixed, std::vector<int>{other});
    ASSERT_EQ(result.redundant_with[static_cast<std::size_t>(other)].size(), 1u);
    EXPECT_EQ(result.redundant_with[static_cast<std::size_t>(other)][0].column, preferred);
  }
}

TEST(Identifiability, ConditionNumberOfOrthogonalColumnsIsOne) {
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(10, 3);
  j(0, 0) = 5.0;
  j(1, 1) = 1e-6;
  j(2, 2) = 1e6;
  EXPECT_NEAR(analyseIdentifiability(j).condition_number, 1.0, 1e-12);
  EXPECT_NEAR(scaledConditionNumber(j, {0, 1, 2}), 1.0, 1e-12);
  const Eigen::MatrixXd twice = j.leftCols(1).replicate(1, 2);  // the same column twice
  EXPECT_TRUE(std::isinf(scaledConditionNumber(twice, {0, 1})) || scaledConditionNumber(twice, {0, 1}) > 1e15);
}

TEST(Identifiability, TypicalChangeDecidesWhatHasNoEffect) {
  Eigen::MatrixXd j = randomColumns(100, 2, 3);
  j.col(1) *= 1e-12;
  EXPECT_TRUE(analyseIdentifiability(j, {}, {1.0, 1.0}).no_effect[1]);
  EXPECT_FALSE(analyseIdentifiability(j, {}, {1.0, 1e6}).no_effect[1]);
}

TEST(Identifiability, RejectsInconsistentInput) {
  const Eigen::MatrixXd j = randomColumns(10, 3, 4);
  EXPECT_THROW(analyseIdentifiability(j, {0, 1}), InvalidArgument);
  EXPECT_THROW(analyseIdentifiability(j, {}, {1.0}), InvalidArgument);
  Eigen::MatrixXd bad = j;
  bad(3, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(analyseIdentifiability(bad), InvalidArgument);
}

}  // namespace
}  // namespace jointcomp
