// Calibration on campaigns measured from several instrument set-ups (the tracker moved between them): the
// flat parameter vector and its names with the further set-ups' frames and scales, each set-up's Jacobian
// against finite differences, a set-up's prediction as the one-set-up prediction with its frame, the
// grouping of campaigns into set-ups, and the joint calibration on simulated campaigns with known truth:
// every frame comes back, the robot's parameters come back within their uncertainty, and they are known
// better than from one campaign alone.
#include <algorithm>
#include <cmath>
#include <memory>
#include <set>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "calibration_test_support.hpp"
#include "model/common/errors.hpp"
#include "model/effects/backlash.hpp"
#include "model/identify/calibration_report.hpp"

namespace jointcomp {
namespace {

using calibration_test::identifiedOn;
using calibration_test::kNominalTarget;
using calibration_test::randomPoses;
using calibration_test::randomTruth;
using calibration_test::trackerFrame;
using calibration_test::ur10;
using calibration_test::ur10Model;

constexpr double kNoise = 20e-6;  // m per axis

GeometricParameters randomParameters(int setups, DeterministicRandom& random) {
  GeometricParameters p = GeometricParameters::zero(6);
  p.setInstrumentFromBase(trackerFrame(random));
  p.target = Eigen::Vector3d(0.01, -0.02, 0.09);
  p.instrument_scale = random.uniform(-1e-4, 1e-4);
  for (int j = 0; j < 6; ++j) {
    p.offset[j] = random.uniform(-0.01, 0.01);
    p.compliance[j] = random.uniform(1e-6, 1e-5);
    for (int k = 0; k < 6; ++k) p.placement[static_cast<std::size_t>(j)][k] = random.uniform(-0.05, 0.05);
  }
  for (int s = 1; s < setups; ++s) {
    GeometricParameters single = GeometricParameters::zero(6);
    single.setInstrumentFromBase(trackerFrame(random));
    single.instrument_scale = random.uniform(-1e-4, 1e-4);
    p.other_setups.emplace_back();
    p.setSetUp(s, single);
  }
  return p;
}

TEST(CalibrationSetUps, TheFlatVectorNamesAndLayoutHoldEverySetUp) {
  DeterministicRandom random(3);
  const GeometricParameters p = randomParameters(3, random);
  ASSERT_EQ(p.setUpCount(), 3);
  const GeometricParameterLayout layout(6, 3);
  const Eigen::VectorXd x = p.toVector();
  ASSERT_EQ(x.size(), layout.size());
  EXPECT_EQ(GeometricParameters::fromVector(x, 6, 3).toVector(), x);
  EXPECT_THROW(GeometricParameters::fromVector(x, 6, 2), InvalidArgument);
  // One set-up's view and back: the same vector.
  GeometricParameters rebuilt = GeometricParameters::fromVector(x, 6, 3);
  for (int s = 0; s < 3; ++s) {
    GeometricParameters single = p.ofSetUp(s);
    EXPECT_EQ(single.setUpCount(), 1);
    rebuilt.setSetUp(s, single);
  }
  EXPECT_EQ(rebuilt.toVector(), x);
  EXPECT_THROW(p.ofSetUp(3), InvalidArgument);
  // Every index is a robot parameter or the frame or scale of exactly one set-up.
  const std::vector<std::string> names = geometricParameterNames(*ur10(), 3);
  ASSERT_EQ(static_cast<int>(names.size()), layout.size());
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()).size(), names.size());
  int frames = 0, scales = 0;
  for (int i = 0; i < layout.size(); ++i) {
    const int s = layout.setUpOf(i);
    const std::string& name = names[static_cast<std::size_t>(i)];
    if (s < 0) {
      EXPECT_FALSE(layout.isFrame(i) || layout.isInstrumentScale(i)) << name;
      EXPECT_EQ(name.find("frame."), std::string::npos) << name;
      continue;
    }
    EXPECT_NE(layout.isFrame(i), layout.isInstrumentScale(i)) << name;
    frames += layout.isFrame(i) ? 1 : 0;
    scales += layout.isInstrumentScale(i) ? 1 : 0;
    EXPECT_EQ(name.rfind("setup", 0) == 0, s > 0) << name;
    if (s > 0) {
      EXPECT_EQ(name.rfind("setup" + std::to_string(s + 1) + ".", 0), 0u) << name;
    }
    EXPECT_EQ(geometricParameterUnit(name), layout.isInstrumentScale(i) ? "1" : (i - layout.frame(s) < 3 ? "m" : "rad"))
        << name;
  }
  EXPECT_EQ(frames, 18);
  EXPECT_EQ(scales, 3);
}

