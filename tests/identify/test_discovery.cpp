// Residual discovery on simulated campaigns whose truth carries an effect the nominal model was not told
// about (backlash, hysteresis, an extra transmission harmonic, a joint offset, nonlinear compliance, an
// undeclared payload, thermal and time drift, two at once) and on a null campaign (truth = model): the tool
// names the right effect (type, joint, part and order), brings the held-out error within 1.3x the noise
// floor, and adds nothing on the null campaign; backlash and hysteresis are told apart; Ra and Rz on a
// held-out spiral drop. Plus the new effects' predictions, strict parsing and round trip.
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/compensation/compensator.hpp"
#include "model/effects/backlash.hpp"
#include "model/effects/hysteresis.hpp"
#include "model/effects/joint_offset.hpp"
#include "model/effects/nonlinear_compliance.hpp"
#include "model/effects/payload.hpp"
#include "model/effects/registry.hpp"
#include "model/effects/thermal_drift.hpp"
#include "model/effects/transmission_error.hpp"
#include "model/experiment/campaign_simulation.hpp"
#include "model/identify/discovery.hpp"
#include "model/identify/discovery_report.hpp"
#include "model/io/parameter_file.hpp"
#include "tests/identify/identify_test_support.hpp"

namespace jointcomp {
namespace {

using namespace identify_test;

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

JointErrorModel withHysteresis(JointErrorModel model, int joint, double width_per_nm) {
  std::vector<double> w(6, 0.0);
  w[static_cast<std::size_t>(joint)] = width_per_nm;
  model.addEffect(std::make_unique<HysteresisEffect>(model.robot(), w));
  return model;
}

JointErrorModel withPayload(JointErrorModel model, double mass, const Eigen::Vector3d& com) {
  model.addEffect(std::make_unique<PayloadEffect>(model.robot(), mass, com));
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
    std::printf(" %s(%s%s%s)", s.type.c_str(), s.joint >= 0 ? ("j" + std::to_string(s.joint + 1)).c_str() : "tool",
                s.part.empty() ? "" : (" " + s.part).c_str(),
                s.cycles > 0 ? (" k" + std::to_string(static_cast<int>(s.cycles))).c_str() : "");
  }
  std::printf(" | held-out %.4f -> %.4f mm, floor %.4f mm (ratio %.2f)\n", r.initial.heldout[0].rms * 1e3,
              r.final_state.heldout[0].rms * 1e3, r.noise_floor * 1e3, r.final_state.heldout[0].rms / r.noise_floor);
}

bool found(const DiscoveryResult& r, const std::string& type, int joint, double cycles = 0.0, int stage = 0) {
  for (const DiscoveryStep& s : r.steps) {
    if (s.type == type && s.joint == joint && (cycles == 0.0 || s.cycles == cycles) && (stage == 0 || s.stage == stage))
      return true;
  }
  return false;
}

TEST(Discovery, NullCampaignAddsNothing) {
  const DiscoveryResult r = discover(rx170Model(), 11);
  print("null", r);
  EXPECT_TRUE(r.steps.empty());
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
  // Both campaigns draw from one range of poses: the held-out one stays inside the fitted coverage.
  ASSERT_EQ(r.heldout_coverage.size(), 1u);
  EXPECT_FALSE(r.heldout_coverage[0].flagged);
}

TEST(Discovery, FlagsAHeldOutCampaignBeyondTheFittedAngles) {
  // Fitted only where joint 1 is below -0.3 rad; the held-out campaign goes everywhere.
  const MeasurementCampaign all = randomCampaign(rx170Model(), 600, 12);
  const MeasurementCampaign fit = campaignRows(all, [&](std::size_t k) { return all.command[k][0] < -0.3; });
  const MeasurementCampaign held = randomCampaign(rx170Model(), 120, 13);
  int beyond = 0;
  for (const JointVector& q : held.command) beyond += q[0] > -0.3 + kCoverageHalfWidth;
  const DiscoveryResult r = discoverEffects(rx170Model(), {fit}, {held}, {});
  ASSERT_EQ(r.heldout_coverage.size(), 1u);
  EXPECT_TRUE(r.heldout_coverage[0].flagged);
  EXPECT_NEAR(r.heldout_coverage[0].fraction_outside[0], beyond / 120.0, 0.05);
  EXPECT_GT(r.heldout_coverage[0].fraction_outside[0], 0.2);
}

// Campaigns seen from an instrument: positions through a rigid transform, the frame declared "instrument".
MeasurementCampaign seenFrom(MeasurementCampaign c, const Eigen::Isometry3d& instrument_from_base,
                             const std::string& source) {
  for (Eigen::Vector3d& p : c.position) p = instrument_from_base * p;
  c.frame = MeasurementFrame::Instrument;
  c.source = source;
  return c;
}

TEST(Discovery, FittedCampaignsFromTwoInstrumentSetUpsEachGetTheirOwnFrame) {
  Eigen::Isometry3d tracker = Eigen::Isometry3d::Identity();
  tracker.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.1, 0.2, 1.0).normalized()).toRotationMatrix();
  tracker.translation() = Eigen::Vector3d(2.5, -1.0, 0.3);
  // The robot has a joint-3 offset the prior does not know.
  const JointErrorModel truth = withOffset(rx170Model(), 2, 1e-3);
  const MeasurementCampaign first = seenFrom(randomCampaign(truth, 200, 14), tracker, "first.csv");
  const MeasurementCampaign same = seenFrom(randomCampaign(truth, 200, 15), tracker, "same.csv");
  DiscoveryOptions options;
  options.types = {"offset"};
  options.max_steps = 1;
  // One set-up: one frame for both.
  const DiscoveryResult together = discoverEffects(rx170Model(), {first, same}, {}, options);
  EXPECT_EQ(together.calibration.setup_of_campaign, (std::vector<int>{0, 0}));
  EXPECT_TRUE(found(together, "offset", 2));
  // The tracker moved 100 mm, or turned 5 degrees: another set-up with its own frame, and the offset is
  // found all the same, leaving the noise.
  Eigen::Isometry3d moved = tracker;
  moved.translation() += Eigen::Vector3d(0.0, 0.1, 0.0);
  Eigen::Isometry3d turned = tracker;
  turned.linear() = Eigen::AngleAxisd(5.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()) * tracker.linear();
  for (const Eigen::Isometry3d& other : {moved, turned}) {
    const MeasurementCampaign second = seenFrom(randomCampaign(truth, 200, 15), other, "second.csv");
    const DiscoveryResult r = discoverEffects(rx170Model(), {first, second}, {}, options);
    EXPECT_EQ(r.calibration.setup_of_campaign, (std::vector<int>{0, 1}));
    ASSERT_EQ(r.calibration.estimate.setUpCount(), 2);
    EXPECT_LT((r.calibration.estimate.ofSetUp(1).instrumentFromBase().translation() - other.translation()).norm(),
              0.01);
    EXPECT_TRUE(found(r, "offset", 2));
    EXPECT_LT(r.final_state.fitted.rms, 1.3 * r.noise_floor);
    EXPECT_GT(r.initial.fitted.rms, 3.0 * r.final_state.fitted.rms);
  }
}

