// Joint coverage: the union of intervals around the visited angles, checked against a brute-force scan.
#include <cmath>

#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/common/random.hpp"
#include "model/identify/joint_coverage.hpp"

namespace jointcomp {
namespace {

TEST(JointCoverage, AgreesWithABruteForceScan) {
  DeterministicRandom random(3);
  std::vector<JointVector> rows;
  for (int k = 0; k < 200; ++k) {
    JointVector q(2);
    // joint 1 in two clusters, joint 2 spread out
    q << (k % 2 ? random.uniform(-2.0, -1.5) : random.uniform(0.5, 0.6)), random.uniform(-3.0, 3.0);
    rows.push_back(q);
  }
  const double h = 0.02;
  const JointCoverage coverage = jointCoverage(rows, h);
  for (int j = 0; j < 2; ++j) {
    for (double a = -3.5; a <= 3.5; a += 0.00137) {
      bool near = false;
      for (const JointVector& q : rows) near = near || std::abs(q[j] - a) <= h;
      EXPECT_EQ(coverage.covers(j, a), near) << "joint " << j << " angle " << a;
    }
    for (std::size_t i = 1; i < coverage.visited[static_cast<std::size_t>(j)].size(); ++i)
      EXPECT_GT(coverage.visited[static_cast<std::size_t>(j)][i].low,
                coverage.visited[static_cast<std::size_t>(j)][i - 1].high);
  }
  EXPECT_GE(coverage.visited[0].size(), 2u);  // the gap between the clusters stays a gap
  std::vector<JointVector> probe = {rows[0], rows[1]};
  probe[0][0] = 0.0;  // in the gap
  EXPECT_DOUBLE_EQ(coverage.fractionOutside(0, probe), 0.5);
  EXPECT_NE(coverage.describe(0).find(", "), std::string::npos);
}

TEST(JointCoverage, MedianDistanceToTheNearestFittedPose) {
  // Two fitted poses; held-out poses 0.1, 0.2 (the median) and 2 rad away; joints covered one by one do not make
  // a covered pose: (1, 1) has both angles visited but lies 1 rad from either fitted pose.
  const std::vector<JointVector> fitted = {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(1.0, 0.0),
                                           Eigen::Vector2d(0.0, 1.0)};
  const std::vector<JointVector> rows = {Eigen::Vector2d(0.1, 0.0), Eigen::Vector2d(1.0, 0.2),
                                         Eigen::Vector2d(1.0, 3.0)};
  EXPECT_DOUBLE_EQ(medianDistanceToNearest(fitted, rows), 0.2);
  const JointCoverage coverage = jointCoverage(fitted, 0.05);
  const std::vector<JointVector> combined = {Eigen::Vector2d(1.0, 1.0)};
  EXPECT_EQ(coverage.fractionOutside(0, combined), 0.0);
  EXPECT_EQ(coverage.fractionOutside(1, combined), 0.0);
  EXPECT_DOUBLE_EQ(medianDistanceToNearest(fitted, combined), 1.0);
  // A stride of at most max_rows rows: 1 of 3 scored, the first.
  EXPECT_DOUBLE_EQ(medianDistanceToNearest(fitted, rows, 1), 0.1);
  // At most max_fitted fitted rows searched: 1 of 3 (the first, (0, 0)); the distances can only grow.
  EXPECT_DOUBLE_EQ(medianDistanceToNearest(fitted, rows, 4000, 1), std::hypot(1.0, 0.2));
  EXPECT_GE(medianDistanceToNearest(fitted, rows, 4000, 2), medianDistanceToNearest(fitted, rows));
  EXPECT_THROW(medianDistanceToNearest(fitted, rows, 4000, 0), InvalidArgument);
  EXPECT_THROW(medianDistanceToNearest({}, rows), InvalidArgument);
  EXPECT_THROW(medianDistanceToNearest(fitted, {Eigen::Vector3d::Zero()}), InvalidArgument);
  EXPECT_THROW(medianDistanceToNearest(fitted, {Eigen::Vector2d(std::nan(""), 0.0)}), InvalidArgument);
}

TEST(JointCoverage, RefusesWhatItCannotCover) {
  EXPECT_THROW(jointCoverage({}, 0.1), InvalidArgument);
  JointVector q(1);
  q << std::nan("");
  EXPECT_THROW(jointCoverage({q}, 0.1), InvalidArgument);
  q << 0.0;
  EXPECT_THROW(jointCoverage({q}, 0.0), InvalidArgument);
}

}  // namespace
}  // namespace jointcomp