TEST(CalibrationSetUps, EachSetUpsJacobianAgreesWithFiniteDifferences) {
  const Robot& robot = *ur10();
  DeterministicRandom random(11);
  const GeometricParameters p = randomParameters(3, random);
  const GeometricParameterLayout layout(6, 3);
  const Eigen::VectorXd x = p.toVector();
  const std::vector<std::string> names = geometricParameterNames(robot, 3);
  for (int setup = 0; setup < 3; ++setup) {
    for (const JointVector& q : randomPoses(3, 40 + static_cast<std::uint64_t>(setup))) {
      JointVector torque(6), other(6);
      for (int j = 0; j < 6; ++j) {
        torque[j] = random.uniform(-150, 150);
        other[j] = random.uniform(-1e-3, 1e-3);
      }
      Eigen::MatrixXd analytic;
      predictMeasurement(robot, p, q, torque, other, &analytic, setup);
      ASSERT_EQ(analytic.cols(), layout.size());
      for (int i = 0; i < layout.size(); ++i) {
        const double h = i >= layout.compliance(0) && i < layout.instrumentScale() ? 1e-9 : 1e-6;
        Eigen::VectorXd plus = x, minus = x;
        plus[i] += h;
        minus[i] -= h;
        const Eigen::Vector3d numeric =
            (predictMeasurement(robot, GeometricParameters::fromVector(plus, 6, 3), q, torque, other, nullptr, setup) -
             predictMeasurement(robot, GeometricParameters::fromVector(minus, 6, 3), q, torque, other, nullptr,
                                setup)) /
            (2.0 * h);
        EXPECT_LE((analytic.col(i) - numeric).norm(), 1e-6 * std::max(1.0, numeric.norm()))
            << "set-up " << setup + 1 << ", " << names[static_cast<std::size_t>(i)];
        // Another set-up's frame and scale do not move this set-up's reading at all.
        const int owner = layout.setUpOf(i);
        if (owner >= 0 && owner != setup) {
          EXPECT_EQ(analytic.col(i).norm(), 0.0) << names[static_cast<std::size_t>(i)];
        }
      }
    }
  }
}

TEST(CalibrationSetUps, ASetUpsPredictionIsTheOneSetUpPredictionWithItsFrame) {
  const Robot& robot = *ur10();
  DeterministicRandom random(5);
  const GeometricParameters p = randomParameters(3, random);
  const JointVector torque = JointVector::Constant(6, 30.0), other = JointVector::Constant(6, 1e-4);
  for (const JointVector& q : randomPoses(4, 9)) {
    // In the base frame (no frame, no scale) every set-up sees the same point.
    GeometricParameters in_base = p.ofSetUp(0);
    in_base.setInstrumentFromBase(Eigen::Isometry3d::Identity());
    in_base.instrument_scale = 0.0;
    const Eigen::Vector3d base_point = predictMeasurement(robot, in_base, q, torque, other);
    for (int s = 0; s < 3; ++s) {
      const GeometricParameters single = p.ofSetUp(s);
      const Eigen::Vector3d reading = predictMeasurement(robot, p, q, torque, other, nullptr, s);
      EXPECT_EQ(reading, predictMeasurement(robot, single, q, torque, other));
      EXPECT_LT((reading - (1.0 + single.instrument_scale) * (single.instrumentFromBase() * base_point)).norm(), 1e-12);
    }
  }
  EXPECT_THROW(predictMeasurement(robot, p, randomPoses(1, 1)[0], torque, other, nullptr, 3), InvalidArgument);
}

struct TwoSetUps {
  GeometricParameters truth;  // two set-ups
  std::vector<MeasurementCampaign> campaigns;
};