TEST(Discovery, RejectsATermThatHelpsOnePartAndHurtsAnother) {
  // Joint 3 is off by 1 mrad, but only where joint 1 is below -0.5 rad (the rest of the workspace is
  // exact): one offset over all the data fits the average, helps one region and hurts the other.
  const MeasurementCampaign biased = randomCampaign(withOffset(rx170Model(), 2, 1e-3), 600, 31);
  const MeasurementCampaign exact = randomCampaign(rx170Model(), 600, 31);
  MeasurementCampaign fit = exact;
  for (std::size_t k = 0; k < fit.size(); ++k) {
    if (fit.command[k][0] < -0.5) fit.position[k] = biased.position[k];
  }
  DiscoveryOptions options;
  options.types = {"offset"};
  const DiscoveryResult r = discoverEffects(rx170Model(), {fit}, {}, options);
  EXPECT_FALSE(found(r, "offset", 2));
  EXPECT_THAT(r.rejected_at_stop, ::testing::HasSubstr("offset joint 3"));
  EXPECT_THAT(r.rejected_at_stop, ::testing::HasSubstr("part"));
  EXPECT_THAT(r.rejected_at_stop, ::testing::HasSubstr("offset joint 3: does not transfer, CV error"));
  // The same offset everywhere transfers and is found.
  const DiscoveryResult everywhere = discoverEffects(rx170Model(), {biased}, {}, options);
  EXPECT_TRUE(found(everywhere, "offset", 2));
}

