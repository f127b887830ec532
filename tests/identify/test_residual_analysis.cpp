// Where a residual lies: discovery, given a vocabulary that cannot express what the truth carries (a joint-2 harmonic
// of output order 9 while only offsets are offered), stops above the noise floor and its report names the joint and
// the order; on a null campaign it reports nothing left. How much of a residual is a function of the pose: checked
// on residuals built with a known share (noise alone, a smooth field plus noise, a drift that changes between two
// passes over the same poses).
#include <cmath>
#include <random>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/effects/transmission_error.hpp"
#include "model/experiment/campaign_simulation.hpp"
#include "model/identify/discovery.hpp"
#include "model/identify/discovery_report.hpp"
#include "model/identify/residual_analysis.hpp"
#include "tests/identify/identify_test_support.hpp"

namespace jointcomp {
namespace {

using namespace identify_test;

DiscoveryResult discoverOffsets(const JointErrorModel& truth) {
  DiscoveryOptions options;
  options.types = {"offset"};
  options.max_steps = 3;
  return discoverEffects(rx170Model(), {randomCampaign(truth, 300, 61)}, {randomCampaign(truth, 120, 62)}, options);
}

TEST(ResidualAnalysis, DiscoveryNamesWhatItCannotExplain) {
  JointErrorModel truth = rx170Model();
  Harmonic h;
  h.joint = 1;
  h.stage = truth.gears().stageCount(1) + 1;  // the output
  h.cycles_per_revolution = 9.0;
  h.amplitude_rad = 1.5e-4;
  h.phase_rad = 0.3;
  truth.addEffect(std::make_unique<TransmissionErrorEffect>(truth.robot(), truth.gears(), std::vector<Harmonic>{h}));
  const DiscoveryResult r = discoverOffsets(truth);
  const UnexplainedResidual& u = r.unexplained;
  ASSERT_TRUE(u.above_floor) << u.summary;
  EXPECT_GT(u.over_floor, kUnexplainedFactor);
  EXPECT_EQ(u.joints.front(), 1) << u.summary;
  ASSERT_FALSE(u.orders.empty());
  EXPECT_EQ(u.orders.front().joint, 1) << u.summary;
  EXPECT_EQ(u.orders.front().angle, "output");
  EXPECT_EQ(u.orders.front().order, 9);
  EXPECT_TRUE(u.orders.front().stands_out);
  EXPECT_NEAR(u.orders.front().amplitude_rad, 1.5e-4, 0.5e-4);
  EXPECT_THAT(u.summary, ::testing::HasSubstr("output order 9"));
  // 300 random poses of six joints lie radians apart: too sparse to tell a function of the pose, and said so.
  ASSERT_TRUE(u.pose.computed);
  EXPECT_GT(u.pose.median_distance_other_times, kPoseSparseDistance);
  EXPECT_THAT(u.summary, ::testing::HasSubstr("too far apart to tell"));
  // The summary file says it too.
  DiscoverySources sources;
  EXPECT_THAT(discoverySummary(r, DiscoveryOptions(), sources), ::testing::HasSubstr("what is left"));
  // And how far the held-out poses lie from the fitted ones: random poses of six joints, radians.
  ASSERT_EQ(r.heldout_coverage.size(), 1u);
  EXPECT_GT(r.heldout_coverage[0].median_pose_distance, kPoseSparseDistance);
  EXPECT_THAT(discoverySummary(r, DiscoveryOptions(), sources),
              ::testing::HasSubstr("(median) from the nearest fitted pose"));
}

// Rows on a dense random set of poses (two joints move), times 1 s apart in the order the poses are visited.
struct PoseRows {
  std::vector<JointVector> q;
  std::vector<Eigen::Vector3d> residual;
  std::vector<double> time;
};

PoseRows randomPoses(int rows, unsigned seed) {
  PoseRows p;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> angle(-1.0, 1.0);
  for (int i = 0; i < rows; ++i) {
    JointVector q = JointVector::Zero(6);
    q[0] = angle(rng);
    q[1] = angle(rng);
    p.q.push_back(q);
    p.time.push_back(static_cast<double>(i));
  }
  return p;
}

Eigen::Vector3d gaussian3(std::mt19937& rng, double sigma) {
  std::normal_distribution<double> g(0.0, sigma);
  return {g(rng), g(rng), g(rng)};
}

TEST(PosePredictability, NoiseAloneIsNoFunctionOfThePose) {
  PoseRows p = randomPoses(3000, 5);
  std::mt19937 rng(6);
  for (std::size_t i = 0; i < p.q.size(); ++i) p.residual.push_back(gaussian3(rng, 1e-4));
  const PosePredictability r = posePredictability(p.q, p.residual, p.time);
  ASSERT_TRUE(r.computed);
  EXPECT_EQ(r.scored_rows, 3000);
  // The mean of k independent neighbours adds 1/k of the variance: sqrt(4/3) of the RMS with k = 3.
  EXPECT_NEAR(r.left_other_times_rms / r.residual_rms, std::sqrt(4.0 / 3.0), 0.05);
  EXPECT_NEAR(r.left_any_time_rms / r.residual_rms, std::sqrt(4.0 / 3.0), 0.05);
  EXPECT_LT(r.smooth_share, 0.05);
}

TEST(PosePredictability, ASmoothFieldPlusNoiseIsFoundWithItsShare) {
  PoseRows p = randomPoses(3000, 7);
  std::mt19937 rng(8);
  const double noise = 0.5e-4;
  double field_ss = 0.0;
  for (const JointVector& q : p.q) {
    const Eigen::Vector3d field(2e-4 * std::sin(q[0] + 2.0 * q[1]), 1e-4 * q[0] * q[1], 1e-4 * std::cos(3.0 * q[0]));
    field_ss += field.squaredNorm();
    p.residual.push_back(field + gaussian3(rng, noise));
  }
  const double field_var = field_ss / static_cast<double>(p.q.size());
  const double share = field_var / (field_var + 3.0 * noise * noise);
  const PosePredictability r = posePredictability(p.q, p.residual, p.time);
  ASSERT_TRUE(r.computed);
  EXPECT_NEAR(r.smooth_share, share, 0.05) << "true share " << share;
  // What neighbours leave is the noise's part, sqrt(3 (1 + 1/3)) sigma.
  EXPECT_NEAR(r.left_other_times_rms, std::sqrt(4.0) * noise, 0.15 * std::sqrt(4.0) * noise);
  EXPECT_LT(r.median_distance_other_times, 0.05);
}

TEST(PosePredictability, ADriftThatChangesBetweenVisitsIsNotAPoseFunction) {
  // One line of poses swept twice, an hour apart; the residual is a random walk in time, another on each pass:
  // rows close in pose and time agree, the same pose on the other pass does not.
  PoseRows p;
  std::mt19937 rng(9);
  for (int pass = 0; pass < 2; ++pass) {
    Eigen::Vector3d walk = Eigen::Vector3d::Zero();
    for (int i = 0; i < 1500; ++i) {
      JointVector q = JointVector::Zero(6);
      q[0] = -1.0 + 2.0 * i / 1500.0;
      q[1] = 0.05 * pass;  // a pose of one pass is nearer to its own pass's neighbours than to the other pass
      walk += gaussian3(rng, 1e-5);
      p.q.push_back(q);
      p.residual.push_back(walk);
      p.time.push_back(pass * 3600.0 + i);
    }
  }
  const PosePredictability r = posePredictability(p.q, p.residual, p.time);
  ASSERT_TRUE(r.computed);
  EXPECT_LT(r.smooth_share, 0.1);
  EXPECT_LT(r.left_any_time_rms, 0.3 * r.left_other_times_rms);
  EXPECT_LT(r.median_distance_any_time, 0.01);
  EXPECT_NEAR(r.median_distance_other_times, 0.05, 0.01);
}

TEST(PosePredictability, ScoresAStrideOfLargeCampaignsAndRejectsBadRows) {
  PoseRows p = randomPoses(1000, 10);
  for (double& t : p.time) t *= 10.0;  // every row has rows 600 s away
  std::mt19937 rng(11);
  for (std::size_t i = 0; i < p.q.size(); ++i) p.residual.push_back(gaussian3(rng, 1e-4));
  EXPECT_EQ(posePredictability(p.q, p.residual, p.time, 3, 600.0, 250).scored_rows, 250);
  // No row has neighbours three hours away: nothing computed, nothing claimed.
  EXPECT_FALSE(posePredictability(p.q, p.residual, p.time, 3, 3.0 * 3600.0).computed);
  p.residual[17].x() = std::nan("");
  EXPECT_THROW(
      {
        try {
          posePredictability(p.q, p.residual, p.time);
        } catch (const InvalidArgument& e) {
          EXPECT_THAT(e.what(), ::testing::HasSubstr("row 17"));
          throw;
        }
      },
      InvalidArgument);
  p.time.pop_back();
  EXPECT_THROW(posePredictability(p.q, p.residual, p.time), InvalidArgument);
}

TEST(ResidualAnalysis, NothingLeftOnANullCampaign) {
  const DiscoveryResult r = discoverOffsets(rx170Model());
  EXPECT_FALSE(r.unexplained.above_floor) << r.unexplained.summary;
  DiscoverySources sources;
  EXPECT_THAT(discoverySummary(r, DiscoveryOptions(), sources), ::testing::Not(::testing::HasSubstr("what is left")));
}

}  // namespace
}  // namespace jointcomp