// Campaign A (200 poses) from one tracker position, B (150 other poses) from another; the robot's
// identified parameters moved from nominal.
TwoSetUps simulateTwoSetUps(std::uint64_t seed) {
  const std::vector<JointVector> poses_a = randomPoses(200, 13), poses_b = randomPoses(150, 14);
  DeterministicRandom random(seed);
  TwoSetUps out;
  out.truth = randomTruth(identifiedOn(poses_a), random);
  GeometricParameters b = out.truth;
  b.setInstrumentFromBase(trackerFrame(random));
  out.campaigns.push_back(simulateGeometricCampaign(ur10Model(), out.truth, poses_a, kNoise, seed, kNominalTarget));
  out.campaigns.push_back(simulateGeometricCampaign(ur10Model(), b, poses_b, kNoise, seed + 1, kNominalTarget));
  out.campaigns[0].source = "A.csv";
  out.campaigns[1].source = "B.csv";
  out.truth.other_setups.emplace_back();
  out.truth.setSetUp(1, b);
  return out;
}

TEST(CalibrationSetUps, CampaignsOfOneSetUpShareAFrameAndOthersGetTheirOwn) {
  TwoSetUps two = simulateTwoSetUps(5);
  // A third campaign from A's set-up, other poses.
  MeasurementCampaign a2 =
      simulateGeometricCampaign(ur10Model(), two.truth.ofSetUp(0), randomPoses(80, 15), kNoise, 9, kNominalTarget);
  a2.source = "A2.csv";
  const InstrumentSetUps setups = instrumentSetUps(ur10Model(), {two.campaigns[0], two.campaigns[1], a2});
  EXPECT_EQ(setups.setup_of_campaign, (std::vector<int>{0, 1, 0}));
  EXPECT_EQ(setups.count(), 2);
  // The frame each is fitted on the prior is near its truth (the robot's few-mm errors apart).
  for (int c = 0; c < 3; ++c) {
    const Eigen::Isometry3d truth = two.truth.ofSetUp(c == 1 ? 1 : 0).instrumentFromBase();
    EXPECT_LT((setups.frame_of_campaign[static_cast<std::size_t>(c)].translation() - truth.translation()).norm(), 0.02);
  }
  // In the base frame there is one set-up; base and instrument together are named.
  MeasurementCampaign in_base = two.campaigns[1];
  in_base.frame = MeasurementFrame::Base;
  in_base.source = "base.csv";
  try {
    instrumentSetUps(ur10Model(), {two.campaigns[0], in_base});
    FAIL() << "campaigns in the base and the instrument frame were grouped";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("base.csv"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("A.csv"));
  }
}

TEST(CalibrationSetUps, OneCalibrationOnTwoSetUpsRecoversEachFrameAndTheRobot) {
  const TwoSetUps two = simulateTwoSetUps(21);
  const GeometricCalibrationResult joint = calibrateGeometry(ur10Model(), two.campaigns);
  EXPECT_EQ(joint.setup_of_campaign, (std::vector<int>{0, 1}));
  ASSERT_EQ(joint.estimate.setUpCount(), 2);
  EXPECT_EQ(joint.used_rows, 350);
  EXPECT_EQ(std::count(joint.campaign_of_row.begin(), joint.campaign_of_row.end(), 1), 150);
  EXPECT_EQ(joint.sources, (std::vector<std::string>{"A.csv", "B.csv"}));
  // Each set-up's frame is its own, and the fit leaves the noise.
  for (int s = 0; s < 2; ++s) {
    EXPECT_LT(
        (joint.estimate.ofSetUp(s).instrumentFromBase().matrix() - two.truth.ofSetUp(s).instrumentFromBase().matrix())
            .norm(),
        1e-4)
        << "set-up " << s + 1;
  }
  EXPECT_LT(joint.after.rms, 2.0 * std::sqrt(3.0) * kNoise);
  EXPECT_GT(joint.before.rms, 10.0 * joint.after.rms);
  // The robot's parameters come back within their uncertainty, and more data knows them better than A alone.
  const GeometricCalibrationResult alone = calibrateGeometry(ur10Model(), two.campaigns[0]);
  const Eigen::VectorXd truth = two.truth.toVector();
  int compared = 0, tighter = 0;
  for (std::size_t i = 9; i < alone.parameters.size(); ++i) {  // the robot's, not frame or target
    const ParameterEstimate& p = joint.parameters[i];
    ASSERT_EQ(p.name, alone.parameters[i].name);
    if (!p.identified) continue;
    EXPECT_LT(std::abs(p.value - truth[static_cast<Eigen::Index>(i)]), 5.0 * p.sigma) << p.name;
    if (!alone.parameters[i].identified) continue;
    ++compared;
    tighter += p.sigma < alone.parameters[i].sigma ? 1 : 0;
  }
  EXPECT_GE(compared, 15);
  EXPECT_GE(tighter, compared * 9 / 10);
  // Set-up 2's frame parameters are named and identified.
  for (const char* name : {"setup2.frame.tx_m", "setup2.frame.rz_rad"}) {
    const auto found = std::find_if(joint.parameters.begin(), joint.parameters.end(),
                                    [&](const ParameterEstimate& p) { return p.name == name; });
    ASSERT_NE(found, joint.parameters.end()) << name;
    EXPECT_TRUE(found->identified) << name;
  }
  // The same campaigns taken as one set-up cannot be fitted: B's points are metres from A's frame.
  bool one_frame_fails = false;
  try {
    const GeometricCalibrationResult one = calibrateGeometry(ur10Model(), concatenateCampaigns(two.campaigns));
    one_frame_fails = one.after.rms > 100.0 * joint.after.rms;
  } catch (const Error&) {
    one_frame_fails = true;
  }
  EXPECT_TRUE(one_frame_fails);
}

