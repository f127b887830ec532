// Discovery's tables whose resolution the data choose, pairs of joints fitted together, and the transfer
// check as statistics: on simulated RX170 campaigns whose truth carries a local ripple (17 cycles per
// revolution of a joint's output, its amplitude changing along the revolution) that no 24-knot table and no
// single harmonic holds, on one joint and on two, and a small thermal drift that lowers the error by much
// while one time block is worse only by its noise.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/effects/periodic_table.hpp"
#include "model/effects/thermal_drift.hpp"
#include "model/identify/discovery.hpp"
#include "tests/identify/identify_test_support.hpp"

namespace jointcomp {
namespace {

using namespace identify_test;

constexpr double kPi = 3.14159265358979323846;

// A table of 128 knots over a joint's output: 17 cycles a revolution, the amplitude swelling and fading
// along it (what a 24-knot table cannot follow: its knots lie 2.8 ripple periods apart).
PeriodicTable ripple(int joint, double amplitude) {
  PeriodicTable table;
  table.joint = joint;
  table.stage = 3;  // the RX170's gear trains have two stages: 3 is the output
  for (int k = 0; k < 128; ++k) {
    const double u = 2.0 * kPi * k / 128.0;
    table.coefficients_rad.push_back(amplitude * std::sin(17.0 * u) * (1.0 + 0.7 * std::cos(u)));
  }
  return table;
}

JointErrorModel withTables(JointErrorModel model, const std::vector<PeriodicTable>& tables) {
  model.addEffect(std::make_unique<PeriodicTableEffect>(model.robot(), model.gears(), tables));
  return model;
}

DiscoveryResult discoverTables(const JointErrorModel& truth, const std::vector<int>& knots, int rows) {
  DiscoveryOptions options;
  options.types = {"offset", "harmonic", "periodic"};
  options.table_knots = knots;
  options.max_steps = 3;
  return discoverEffects(rx170Model(), {randomCampaign(truth, rows, 301)}, {randomCampaign(truth, rows / 3, 302)},
                         options);
}

void print(const char* name, const DiscoveryResult& r) {
  std::printf("[ tables ] %-28s", name);
  for (const DiscoveryStep& s : r.steps)
    std::printf(" | %s %s%s", s.type.c_str(), s.joint_name.c_str(), s.detail.c_str());
  std::printf(" | held-out %.4f -> %.4f mm, floor %.4f mm\n", r.initial.heldout[0].rms * 1e3,
              r.final_state.heldout[0].rms * 1e3, r.noise_floor * 1e3);
}

TEST(DiscoveryTables, TheDataChooseAFineTableForALocalRipple) {
  const JointErrorModel truth = withTables(rx170Model(), {ripple(1, 1.5e-4)});
  const DiscoveryResult fine = discoverTables(truth, {16, 32, 64, 128}, 3000);
  print("ripple j2, up to 128 knots", fine);
  ASSERT_FALSE(fine.steps.empty()) << fine.stop_reason << "; " << fine.rejected_at_stop;
  const DiscoveryStep& first = fine.steps[0];
  EXPECT_EQ(first.type, "periodic");
  EXPECT_EQ(first.joint, 1);
  EXPECT_EQ(first.part, "output");
  EXPECT_GE(first.cycles, 64.0);  // the knot count, chosen by cross-validation
  EXPECT_TRUE(first.report_fields.contains("roughness_weight"));
  EXPECT_TRUE(first.report_fields.contains("ridge_weight"));
  EXPECT_LT(fine.final_state.heldout[0].rms, 1.3 * fine.noise_floor);
  // Offered only 24 knots, the best discovery can do leaves the held-out campaign well above that.
  const DiscoveryResult coarse = discoverTables(truth, {24}, 3000);
  print("ripple j2, 24 knots only", coarse);
  EXPECT_GT(coarse.final_state.heldout[0].rms, 1.5 * fine.final_state.heldout[0].rms);
}

TEST(DiscoveryTables, RipplesOnTwoJointsAreTakenTogether) {
  const JointErrorModel truth = withTables(rx170Model(), {ripple(1, 1.2e-4), ripple(2, 1.2e-4)});
  const DiscoveryResult r = discoverTables(truth, {32, 64, 128}, 3000);
  print("ripples j2 and j3", r);
  ASSERT_FALSE(r.steps.empty()) << r.stop_reason << "; " << r.rejected_at_stop;
  // The first step moves both joints (their order-17 harmonics, which the spectrum scan proposes, or their
  // tables); the tables take what the harmonics leave.
  const DiscoveryStep& first = r.steps[0];
  ASSERT_EQ(first.joints.size(), 2u) << first.joint_name << first.detail;
  EXPECT_EQ(first.joints[0], 1);
  EXPECT_EQ(first.joints[1], 2);
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
  // Without pairs, the two are found one at a time.
  DiscoveryOptions single;
  single.types = {"offset", "harmonic", "periodic"};
  single.table_knots = {32, 64, 128};
  single.pairs = false;
  single.max_steps = 3;
  const DiscoveryResult one_by_one =
      discoverEffects(rx170Model(), {randomCampaign(truth, 3000, 301)}, {randomCampaign(truth, 1000, 302)}, single);
  ASSERT_FALSE(one_by_one.steps.empty());
  EXPECT_EQ(one_by_one.steps[0].joints.size(), 1u);
}

}  // namespace
}  // namespace jointcomp
