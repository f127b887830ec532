// Gear-mesh orders are never missed silently: an order-6 motor harmonic (beyond the default range of 4)
// is found without the user raising an option, proposed by the spectrum scan of the base fit's joint
// residual; an order beyond the scan too (31, a stage's gear mesh) is found when the gear data of the
// parameter file gives that stage's input teeth, and is not offered when it does not. The gear data's
// teeth are read strictly and written back.
#include <fstream>
#include <sstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "model/effects/transmission_error.hpp"
#include "model/experiment/campaign_simulation.hpp"
#include "model/identify/discovery.hpp"
#include "model/io/parameter_file.hpp"
#include "tests/identify/identify_test_support.hpp"

namespace jointcomp {
namespace {

using namespace identify_test;

// The shipped RX170 parameter file with joint 3's second stage given `teeth` input teeth.
JointErrorModel rx170WithTeeth(int teeth) {
  std::ifstream in(std::string(JOINTCOMP_DATA_DIR) + "/params/rx170.json");
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json json = nlohmann::json::parse(text.str());
  json["gears"]["joints"][2]["stage_input_teeth"] = {0, teeth};
  return parseParameters(json.dump(), "rx170 with teeth", rx170());
}

const DiscoveryStep* harmonicStep(const DiscoveryResult& r, int joint, int stage, double cycles) {
  for (const DiscoveryStep& s : r.steps) {
    if (s.type == "harmonic" && s.joint == joint && s.stage == stage && s.cycles == cycles) return &s;
  }
  return nullptr;
}

DiscoveryResult discoverHarmonics(const JointErrorModel& prior, const JointErrorModel& truth) {
  DiscoveryOptions options;  // default orders: 1 .. 4
  options.types = {"harmonic", "offset"};
  options.max_steps = 3;
  return discoverEffects(prior, {randomCampaign(truth, 300, 71)}, {randomCampaign(truth, 120, 72)}, options);
}

TEST(DiscoveryOrders, FindsAMotorOrderBeyondTheDefaultRangeByTheSpectrumScan) {
  ASSERT_LT(DiscoveryOptions().max_harmonic_order, 6);
  const DiscoveryResult r = discoverHarmonics(rx170Model(), withHarmonic(rx170Model(), 1, 1, 6.0, 8e-5, 1.1));
  const DiscoveryStep* step = harmonicStep(r, 1, 1, 6.0);
  ASSERT_NE(step, nullptr) << "steps: " << r.steps.size() << ", stop: " << r.stop_reason;
  EXPECT_EQ(step->report_fields.value("proposed_by", ""), "spectrum scan");
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
}

TEST(DiscoveryOrders, FindsAGearMeshOrderFromTheGearData) {
  constexpr int kMesh = 31;  // beyond the scan (kMaxScannedHarmonicOrder)
  ASSERT_GT(kMesh, kMaxScannedHarmonicOrder);
  const JointErrorModel prior = rx170WithTeeth(kMesh);
  const JointErrorModel truth = withHarmonic(prior, 2, 2, kMesh, 8e-5, 1.1);
  const DiscoveryResult r = discoverHarmonics(prior, truth);
  const DiscoveryStep* step = harmonicStep(r, 2, 2, kMesh);
  ASSERT_NE(step, nullptr) << "steps: " << r.steps.size() << ", stop: " << r.stop_reason;
  EXPECT_EQ(step->report_fields.value("proposed_by", ""), "gear mesh");
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
  // Without the teeth in the gear data the order is not offered, and what is left says so.
  const DiscoveryResult blind = discoverHarmonics(rx170Model(), truth);
  EXPECT_EQ(harmonicStep(blind, 2, 2, kMesh), nullptr);
  EXPECT_TRUE(blind.unexplained.above_floor);
}

TEST(DiscoveryOrders, GearTeethAreReadStrictlyAndWrittenBack) {
  const JointErrorModel model = rx170WithTeeth(31);
  EXPECT_EQ(model.gears().stageInputTeeth(2, 2), 31);
  EXPECT_EQ(model.gears().stageInputTeeth(2, 1), 0);
  EXPECT_EQ(model.gears().stageInputTeeth(0, 1), 0);
  const nlohmann::json written = model.gears().toJson(model.robot());
  EXPECT_EQ(written["joints"][2]["stage_input_teeth"], nlohmann::json({0, 31}));
  EXPECT_FALSE(written["joints"][0].contains("stage_input_teeth"));
  for (const nlohmann::json& bad : {nlohmann::json({31}), nlohmann::json({0, 2.5}), nlohmann::json({0, -1})}) {
    std::ifstream in(std::string(JOINTCOMP_DATA_DIR) + "/params/rx170.json");
    std::stringstream text;
    text << in.rdbuf();
    nlohmann::json json = nlohmann::json::parse(text.str());
    json["gears"]["joints"][2]["stage_input_teeth"] = bad;
    try {
      parseParameters(json.dump(), "bad teeth", rx170());
      ADD_FAILURE() << "accepted " << bad.dump();
    } catch (const ParameterError& error) {
      EXPECT_THAT(error.what(), ::testing::HasSubstr("stage_input_teeth"));
    }
  }
}

}  // namespace
}  // namespace jointcomp
