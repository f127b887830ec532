// Residual discovery on simulated campaigns whose truth carries an effect the nominal model was not told
// about (backlash, an extra transmission harmonic, a joint offset, two at once) and on a null campaign
// (truth = model): the tool names the right effect (type, joint, part and order), brings the held-out error
// within 1.3x the noise floor, and adds nothing on the null campaign. Plus the new effects' round trip.
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/effects/backlash.hpp"
#include "model/effects/joint_offset.hpp"
#include "model/effects/nonlinear_compliance.hpp"
#include "model/effects/registry.hpp"
#include "model/effects/thermal_drift.hpp"
#include "model/effects/transmission_error.hpp"
#include "model/identify/campaign_simulation.hpp"
#include "model/identify/discovery.hpp"
#include "model/io/parameter_file.hpp"
#include "tests/identify/identify_test_support.hpp"

namespace jointcomp {
namespace {

using namespace identify_test;

MeasurementCampaign randomCampaign(const JointErrorModel& truth, int count, std::uint64_t seed) {
  CampaignSimulationSpec spec;
  spec.protocol = CampaignProtocol::RandomPoses;
  spec.seed = seed;
  spec.random.count = count;
  return simulateCampaign(truth, spec);
}

struct Scenario {
  std::string name;
  JointErrorModel truth;
};

JointErrorModel withBacklash(JointErrorModel model, int joint, double width) {
  std::vector<double> w(6, 0.0);
  w[static_cast<std::size_t>(joint)] = width;
  model.addEffect(std::make_unique<BacklashEffect>(model.robot(), w));
  return model;
}

JointErrorModel withOffset(JointErrorModel model, int joint, double offset) {
  std::vector<double> o(6, 0.0);
  o[static_cast<std::size_t>(joint)] = offset;
  model.addEffect(std::make_unique<JointOffsetEffect>(model.robot(), o));
  return model;
}

JointErrorModel withHarmonic(JointErrorModel model, int joint, int stage, double cycles, double amplitude) {
  Harmonic h;
  h.joint = joint;
  h.stage = stage;
  h.cycles_per_revolution = cycles;
  h.amplitude_rad = amplitude;
  h.phase_rad = 0.6;
  model.addEffect(std::make_unique<TransmissionErrorEffect>(model.robot(), model.gears(), std::vector<Harmonic>{h}));
  return model;
}

DiscoveryResult discover(const JointErrorModel& truth, std::uint64_t seed) {
  const MeasurementCampaign fit = randomCampaign(truth, 240, seed);
  const MeasurementCampaign held = randomCampaign(truth, 120, seed + 1000);
  DiscoveryOptions options;
  options.max_harmonic_order = 3;
  options.max_steps = 4;
  return discoverEffects(rx170Model(), {fit}, {held}, options);
}

void print(const std::string& name, const DiscoveryResult& r) {
  std::printf("[ discovery ] %-22s", name.c_str());
  for (const DiscoveryStep& s : r.steps) {
    std::printf(" %s(j%d%s%s)", s.type.c_str(), s.joint + 1, s.part.empty() ? "" : (" " + s.part).c_str(),
                s.cycles > 0 ? (" k" + std::to_string(static_cast<int>(s.cycles))).c_str() : "");
  }
  std::printf(" | held-out %.4f -> %.4f mm, floor %.4f mm (ratio %.2f)\n", r.initial.heldout[0].rms * 1e3,
              r.final_state.heldout[0].rms * 1e3, r.noise_floor * 1e3, r.final_state.heldout[0].rms / r.noise_floor);
}

bool found(const DiscoveryResult& r, const std::string& type, int joint, double cycles = 0.0, int stage = 0) {
  for (const DiscoveryStep& s : r.steps) {
    if (s.type == type && s.joint == joint && (cycles == 0.0 || s.cycles == cycles) && (stage == 0 || s.stage == stage)) return true;
  }
  return false;
}

TEST(Discovery, NullCampaignAddsNothing) {
  const DiscoveryResult r = discover(rx170Model(), 11);
  print("null", r);
  EXPECT_TRUE(r.steps.empty());
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
}

TEST(Discovery, FindsBacklash) {
  const DiscoveryResult r = discover(withBacklash(rx170Model(), 1, 0.012 * kDegree), 21);
  print("backlash j2", r);
  ASSERT_FALSE(r.steps.empty());
  EXPECT_EQ(r.steps[0].type, "backlash");
  EXPECT_EQ(r.steps[0].joint, 1);
  EXPECT_NEAR(r.steps[0].parameters.at(0).value, 0.012 * kDegree, 0.2 * 0.012 * kDegree);
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
}

TEST(Discovery, FindsExtraHarmonic) {
  // Joint 3, one cycle per motor revolution (the prior has 2 cycles per stage-2 input turn there).
  const DiscoveryResult r = discover(withHarmonic(rx170Model(), 2, 1, 1.0, 0.004 * kDegree), 31);
  print("harmonic j3 motor k1", r);
  ASSERT_FALSE(r.steps.empty());
  EXPECT_EQ(r.steps[0].type, "harmonic");
  EXPECT_EQ(r.steps[0].joint, 2);
  EXPECT_EQ(r.steps[0].part, "motor");
  EXPECT_EQ(r.steps[0].cycles, 1.0);
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
}

TEST(Discovery, FindsJointOffset) {
  const DiscoveryResult r = discover(withOffset(rx170Model(), 3, 0.03 * kDegree), 41);
  print("offset j4", r);
  ASSERT_FALSE(r.steps.empty());
  EXPECT_EQ(r.steps[0].type, "offset");
  EXPECT_EQ(r.steps[0].joint, 3);
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
}

TEST(Discovery, FindsNonlinearCompliance) {
  JointErrorModel truth = rx170Model();
  // Joint 2 carries a few hundred N m here (balancer included): c3 = 3e-12 rad/(N m)^3 gives tenths of a mrad.
  truth.addEffect(std::make_unique<NonlinearComplianceEffect>(truth.robot(), std::vector<double>{0, 3e-12, 0, 0, 0, 0}));
  const DiscoveryResult r = discover(truth, 61);
  print("nonlinear_compliance j2", r);
  ASSERT_FALSE(r.steps.empty());
  EXPECT_EQ(r.steps[0].type, "nonlinear_compliance");
  EXPECT_EQ(r.steps[0].joint, 1);
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
}

TEST(Discovery, FindsTwoAtOnce) {
  const DiscoveryResult r =
      discover(withOffset(withBacklash(rx170Model(), 1, 0.012 * kDegree), 4, 0.03 * kDegree), 51);
  print("backlash j2 + offset j5", r);
  EXPECT_TRUE(found(r, "backlash", 1));
  EXPECT_TRUE(found(r, "offset", 4));
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
}

TEST(Discovery, WrittenModelRoundTripsThroughTheParameterFile) {
  const DiscoveryResult r = discover(withBacklash(rx170Model(), 1, 0.012 * kDegree), 21);
  const std::string text = parametersToJson(r.model);
  const JointErrorModel back = parseParameters(text, "discovered.json", r.model.sharedRobot());
  EXPECT_GE(back.findEffect(BacklashEffect::kType), 0);
  EXPECT_EQ(parametersToJson(back), text);
}

TEST(DiscoveryEffects, NewEffectsPredictAndValidate) {
  const JointErrorModel model = rx170Model();
  const Robot& robot = model.robot();
  JointContext ctx(6);
  ctx.velocity = JointVector::Zero(6);
  ctx.velocity[1] = 0.5;
  ctx.load_torque = JointVector::Constant(6, 10.0);
  ctx.temperature = 25.0;
  ctx.time = 100.0;
  JointVector dq = JointVector::Zero(6);
  BacklashEffect(robot, {0, 2e-4, 0, 0, 0, 0}).addJointError(robot, ctx, dq);
  EXPECT_NEAR(dq[1], -1e-4, 1e-12);
  dq.setZero();
  NonlinearComplianceEffect(robot, {1e-9, 0, 0, 0, 0, 0}).addJointError(robot, ctx, dq);
  EXPECT_NEAR(dq[0], -1e-6, 1e-15);
  dq.setZero();
  ThermalDriftEffect(robot, {1e-5, 0, 0, 0, 0, 0}, 20.0, {0, 1e-7, 0, 0, 0, 0}, 0.0).addJointError(robot, ctx, dq);
  EXPECT_NEAR(dq[0], 5e-5, 1e-15);
  EXPECT_NEAR(dq[1], 1e-5, 1e-15);
  EXPECT_THROW(BacklashEffect(robot, {0, 0, 0}), ParameterError);
  EXPECT_THROW(BacklashEffect(robot, std::vector<double>(6, 0.0), -1.0), ParameterError);
  const nlohmann::json bad = {{"type", "backlash"}, {"width_rad", {0, 0, 0, 0, 0, 0}}, {"oops", 1}};
  EXPECT_THROW(createEffect(bad, robot, model.gears(), "effects[3]"), ParameterError);
  for (const char* type : {"backlash", "nonlinear_compliance", "thermal"}) {
    bool registered = false;
    for (const auto& t : registeredEffectTypes()) registered = registered || t == type;
    EXPECT_TRUE(registered) << type;
  }
}

}  // namespace
}  // namespace jointcomp

