// Where a residual lies: discovery, given a vocabulary that cannot express what the truth carries (a joint-2 harmonic
// of output order 9 while only offsets are offered), stops above the noise floor and its report names the joint and
// the order; on a null campaign it reports nothing left.
#include <cmath>
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
  // The summary file says it too.
  DiscoverySources sources;
  EXPECT_THAT(discoverySummary(r, DiscoveryOptions(), sources), ::testing::HasSubstr("what is left"));
}

TEST(ResidualAnalysis, NothingLeftOnANullCampaign) {
  const DiscoveryResult r = discoverOffsets(rx170Model());
  EXPECT_FALSE(r.unexplained.above_floor) << r.unexplained.summary;
  DiscoverySources sources;
  EXPECT_THAT(discoverySummary(r, DiscoveryOptions(), sources), ::testing::Not(::testing::HasSubstr("what is left")));
}

}  // namespace
}  // namespace jointcomp