TEST(CalibrationSetUps, EachSetUpsScaleIsFittedWhenAsked) {
  TwoSetUps two = simulateTwoSetUps(33);
  // B's tracker reads 80 ppm long (another temperature): a relative scale the data can see.
  GeometricParameters b = two.truth.ofSetUp(1);
  b.instrument_scale = 8e-5;
  two.truth.setSetUp(1, b);
  two.campaigns[1] = simulateGeometricCampaign(ur10Model(), b, randomPoses(150, 14), kNoise, 34, kNominalTarget);
  GeometricCalibrationOptions options;
  options.fit_instrument_scale = true;
  const GeometricCalibrationResult result = calibrateGeometry(ur10Model(), two.campaigns, options);
  const double a_scale = result.estimate.instrument_scale, b_scale = result.estimate.ofSetUp(1).instrument_scale;
  // One scale is redundant with the robot's lengths; their ratio is what the data fix.
  EXPECT_NEAR((1.0 + b_scale) / (1.0 + a_scale) - 1.0, 8e-5, 1.5e-5);
  EXPECT_LT(result.after.rms, 2.0 * std::sqrt(3.0) * kNoise);
  // Without the scale, B's 80 ppm over its metres is left in the residual.
  const GeometricCalibrationResult without = calibrateGeometry(ur10Model(), two.campaigns);
  EXPECT_GT(without.after.rms, 1.2 * result.after.rms);
}

TEST(CalibrationSetUps, CampaignsThatCannotBeCalibratedTogetherAreNamed) {
  TwoSetUps two = simulateTwoSetUps(41);
  two.campaigns[1].target_in_flange = Eigen::Vector3d(0.0, 0.0, 0.2);
  try {
    calibrateGeometry(ur10Model(), two.campaigns);
    FAIL() << "two targets were calibrated as one";
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("B.csv"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("target"));
  }
  // A set-up of two rows cannot fix its frame.
  TwoSetUps few = simulateTwoSetUps(42);
  few.campaigns[1].command.resize(2);
  few.campaigns[1].position.resize(2);
  few.campaigns[1].time.resize(2);
  few.campaigns[1].temperature.resize(2);
  few.campaigns[1].wrench.resize(2);
  few.campaigns[1].payload.resize(2);
  EXPECT_THROW(calibrateGeometry(ur10Model(), few.campaigns), InvalidArgument);
  EXPECT_THROW(calibrateGeometry(ur10Model(), std::vector<MeasurementCampaign>{}), InvalidArgument);
  // Set-ups given by hand: one per campaign, numbered without gaps.
  const TwoSetUps fine = simulateTwoSetUps(43);
  EXPECT_THROW(prepareCalibrationData(ur10Model(), fine.campaigns, {0}), InvalidArgument);
  EXPECT_THROW(prepareCalibrationData(ur10Model(), fine.campaigns, {0, 2}), InvalidArgument);
  EXPECT_THROW(prepareCalibrationData(ur10Model(), fine.campaigns, {1, 1}), InvalidArgument);
  EXPECT_THROW(prepareCalibrationData(ur10Model(), fine.campaigns, {0, -1}), InvalidArgument);
  const CalibrationData rows = prepareCalibrationData(ur10Model(), fine.campaigns, {0, 1});
  EXPECT_EQ(rows.setups, 2);
  EXPECT_EQ(std::count(rows.campaign.begin(), rows.campaign.end(), 1), 150);
  EXPECT_EQ(rows.setup, rows.campaign);
}

