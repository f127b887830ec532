// A joint error of a shape no few harmonics describe (a narrow bump once per motor revolution of joint 2) is found by
// the "periodic" family: discovery names a table of joint 2's motor, brings the held-out error to the noise floor,
// writes the table and reports its spectrum and the angle ranges it covers. The harmonics alone leave more on the
// held-out campaign.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/effects/periodic_table.hpp"
#include "model/identify/discovery.hpp"
#include "tests/identify/identify_test_support.hpp"

namespace jointcomp {
namespace {

using namespace identify_test;

// The RX170 with a narrow bump of joint 2's motor: two knots of 24 raised by 1.5e-4 rad, once per motor
// revolution, a shape whose spectrum spreads over many orders (no three harmonics hold it).
JointErrorModel withBump(JointErrorModel model) {
  std::vector<double> c(24, 0.0);
  c[5] = c[6] = 1.5e-4;
  PeriodicTable table;
  table.joint = 1;
  table.stage = 1;
  table.coefficients_rad = c;
  model.addEffect(
      std::make_unique<PeriodicTableEffect>(model.robot(), model.gears(), std::vector<PeriodicTable>{table}));
  return model;
}

DiscoveryResult discover(const JointErrorModel& truth, const std::vector<std::string>& types) {
  DiscoveryOptions options;
  options.types = types;
  options.max_steps = 3;
  return discoverEffects(rx170Model(), {randomCampaign(truth, 400, 81)}, {randomCampaign(truth, 150, 82)}, options);
}

TEST(DiscoveryPeriodic, FindsABumpShapedMotorErrorAndReportsItsSpectrum) {
  const JointErrorModel truth = withBump(rx170Model());
  const DiscoveryResult r = discover(truth, {"offset", "harmonic", "periodic"});
  const DiscoveryStep* table = nullptr;
  for (const DiscoveryStep& s : r.steps) {
    if (s.type == "periodic" && s.joint == 1 && s.stage == 1) table = &s;
  }
  ASSERT_NE(table, nullptr) << "steps: " << r.steps.size() << ", stop: " << r.stop_reason;
  EXPECT_TRUE(table->report_fields.contains("covered_deg"));
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
  // The table is in the discovered model, and the step reports its spectrum beside its coefficients.
  ASSERT_GE(r.model.findEffect(PeriodicTableEffect::kType), 0);
  int orders = 0;
  for (const DiscoveredParameter& p : table->parameters) orders += p.name.find(".order_") != std::string::npos;
  EXPECT_EQ(orders, 3);

  // Harmonics up to the default orders leave more of it.
  const DiscoveryResult harmonics_only = discover(truth, {"offset", "harmonic"});
  EXPECT_GT(harmonics_only.final_state.heldout[0].rms, 1.2 * r.final_state.heldout[0].rms);
}

}  // namespace
}  // namespace jointcomp