TEST(Discovery, FindsBacklash) {
  const DiscoveryResult r = discover(withBacklash(rx170Model(), 1, 0.012 * kDegree), 21);
  print("backlash j2", r);
  ASSERT_FALSE(r.steps.empty());
  EXPECT_EQ(r.steps[0].type, "backlash");
  EXPECT_EQ(r.steps[0].joint, 1);
  EXPECT_NEAR(r.steps[0].parameters.at(0).value, 0.012 * kDegree, 0.2 * 0.012 * kDegree);
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
  // The summary gives the discovered width as the last refit left it, as parameters.json has it.
  const std::string summary = discoverySummary(r, DiscoveryOptions(), DiscoverySources{});
  const std::string width = r.model.robot().joints[1].name + ".backlash_width_rad";
  const std::size_t final_section = summary.find("final values of the discovered effects");
  ASSERT_NE(final_section, std::string::npos) << summary;
  EXPECT_NE(summary.find(width, final_section), std::string::npos) << summary;
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
  truth.addEffect(
      std::make_unique<NonlinearComplianceEffect>(truth.robot(), std::vector<double>{0, 3e-12, 0, 0, 0, 0}));
  const DiscoveryResult r = discover(truth, 61);
  print("nonlinear_compliance j2", r);
  ASSERT_FALSE(r.steps.empty());
  EXPECT_EQ(r.steps[0].type, "nonlinear_compliance");
  EXPECT_EQ(r.steps[0].joint, 1);
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
}