TEST(CalibrationSetUps, TheReportsNameEachCampaignAndSetUp) {
  const TwoSetUps two = simulateTwoSetUps(51);
  const CalibrationRun run = runCalibration(ur10Model(), two.campaigns, {}, {});
  CalibrationSources sources;
  sources.campaign = "data/A.csv,data/B.csv";
  sources.campaigns = {"data/A.csv", "data/B.csv"};
  // Each row's residual is in its own set-up's frame: its length is the row's error after the fit.
  ASSERT_EQ(run.residual.size(), run.result.error_after.size());
  for (std::size_t k = 0; k < run.residual.size(); ++k) {
    EXPECT_NEAR(run.residual[k].error.norm(), run.result.error_after[k], 1e-9) << k;
  }
  const nlohmann::ordered_json report = calibrationReportJson(run, {}, sources);
  ASSERT_EQ(report["instrument_setups"].size(), 2u);
  EXPECT_EQ(report["instrument_setups"][1]["campaigns"][0], "data/B.csv");
  const Eigen::Vector3d b_frame = run.result.estimate.ofSetUp(1).frame_translation;
  EXPECT_DOUBLE_EQ(report["instrument_setups"][1]["frame_translation_m"][0].get<double>(), b_frame.x());
  EXPECT_EQ(report["rows"]["total"], 350);
  ASSERT_EQ(report["campaigns"].size(), 2u);
  double squares = 0.0;
  for (int c = 0; c < 2; ++c) {
    const auto& entry = report["campaigns"][static_cast<std::size_t>(c)];
    EXPECT_EQ(entry["setup"], c + 1);
    EXPECT_EQ(entry["role"], "calibration");
    const double rms = entry["after"]["rms_mm"].get<double>() * 1e-3;
    squares += rms * rms * entry["rows"].get<double>();
  }
  // The campaigns' RMS figures make up the whole one.
  EXPECT_NEAR(std::sqrt(squares / 350.0), run.result.after.rms, 1e-12);
  const std::string summary = calibrationSummary(run, sources);
  EXPECT_THAT(summary, ::testing::HasSubstr("2 campaigns from 2 instrument set-ups"));
  EXPECT_THAT(summary, ::testing::HasSubstr("set-up 2: B.csv"));
  EXPECT_THAT(summary, ::testing::HasSubstr("setup2.frame.tx_m"));
  const std::string csv = calibrationResidualsCsv(run, sources);
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 351);
  EXPECT_NE(csv.find("\nB.csv,calibration,149,"), std::string::npos);
}

TEST(CalibrationSetUps, TheReportedResidualsAreTheRowsTheFitSaw) {
  // With lost motion in the prior, a row's prediction depends on the moves before it: the second campaign's
  // first rows remember the first campaign's last move. The reported residual of every row is the fit's.
  JointErrorModel prior = ur10Model();
  prior.addEffect(std::make_unique<BacklashEffect>(prior.robot(), std::vector<double>(6, 2e-3)));
  const TwoSetUps two = simulateTwoSetUps(61);
  const CalibrationRun run = runCalibration(prior, two.campaigns, {}, {});
  ASSERT_EQ(run.residual.size(), run.result.error_after.size());
  for (std::size_t k = 0; k < run.residual.size(); ++k) {
    EXPECT_NEAR(run.residual[k].error.norm(), run.result.error_after[k], 1e-9) << k;
    EXPECT_EQ(run.residual[k].row, run.result.row[k]) << k;
  }
  // The campaign on its own forgets that move: its first row is predicted otherwise.
  const std::vector<RowResidual> alone = rowResiduals(prior, run.result.estimate.ofSetUp(1), two.campaigns[1]);
  EXPECT_GT((alone.front().error - run.residual[200].error).norm(), 1e-6);
}

}  // namespace
}  // namespace jointcomp