namespace jointcomp {
namespace {

// Detection rate over seeds, noise levels and magnitudes, and the smallest magnitude found at every
// seed. Printed (the numbers of the report); asserted: the largest magnitudes are always found at the
// nominal noise and the null campaigns stay empty.
TEST(DiscoverySweep, DetectionRateOverSeedsNoiseAndMagnitudes) {
  struct Case {
    std::string name, type;
    int joint;
    double cycles;
    std::function<JointErrorModel(double)> truth;
    std::vector<double> magnitudes;  // rad
  };
  const std::vector<Case> cases = {
      {"backlash j2", "backlash", 1, 0.0, [](double m) { return withBacklash(rx170Model(), 1, m); },
       {0.001 * kDegree, 0.003 * kDegree, 0.01 * kDegree}},
      {"harmonic j3 motor k1", "harmonic", 2, 1.0, [](double m) { return withHarmonic(rx170Model(), 2, 1, 1.0, m); },
       {0.0005 * kDegree, 0.0015 * kDegree, 0.005 * kDegree}},
      {"offset j4", "offset", 3, 0.0, [](double m) { return withOffset(rx170Model(), 3, m); },
       {0.002 * kDegree, 0.006 * kDegree, 0.02 * kDegree}},
  };
  const std::vector<double> noise_scales = {1.0, 3.0};
  const int seeds = 4;
  for (const Case& c : cases) {
    for (double noise : noise_scales) {
      double smallest = -1.0;
      for (std::size_t m = c.magnitudes.size(); m-- > 0;) {
        int hits = 0, within = 0;
        std::string misses;
        for (int seed = 0; seed < seeds; ++seed) {
          const JointErrorModel truth = c.truth(c.magnitudes[m]);
          CampaignSimulationSpec spec;
          spec.protocol = CampaignProtocol::RandomPoses;
          spec.random.count = 240;
          spec.tracker.constant_m *= noise;
          spec.tracker.per_metre *= noise;
          spec.seed = 100 + static_cast<std::uint64_t>(seed);
          const MeasurementCampaign fit = simulateCampaign(truth, spec);
          spec.seed += 1000;
          spec.random.count = 120;
          const MeasurementCampaign held = simulateCampaign(truth, spec);
          DiscoveryOptions options;
          options.max_harmonic_order = 3;
          options.max_steps = 3;
          const DiscoveryResult r = discoverEffects(rx170Model(), {fit}, {held}, options);
          const bool hit = !r.steps.empty() && r.steps[0].type == c.type && r.steps[0].joint == c.joint &&
                           (c.cycles == 0.0 || r.steps[0].cycles == c.cycles);
          hits += hit;
          if (!hit) misses += " " + (r.steps.empty() ? std::string("nothing") : r.steps[0].type + "@j" + std::to_string(r.steps[0].joint + 1));
          within += r.final_state.heldout[0].rms <= 1.3 * r.noise_floor;
        }
        std::printf("[ sweep ] %-22s noise x%.0f magnitude %.4f deg: detected %d/%d, held-out within 1.3x floor %d/%d%s%s\n",
                    c.name.c_str(), noise, c.magnitudes[m] / kDegree, hits, seeds, within, seeds,
                    misses.empty() ? "" : "; first step instead:", misses.c_str());
        // The smallest magnitude from which up every magnitude tried was found at every seed.
        if (hits == seeds && (smallest > 0 || m + 1 == c.magnitudes.size())) smallest = c.magnitudes[m];
        if (hits < seeds) smallest = smallest > 0 ? -smallest : smallest;  // a miss stops the run
        if (m + 1 == c.magnitudes.size() && noise == 1.0) {
          EXPECT_EQ(hits, seeds) << c.name;
        }
      }
      std::printf("[ sweep ] %-22s noise x%.0f: smallest magnitude found at every seed: %s\n", c.name.c_str(), noise,
                  smallest != -1.0 ? (std::to_string(std::abs(smallest) / kDegree) + " deg").c_str() : "none");
    }
  }
  // Null campaigns: nothing added at any seed or noise level.
  for (double noise : noise_scales) {
    for (int seed = 0; seed < seeds; ++seed) {
      CampaignSimulationSpec spec;
      spec.protocol = CampaignProtocol::RandomPoses;
      spec.random.count = 240;
      spec.tracker.constant_m *= noise;
      spec.tracker.per_metre *= noise;
      spec.seed = 200 + static_cast<std::uint64_t>(seed);
      const MeasurementCampaign fit = simulateCampaign(rx170Model(), spec);
      spec.seed += 1000;
      const MeasurementCampaign held = simulateCampaign(rx170Model(), spec);
      const DiscoveryResult r = discoverEffects(rx170Model(), {fit}, {held}, {});
      EXPECT_TRUE(r.steps.empty()) << "null, noise x" << noise << ", seed " << seed << ": added "
                                   << (r.steps.empty() ? std::string() : r.steps[0].type);
    }
  }
}

}  // namespace
}  // namespace jointcomp