TEST(Discovery, FindsTwoAtOnce) {
  const DiscoveryResult r = discover(withOffset(withBacklash(rx170Model(), 1, 0.012 * kDegree), 4, 0.03 * kDegree), 51);
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

// Largest |link - planned| of joint `joint` over random poses when the truth is commanded with the
// references a model's compensator computes (each pose approached from the previous one).
double compensatedJointError(const JointErrorModel& truth, const JointErrorModel& model, int joint) {
  const MeasurementCampaign poses = randomCampaign(truth, 40, 777);
  Compensator compensator(model, model.allEffects());
  JointErrorWorkspace ws(truth.robot());
  double worst = 0.0;
  for (std::size_t k = 1; k < poses.size(); ++k) {
    JointContext planned(6);
    planned.q = poses.command[k];
    planned.velocity = (poses.command[k] - poses.command[k - 1]) / 5.0;
    JointVector reference(6);
    compensator.compensate(planned, reference);
    JointContext actual(6);
    actual.command = reference;
    actual.velocity = planned.velocity;
    EXPECT_TRUE(settleStatically(truth, truth.allEffects(), ws, actual).converged);
    worst = std::max(worst, std::abs(actual.q[joint] - poses.command[k][joint]));
  }
  return worst;
}

TEST(Discovery, FindsHysteresis) {
  // Joint 2, h = 1.5e-6 rad/(N m): at the mean |tau| of the random poses (about 150 N m) the link lags by
  // about 1.1e-4 rad (0.006 deg), as much as the backlash of FindsBacklash, but zero where joint 2 is unloaded.
  const JointErrorModel truth = withHysteresis(rx170Model(), 1, 1.5e-6);
  const DiscoveryResult r = discover(truth, 71);
  print("hysteresis j2", r);
  ASSERT_FALSE(r.steps.empty());
  EXPECT_EQ(r.steps[0].type, "hysteresis");
  EXPECT_EQ(r.steps[0].joint, 1);
  EXPECT_EQ(r.steps[0].parameters.at(0).name, "joint_2.hysteresis_width_rad_per_nm");
  EXPECT_NEAR(r.steps[0].parameters.at(0).value, 1.5e-6, 0.2 * 1.5e-6);
  EXPECT_FALSE(found(r, "backlash", 1));
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
  // The written parameter file loads back, and its compensator takes the hysteresis out of joint 2.
  const std::string text = parametersToJson(r.model);
  const JointErrorModel back = parseParameters(text, "discovered.json", r.model.sharedRobot());
  ASSERT_GE(back.findEffect(HysteresisEffect::kType), 0);
  EXPECT_EQ(parametersToJson(back), text);
  const double without = compensatedJointError(truth, rx170Model(), 1);
  const double with = compensatedJointError(truth, back, 1);
  std::printf("[ discovery ] hysteresis j2: joint-2 error after compensation %.2e rad (nominal model %.2e rad)\n", with,
              without);
  EXPECT_LT(with, 0.3 * without);
}

// Backlash (constant lost motion) and hysteresis (lost motion growing with the load) on the same joint
// are told apart: each truth is named as what it is, and the other is not added.
TEST(Discovery, BacklashAndHysteresisAreToldApart) {
  for (std::uint64_t seed : {81u, 82u}) {
    const DiscoveryResult b = discover(withBacklash(rx170Model(), 1, 0.012 * kDegree), seed);
    print("backlash j2 (vs hyst.)", b);
    ASSERT_FALSE(b.steps.empty());
    EXPECT_EQ(b.steps[0].type, "backlash") << "seed " << seed;
    EXPECT_FALSE(found(b, "hysteresis", 1)) << "seed " << seed;
    const DiscoveryResult h = discover(withHysteresis(rx170Model(), 1, 1.5e-6), seed);
    print("hysteresis j2 (vs back.)", h);
    ASSERT_FALSE(h.steps.empty());
    EXPECT_EQ(h.steps[0].type, "hysteresis") << "seed " << seed;
    EXPECT_FALSE(found(h, "backlash", 1)) << "seed " << seed;
  }
}

TEST(Discovery, FindsPayload) {
  // 12 kg the campaign does not declare, its centre 0.05 m off the flange axis and 0.12 m out.
  const Eigen::Vector3d com(0.05, 0.0, 0.12);
  const JointErrorModel truth = withPayload(rx170Model(), 12.0, com);
  const DiscoveryResult r = discover(truth, 91);
  print("payload 12 kg", r);
  ASSERT_FALSE(r.steps.empty());
  EXPECT_EQ(r.steps[0].type, "payload");
  EXPECT_EQ(r.steps[0].joint, -1);
  ASSERT_EQ(r.steps[0].parameters.size(), 4u);
  EXPECT_EQ(r.steps[0].parameters[0].name, "payload.mass_kg");
  EXPECT_NEAR(r.steps[0].parameters[0].value, 12.0, 0.1 * 12.0);
  std::printf("[ discovery ] payload: m = %.3f +- %.3f kg, c = (%.3f, %.3f, %.3f) m\n", r.steps[0].parameters[0].value,
              r.steps[0].parameters[0].sigma, r.steps[0].parameters[1].value, r.steps[0].parameters[2].value,
              r.steps[0].parameters[3].value);
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
  // The parameter file holds it as a "payload" load effect and loads back.
  const std::string text = parametersToJson(r.model);
  const JointErrorModel back = parseParameters(text, "discovered.json", r.model.sharedRobot());
  const int index = back.findEffect(PayloadEffect::kType);
  ASSERT_GE(index, 0);
  EXPECT_EQ(back.effect(index).role(), EffectRole::Load);
  EXPECT_EQ(parametersToJson(back), text);
  // Its compensator takes the payload's deflection out of joint 2.
  const double without = compensatedJointError(truth, rx170Model(), 1);
  const double with = compensatedJointError(truth, back, 1);
  std::printf("[ discovery ] payload: joint-2 error after compensation %.2e rad (nominal model %.2e rad)\n", with,
              without);
  EXPECT_LT(with, 0.1 * without);
  // The report names it without a joint.
  const nlohmann::ordered_json report = discoveryReportJson(r, {}, DiscoverySources{}, 0.0);
  EXPECT_EQ(report["steps"][0]["type"], "payload");
  EXPECT_TRUE(report["steps"][0]["joint"].is_null());
  EXPECT_TRUE(report["not_candidates"].empty());
}

TEST(Discovery, FindsThermalDrift) {
  // Joint 3 drifts by 3e-5 rad/degC; the robot warms up by 10 degC (time constant 400 s: most of it in
  // the first third of the 20 min of each campaign, then a plateau, which a drift linear in time does not
  // follow), and the campaign files carry the temperature.
  JointErrorModel truth = rx170Model();
  truth.addEffect(std::make_unique<ThermalDriftEffect>(truth.robot(), std::vector<double>{0, 0, 3e-5, 0, 0, 0}, 20.0,
                                                       std::vector<double>(6, 0.0), 0.0));
  CampaignSimulationSpec spec;
  spec.protocol = CampaignProtocol::RandomPoses;
  spec.random.count = 240;
  spec.seed = 101;
  spec.temperature.enabled = true;
  spec.temperature.time_constant_s = 400.0;
  const MeasurementCampaign fit = simulateCampaign(truth, spec);
  ASSERT_TRUE(std::isfinite(fit.temperature.back()));
  EXPECT_GT(fit.temperature.back() - fit.temperature.front(), 5.0);
  spec.seed += 1000;
  spec.random.count = 120;
  const MeasurementCampaign held = simulateCampaign(truth, spec);
  DiscoveryOptions options;
  options.max_harmonic_order = 3;
  options.max_steps = 4;
  const DiscoveryResult r = discoverEffects(rx170Model(), {fit}, {held}, options);
  print("thermal j3", r);
  ASSERT_FALSE(r.steps.empty());
  bool thermal = false;
  for (const DiscoveryStep& s : r.steps) {
    thermal = thermal || (s.type == "thermal" && s.joint == 2 && s.part == "temperature");
    EXPECT_FALSE(s.type == "thermal" && s.joint != 2) << "thermal on joint " << s.joint + 1;
  }
  EXPECT_TRUE(thermal);
  EXPECT_EQ(r.steps[0].type, "thermal");
  EXPECT_EQ(r.steps[0].part, "temperature");
  EXPECT_EQ(r.steps[0].joint, 2);
  EXPECT_FALSE(found(r, "thermal", 2, 0.0) && r.steps.size() > 1 && r.steps[1].type == "thermal");
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
}

TEST(Discovery, FindsTimeDrift) {
  // Joint 2 creeps by 2e-7 rad/s (0.24 mrad over the 20 min of a campaign); no temperature column.
  JointErrorModel truth = rx170Model();
  truth.addEffect(std::make_unique<ThermalDriftEffect>(truth.robot(), std::vector<double>(6, 0.0), 20.0,
                                                       std::vector<double>{0, 2e-7, 0, 0, 0, 0}, 0.0));
  const DiscoveryResult r = discover(truth, 121);
  print("time drift j2", r);
  ASSERT_FALSE(r.steps.empty());
  EXPECT_EQ(r.steps[0].type, "thermal");
  EXPECT_EQ(r.steps[0].part, "time");
  EXPECT_EQ(r.steps[0].joint, 1);
  EXPECT_NEAR(r.steps[0].parameters.at(0).value, 2e-7, 0.2 * 2e-7);
  EXPECT_LT(r.final_state.heldout[0].rms, 1.3 * r.noise_floor);
}

// Ra and Rz of the Z error on a path: a held-out spiral (the paper's, quasi-static robot) beside the
// fitted random poses. Finite, Ra well below Rz, and both lower once the injected effect is found.
TEST(Discovery, RaRzOnHeldOutSpiral) {
  const JointErrorModel truth = withHarmonic(rx170Model(), 2, 1, 1.0, 0.004 * kDegree);
  const MeasurementCampaign fit = randomCampaign(truth, 240, 111);
  CampaignSimulationSpec spec;
  spec.protocol = CampaignProtocol::Spiral;
  spec.seed = 112;
  const MeasurementCampaign spiral = simulateCampaign(truth, spec);
  EXPECT_TRUE(isPathCampaign(spiral));
  EXPECT_FALSE(isPathCampaign(fit));
  DiscoveryOptions options;
  options.max_harmonic_order = 3;
  options.max_steps = 4;
  const DiscoveryResult r = discoverEffects(rx170Model(), {fit}, {spiral}, options);
  print("harmonic j3, spiral", r);
  ASSERT_FALSE(r.steps.empty());
  EXPECT_EQ(r.steps[0].type, "harmonic");
  ASSERT_EQ(r.initial.paths.size(), 1u);
  ASSERT_EQ(r.final_state.paths.size(), 1u);
  const PathRoughness& before = r.initial.paths[0];
  const PathRoughness& after = r.final_state.paths[0];
  std::printf("[ discovery ] spiral (%d rows): Ra %.4f -> %.4f mm, Rz %.4f -> %.4f mm\n", after.rows, before.ra * 1e3,
              after.ra * 1e3, before.rz * 1e3, after.rz * 1e3);
  EXPECT_TRUE(before.held_out);
  EXPECT_EQ(before.rows, static_cast<int>(spiral.size()));
  for (const PathRoughness* p : {&before, &after}) {
    EXPECT_TRUE(std::isfinite(p->ra) && std::isfinite(p->rz));
    EXPECT_GT(p->ra, 0.0);
    EXPECT_LE(p->ra, 0.5 * p->rz);
  }
  EXPECT_LT(after.ra, 0.7 * before.ra);
  EXPECT_LT(after.rz, 0.8 * before.rz);
  const nlohmann::ordered_json report =
      discoveryReportJson(r, options, DiscoverySources{{}, {}, {"fit.csv"}, {"spiral.csv"}, {}}, 0.0);
  ASSERT_EQ(report["final"]["ra_rz_on_paths"].size(), 1u);
  EXPECT_EQ(report["final"]["ra_rz_on_paths"][0]["campaign"], "spiral.csv");
  EXPECT_EQ(report["final"]["ra_rz_on_paths"][0]["set"], "held_out");
  EXPECT_NEAR(report["final"]["ra_rz_on_paths"][0]["ra_mm"].get<double>(), after.ra * 1e3, 1e-12);
  EXPECT_TRUE(report["initial"]["ra_rz_on_paths"].is_array());
  // A fitted path: the spiral's rows among the fitted ones are scored as the second fitted campaign.
  options.max_steps = 1;
  options.types = {"harmonic"};
  const DiscoveryResult both = discoverEffects(rx170Model(), {fit, spiral}, {}, options);
  ASSERT_EQ(both.initial.paths.size(), 1u);
  EXPECT_FALSE(both.initial.paths[0].held_out);
  EXPECT_EQ(both.initial.paths[0].campaign, 1);
  EXPECT_EQ(both.initial.paths[0].rows, static_cast<int>(spiral.size()));
  ASSERT_EQ(both.final_state.paths.size(), 1u);
  EXPECT_LT(both.final_state.paths[0].ra, both.initial.paths[0].ra);
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
  // Hysteresis: -h/2 |tau| tanh(v / v_s), zero without load, flips with the direction.
  JointContext loaded = ctx;
  loaded.load_torque[1] = -200.0;
  dq.setZero();
  HysteresisEffect(robot, {0, 1e-6, 0, 0, 0, 0}).addJointError(robot, loaded, dq);
  EXPECT_NEAR(dq[1], -0.5 * 1e-6 * 200.0 * std::tanh(0.5 / 1e-3), 1e-15);
  loaded.velocity[1] = -0.5;
  dq.setZero();
  HysteresisEffect(robot, {0, 1e-6, 0, 0, 0, 0}).addJointError(robot, loaded, dq);
  EXPECT_NEAR(dq[1], 1e-4, 1e-15);
  loaded.load_torque[1] = 0.0;
  dq.setZero();
  HysteresisEffect(robot, {0, 1e-6, 0, 0, 0, 0}).addJointError(robot, loaded, dq);
  EXPECT_EQ(dq[1], 0.0);
  EXPECT_THROW(HysteresisEffect(robot, {0, 0}), ParameterError);
  EXPECT_THROW(HysteresisEffect(robot, {0, std::nan(""), 0, 0, 0, 0}), ParameterError);
  EXPECT_THROW(HysteresisEffect(robot, std::vector<double>(6, 0.0), 0.0), ParameterError);
  const nlohmann::json bad_h = {{"type", "hysteresis"}, {"width_rad_per_nm", {0, 0, 0, 0, 0, 0}}, {"width_rad", 1}};
  EXPECT_THROW(createEffect(bad_h, robot, model.gears(), "effects[3]"), ParameterError);
  const nlohmann::json short_h = {{"type", "hysteresis"}, {"width_rad_per_nm", {0, 0}}};
  EXPECT_THROW(createEffect(short_h, robot, model.gears(), "effects[3]"), ParameterError);
  // Payload: the same load torque as a declared payload of that mass at that centre.
  const Eigen::Vector3d com(0.05, -0.02, 0.12);
  JointVector q(6);
  q << 0.3, 0.7, 0.4, -0.5, 0.9, 0.2;
  JointErrorWorkspace ws(robot);
  JointContext declared(6);
  declared.q = q;
  declared.payload_mass = 7.5;
  declared.payload_com = com;
  computeLoadTorque(model, 0, ws, declared);
  JointErrorModel carrying = model;
  carrying.addEffect(std::make_unique<PayloadEffect>(robot, 7.5, com));
  JointContext undeclared(6);
  undeclared.q = q;
  computeLoadTorque(carrying, EffectMask(1) << (carrying.effectCount() - 1), ws, undeclared);
  EXPECT_LT((undeclared.load_torque - declared.load_torque).cwiseAbs().maxCoeff(), 1e-9);
  JointContext bare(6);
  bare.q = q;
  computeLoadTorque(model, 0, ws, bare);
  EXPECT_GT((undeclared.load_torque - bare.load_torque).cwiseAbs().maxCoeff(), 10.0);
  EXPECT_THROW(PayloadEffect(robot, std::nan(""), com), ParameterError);
  const nlohmann::json good_p = {{"type", "payload"}, {"mass_kg", 7.5}, {"com_m", {0.05, -0.02, 0.12}}};
  const auto parsed = createEffect(good_p, robot, model.gears(), "effects[3]");
  EXPECT_EQ(parsed->parameters(), (std::vector<double>{7.5, 0.05, -0.02, 0.12}));
  EXPECT_EQ(parsed->toJson(), good_p);
  const nlohmann::json bad_p = {{"type", "payload"}, {"mass_kg", 7.5}, {"com_m", {0.05, 0.12}}};
  EXPECT_THROW(createEffect(bad_p, robot, model.gears(), "effects[3]"), ParameterError);
  const nlohmann::json extra_p = {{"type", "payload"}, {"mass_kg", 7.5}, {"com_m", {0, 0, 0}}, {"inertia", 1}};
  EXPECT_THROW(createEffect(extra_p, robot, model.gears(), "effects[3]"), ParameterError);
  const nlohmann::json missing_p = {{"type", "payload"}, {"com_m", {0, 0, 0}}};
  EXPECT_THROW(createEffect(missing_p, robot, model.gears(), "effects[3]"), ParameterError);
  for (const char* type : {"backlash", "nonlinear_compliance", "thermal", "hysteresis", "payload"}) {
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
    int joint;  // -1: payload
    double cycles;
    std::function<JointErrorModel(double)> truth;
    std::vector<double> magnitudes;  // rad (hysteresis: rad/(N m), payload: kg, thermal: rad/degC)
    bool warm_up = false;            // the campaigns carry a temperature (warm-up of 10 degC, 400 s)
    std::string part;                // must match when not empty (thermal: "temperature")
  };
  const std::vector<Case> cases = {
      {"backlash j2",
       "backlash",
       1,
       0.0,
       [](double m) { return withBacklash(rx170Model(), 1, m); },
       {0.001 * kDegree, 0.003 * kDegree, 0.01 * kDegree},
       false,
       ""},
      {"harmonic j3 motor k1",
       "harmonic",
       2,
       1.0,
       [](double m) { return withHarmonic(rx170Model(), 2, 1, 1.0, m); },
       {0.0005 * kDegree, 0.0015 * kDegree, 0.005 * kDegree},
       false,
       ""},
      {"offset j4",
       "offset",
       3,
       0.0,
       [](double m) { return withOffset(rx170Model(), 3, m); },
       {0.002 * kDegree, 0.006 * kDegree, 0.02 * kDegree},
       false,
       ""},
      {"hysteresis j2 [rad/Nm]",
       "hysteresis",
       1,
       0.0,
       [](double m) { return withHysteresis(rx170Model(), 1, m); },
       {1.5e-7, 5e-7, 1.5e-6},
       false,
       ""},
      {"payload [kg]",
       "payload",
       -1,
       0.0,
       [](double m) { return withPayload(rx170Model(), m, Eigen::Vector3d(0.05, 0.0, 0.12)); },
       {0.5, 2.0, 8.0},
       false,
       ""},
      {"thermal j3 [rad/degC]",
       "thermal",
       2,
       0.0,
       [](double m) {
         JointErrorModel t = rx170Model();
         std::vector<double> a(6, 0.0);
         a[2] = m;
         t.addEffect(std::make_unique<ThermalDriftEffect>(t.robot(), a, 20.0, std::vector<double>(6, 0.0), 0.0));
         return t;
       },
       {1e-6, 3e-6, 1e-5},
       true,
       "temperature"},
  };
  const std::vector<double> noise_scales = {1.0, 3.0};
  const int seeds = 4;
  for (const Case& c : cases) {
    const bool in_degrees = c.name.find('[') == std::string::npos;
    const double unit = in_degrees ? kDegree : 1.0;
    const char* unit_name = in_degrees ? "deg" : "";
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
          spec.temperature.enabled = c.warm_up;
          spec.temperature.time_constant_s = 400.0;
          const MeasurementCampaign fit = simulateCampaign(truth, spec);
          spec.seed += 1000;
          spec.random.count = 120;
          const MeasurementCampaign held = simulateCampaign(truth, spec);
          DiscoveryOptions options;
          options.max_harmonic_order = 3;
          options.max_steps = 3;
          const DiscoveryResult r = discoverEffects(rx170Model(), {fit}, {held}, options);
          const bool hit = !r.steps.empty() && r.steps[0].type == c.type && r.steps[0].joint == c.joint &&
                           (c.cycles == 0.0 || r.steps[0].cycles == c.cycles) &&
                           (c.part.empty() || r.steps[0].part == c.part);
          hits += hit;
          if (!hit)
            misses +=
                " " + (r.steps.empty() ? std::string("nothing")
                                       : r.steps[0].type + (r.steps[0].part.empty() ? "" : "/" + r.steps[0].part) +
                                             "@j" + std::to_string(r.steps[0].joint + 1));
          within += r.final_state.heldout[0].rms <= 1.3 * r.noise_floor;
        }
        std::printf(
            "[ sweep ] %-22s noise x%.0f magnitude %.4g %s: detected %d/%d, held-out within 1.3x floor %d/%d%s%s\n",
            c.name.c_str(), noise, c.magnitudes[m] / unit, unit_name, hits, seeds, within, seeds,
            misses.empty() ? "" : "; first step instead:", misses.c_str());
        // The smallest magnitude from which up every magnitude tried was found at every seed.
        if (hits == seeds && (smallest > 0 || m + 1 == c.magnitudes.size())) smallest = c.magnitudes[m];
        if (hits < seeds) smallest = smallest > 0 ? -smallest : smallest;  // a miss stops the run
        if (m + 1 == c.magnitudes.size() && noise == 1.0) {
          EXPECT_EQ(hits, seeds) << c.name;
        }
      }
      char smallest_text[64] = "none";
      if (smallest != -1.0)
        std::snprintf(smallest_text, sizeof(smallest_text), "%.4g %s", std::abs(smallest) / unit, unit_name);
      std::printf("[ sweep ] %-22s noise x%.0f: smallest magnitude found at every seed: %s\n", c.name.c_str(), noise,
                  smallest_text);
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
