// The kinematic calibration (model/identify/geometric_calibration.hpp) on simulated UR10 campaigns with
// known true parameters and tracker noise: the analytic Jacobian agrees with finite differences, the true
// parameters come back within the reported uncertainty and the reported 1-sigma intervals hold the truth
// at about the stated rate, the redundancy of the frame rotation about z and the joint-1 offset is found,
// and what the calibration writes (URDF, parameter file) reproduces its predictions.
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "calibration_test_support.hpp"
#include "model/common/errors.hpp"
#include "model/effects/compliance.hpp"
#include "model/effects/joint_offset.hpp"
#include "model/identify/calibration_report.hpp"
#include "model/io/parameter_file.hpp"
#include "model/io/urdf_writer.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {
namespace {

using calibration_test::randomPoses;
using calibration_test::trackerFrame;
using calibration_test::ur10;
using calibration_test::ur10Model;

using calibration_test::identifiedOn;
using calibration_test::kNominalTarget;
using calibration_test::randomTruth;

constexpr double kNoise = 20e-6;  // m per axis, a laser tracker at a few metres

const ParameterEstimate& find(const GeometricCalibrationResult& result, const std::string& name) {
  for (const ParameterEstimate& p : result.parameters) {
    if (p.name == name) return p;
  }
  throw std::runtime_error("no parameter " + name);
}

TEST(GeometricCalibration, AnalyticJacobianAgreesWithFiniteDifferences) {
  const Robot& robot = *ur10();
  DeterministicRandom random(17);
  GeometricParameters p = GeometricParameters::zero(6);
  p.setInstrumentFromBase(trackerFrame(random));
  p.target = Eigen::Vector3d(0.01, -0.02, 0.09);
  for (int j = 0; j < 6; ++j) {
    p.offset[j] = random.uniform(-0.01, 0.01);
    p.compliance[j] = random.uniform(1e-6, 1e-5);
    for (int k = 0; k < 6; ++k) p.placement[static_cast<std::size_t>(j)][k] = random.uniform(-0.05, 0.05);
  }
  const GeometricParameterLayout layout(6);
  for (const JointVector& q : randomPoses(5, 2)) {
    JointVector torque(6), other(6);
    for (int j = 0; j < 6; ++j) {
      torque[j] = random.uniform(-150, 150);
      other[j] = random.uniform(-1e-3, 1e-3);
    }
    Eigen::MatrixXd analytic;
    predictMeasurement(robot, p, q, torque, other, &analytic);
    const Eigen::VectorXd x = p.toVector();
    for (int i = 0; i < layout.size(); ++i) {
      const double h = i >= layout.compliance(0) ? 1e-9 : 1e-6;
      Eigen::VectorXd plus = x, minus = x;
      plus[i] += h;
      minus[i] -= h;
      const Eigen::Vector3d numeric =
          (predictMeasurement(robot, GeometricParameters::fromVector(plus, 6), q, torque, other) -
           predictMeasurement(robot, GeometricParameters::fromVector(minus, 6), q, torque, other)) /
          (2.0 * h);
      const double scale = std::max(1.0, numeric.norm());
      EXPECT_LE((analytic.col(i) - numeric).norm(), 1e-6 * scale)
          << geometricParameterNames(robot)[static_cast<std::size_t>(i)];
    }
  }
}

TEST(GeometricCalibration, ZeroCorrectionsPredictTheRobotsForwardKinematics) {
  const Robot& robot = *ur10();
  RobotWorkspace ws(robot);
  GeometricParameters p = GeometricParameters::zero(6);
  p.target = kNominalTarget;
  for (const JointVector& q : randomPoses(10, 4)) {
    forwardKinematics(robot, ws, q);
    const Eigen::Vector3d expected = ws.tool_pose * kNominalTarget;
    const Eigen::Vector3d predicted = predictMeasurement(robot, p, q, JointVector::Zero(6), JointVector::Zero(6));
    EXPECT_LE((predicted - expected).norm(), 1e-14);
  }
  // And the corrected robot carries the placement corrections.
  p.placement[2] << 1e-3, -2e-3, 0.5e-3, 1e-3, 2e-3, -1e-3;
  const Robot corrected = correctedRobot(robot, p);
  RobotWorkspace corrected_ws(corrected);
  for (const JointVector& q : randomPoses(10, 5)) {
    forwardKinematics(corrected, corrected_ws, q);
    const Eigen::Vector3d predicted = predictMeasurement(robot, p, q, JointVector::Zero(6), JointVector::Zero(6));
    EXPECT_LE((predicted - corrected_ws.tool_pose * kNominalTarget).norm(), 1e-14);
  }
}

// The parameters a noise-free campaign on these poses identifies.
TEST(GeometricCalibration, RecoversTheTruthWithHonestUncertaintyOverSeeds) {
  const std::vector<JointVector> poses = randomPoses(250, 7);
  const std::vector<std::string> identified = identifiedOn(poses);
  ASSERT_GE(identified.size(), 25u);
  const std::vector<std::string> names = geometricParameterNames(*ur10());
  int samples = 0, inside_one = 0, inside_three = 0;
  double worst = 0.0;
  std::string worst_name;
  const int seeds = 24;
  for (int seed = 0; seed < seeds; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    DeterministicRandom random(100 + static_cast<std::uint64_t>(seed));
    const GeometricParameters truth = randomTruth(identified, random);
    const MeasurementCampaign campaign = simulateGeometricCampaign(
        ur10Model(), truth, poses, kNoise, 500 + static_cast<std::uint64_t>(seed), kNominalTarget);
    const GeometricCalibrationResult result = calibrateGeometry(ur10Model(), campaign);
    std::vector<std::string> now;
    for (const ParameterEstimate& p : result.parameters) {
      if (p.identified) now.push_back(p.name);
    }
    ASSERT_EQ(now, identified);
    // The residual sigma is the noise (750 residuals: 2.6 % standard deviation), and the fit leaves the
    // noise: RMS 3-D error sqrt(3) sigma less the degrees of freedom the parameters take.
    EXPECT_NEAR(result.residual_sigma, kNoise, 0.1 * kNoise);
    const double expected_rms = std::sqrt(3.0 * kNoise * kNoise * (1.0 - identified.size() / (3.0 * poses.size())));
    EXPECT_NEAR(result.after.rms, expected_rms, 0.12 * expected_rms);
    const Eigen::VectorXd x = truth.toVector();
    for (std::size_t i = 0; i < names.size(); ++i) {
      const ParameterEstimate& p = result.parameters[i];
      if (!p.identified) {
        EXPECT_EQ(p.value, p.nominal) << p.name;
        continue;
      }
      ASSERT_GT(p.sigma, 0.0) << p.name;
      const double z = std::abs(p.value - x[static_cast<Eigen::Index>(i)]) / p.sigma;
      ++samples;
      inside_one += z <= 1.0 ? 1 : 0;
      inside_three += z <= 3.0 ? 1 : 0;
      if (z > worst) worst = z, worst_name = p.name + " (seed " + std::to_string(seed) + ")";
    }
  }
  const double coverage = static_cast<double>(inside_one) / samples;
  const double coverage3 = static_cast<double>(inside_three) / samples;
  std::printf(
      "[ calibration ] %d estimates over %d seeds: %.1f %% within 1 sigma, %.1f %% within 3 sigma, worst "
      "%.2f sigma (%s)\n",
      samples, seeds, 100 * coverage, 100 * coverage3, worst, worst_name.c_str());
  EXPECT_GE(coverage, 0.50);
  EXPECT_LE(coverage, 0.85);
  EXPECT_GE(coverage3, 0.97);
  EXPECT_LT(worst, 5.0) << worst_name;
}

TEST(GeometricCalibration, FindsTheFrameRotationAboutZRedundantWithTheJointOneOffset) {
  const std::vector<JointVector> poses = randomPoses(120, 8);
  GeometricParameters truth = GeometricParameters::zero(6);
  Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();
  frame.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  frame.translation() = Eigen::Vector3d(2.0, 0.5, -0.3);
  truth.setInstrumentFromBase(frame);
  truth.target = kNominalTarget;
  truth.offset[0] = 2e-3;  // seen by the data as a frame rotation
  const MeasurementCampaign campaign = simulateGeometricCampaign(ur10Model(), truth, poses, kNoise, 3, kNominalTarget);
  const GeometricCalibrationResult result = calibrateGeometry(ur10Model(), campaign);
  const ParameterEstimate& offset = find(result, "joint_1.offset_rad");
  EXPECT_FALSE(offset.identified);
  EXPECT_THAT(offset.fixed_because, ::testing::HasSubstr("redundant"));
  ASSERT_FALSE(offset.redundant_with.empty());
  EXPECT_EQ(offset.redundant_with[0].first, "frame.rz_rad");
  EXPECT_NEAR(offset.redundant_with[0].second, 1.0, 1e-9);
  EXPECT_TRUE(find(result, "frame.rz_rad").identified);
  // The frame takes the offset over: rotation about z = 0.7 + 2e-3.
  EXPECT_NEAR(find(result, "frame.rz_rad").value, 0.702, 5 * find(result, "frame.rz_rad").sigma);
  EXPECT_LT(result.after.rms, 2.0 * kNoise);

  // Measured in the base frame (no frame to fit), the joint-1 offset is identifiable.
  GeometricParameters in_base = truth;
  in_base.setInstrumentFromBase(Eigen::Isometry3d::Identity());
  MeasurementCampaign base = simulateGeometricCampaign(ur10Model(), in_base, poses, kNoise, 4, kNominalTarget);
  base.frame = MeasurementFrame::Base;
  const GeometricCalibrationResult base_result = calibrateGeometry(ur10Model(), base);
  const ParameterEstimate& base_offset = find(base_result, "joint_1.offset_rad");
  EXPECT_TRUE(base_offset.identified);
  EXPECT_NEAR(base_offset.value, 2e-3, 4 * base_offset.sigma);
  EXPECT_FALSE(find(base_result, "frame.rz_rad").identified);
}

TEST(GeometricCalibration, CalibratedUrdfAndParameterFileReproduceThePredictions) {
  // A prior with a compliance effect for every joint: the joints whose compliance the data cannot see keep
  // the prior's, and the compliance effect is written.
  auto robot = ur10();
  std::vector<std::unique_ptr<Effect>> effects;
  effects.push_back(std::make_unique<ComplianceEffect>(*robot, std::vector<double>{2e5, 1e5, 1e5, 5e4, 5e4, 5e4}));
  const JointErrorModel prior(robot, GearTrain::direct(6), std::move(effects));
  const std::vector<JointVector> poses = randomPoses(200, 9);
  DeterministicRandom random(21);
  GeometricParameters truth = nominalParameters(prior, MeasurementCampaign());
  truth.setInstrumentFromBase(trackerFrame(random));
  truth.target = kNominalTarget + Eigen::Vector3d(1e-3, -0.5e-3, -16e-3);
  truth.offset << 0, 1e-3, -1e-3, 0.5e-3, -0.5e-3, 0;
  truth.placement[2] << 0.4e-3, 0, 0, 0.5e-3, -0.3e-3, 0;
  truth.compliance[1] = 8e-6;
  truth.compliance[2] = 9e-6;
  const MeasurementCampaign campaign = simulateGeometricCampaign(prior, truth, poses, kNoise, 6, kNominalTarget);
  const GeometricCalibrationResult result = calibrateGeometry(prior, campaign);
  EXPECT_TRUE(result.compliance_left_out.empty());

  // Write and read back.
  const std::string directory = ::testing::TempDir();
  const auto calibrated_robot = std::make_shared<const Robot>(correctedRobot(*robot, result.estimate));
  saveRobotUrdf(*calibrated_robot, directory + "/calibrated.urdf");
  std::vector<std::string> left_out;
  saveParameterFile(calibratedJointErrorModel(prior, calibrated_robot, result, left_out),
                    directory + "/calibrated.json");
  EXPECT_TRUE(left_out.empty());
  auto loaded_robot = std::make_shared<const Robot>(loadRobotFromUrdfFile(directory + "/calibrated.urdf"));
  const JointErrorModel loaded = loadParameterFile(directory + "/calibrated.json", loaded_robot);
  ASSERT_GE(loaded.findEffect(JointOffsetEffect::kType), 0);
  ASSERT_GE(loaded.findEffect(ComplianceEffect::kType), 0);

  // The quasi-static robot of the written files sees the target where the calibration predicts it.
  JointErrorWorkspace ws(*loaded_robot);
  const Eigen::Isometry3d frame = result.estimate.instrumentFromBase();
  double worst = 0.0;
  for (const JointVector& q : randomPoses(50, 10)) {
    JointContext ctx(6);
    ctx.command = q;
    settleStatically(loaded, loaded.allEffects(), ws, ctx);
    forwardKinematics(*loaded_robot, ws.robot, ctx.q);
    const Eigen::Vector3d from_files = frame * (ws.robot.tool_pose * result.estimate.target);
    const CalibrationData data = [&] {
      MeasurementCampaign one = simulateGeometricCampaign(prior, truth, {q}, 0.0, 1, kNominalTarget);
      return prepareCalibrationData(prior, one);
    }();
    const Eigen::Vector3d predicted =
        predictMeasurement(*robot, result.estimate, q, data.load_torque[0], data.other_error[0]);
    worst = std::max(worst, (from_files - predicted).norm());
  }
  // The calibration takes the load torque at the commanded pose, the quasi-static robot at the settled
  // one: a few micrometres apart at most.
  EXPECT_LT(worst, 5e-6);
}

TEST(GeometricCalibration, ComplianceFittedNotPositiveIsHeldAndLeftOut) {
  // Truth with joint-4 compliance negative (not physical): the fit holds it at nominal (0), says so, and the
  // compliance effect is not written.
  const std::vector<JointVector> poses = randomPoses(200, 12);
  GeometricParameters truth = GeometricParameters::zero(6);
  DeterministicRandom random(2);
  truth.setInstrumentFromBase(trackerFrame(random));
  truth.target = kNominalTarget;
  truth.compliance[1] = 8e-6;
  truth.compliance[2] = 8e-6;
  truth.compliance[3] = -2e-4;
  const MeasurementCampaign campaign = simulateGeometricCampaign(ur10Model(), truth, poses, kNoise, 8, kNominalTarget);
  const GeometricCalibrationResult result = calibrateGeometry(ur10Model(), campaign);
  const ParameterEstimate& c4 = find(result, "joint_4.compliance_rad_per_nm");
  EXPECT_FALSE(c4.identified);
  EXPECT_EQ(c4.value, 0.0);
  EXPECT_THAT(c4.fixed_because, ::testing::HasSubstr("not positive"));
  EXPECT_TRUE(find(result, "joint_2.compliance_rad_per_nm").identified);
  std::vector<std::string> left_out;
  const JointErrorModel model = calibratedJointErrorModel(
      ur10Model(), std::make_shared<const Robot>(correctedRobot(*ur10(), result.estimate)), result, left_out);
  // The fitted joints keep their compliance; joint 4 is written as rigid (infinite stiffness).
  const int compliance_index = model.findEffect(ComplianceEffect::kType);
  ASSERT_GE(compliance_index, 0);
  const auto& compliance = dynamic_cast<const ComplianceEffect&>(model.effect(compliance_index));
  EXPECT_TRUE(std::isinf(compliance.stiffness(3)));
  EXPECT_NEAR(1.0 / compliance.stiffness(1), find(result, "joint_2.compliance_rad_per_nm").value, 1e-18);
  EXPECT_GE(model.findEffect(JointOffsetEffect::kType), 0);
  bool names_joint_4 = false;
  for (const std::string& item : left_out) names_joint_4 = names_joint_4 || item.rfind("joint_4:", 0) == 0;
  EXPECT_TRUE(names_joint_4);
  // The summary says what the written file holds: a compliance effect, joint 4 rigid in it.
  const CalibrationRun run = runCalibration(ur10Model(), campaign, {}, {});
  const std::string summary = calibrationSummary(run, {});
  EXPECT_THAT(summary, ::testing::HasSubstr("these joints are written as rigid"));
  EXPECT_THAT(summary, ::testing::HasSubstr("  joint_4: "));
  EXPECT_THAT(summary, ::testing::Not(::testing::HasSubstr("NOT written")));
  EXPECT_GE(run.calibrated.findEffect(ComplianceEffect::kType), 0);
}

TEST(GeometricCalibration, TheSummarySaysHowMuchOfWhatIsLeftIsAFunctionOfThePose) {
  // 60 poses, each visited in four rounds 10 minutes apart (a few mrad off each time): the nearest poses measured
  // at other times are the same poses. Left alone, the calibration leaves the tracker's noise; with a smooth field
  // added that no kinematic parameter can take, what it leaves is mostly a function of the pose.
  const std::vector<JointVector> base = randomPoses(60, 21);
  std::vector<JointVector> poses;
  DeterministicRandom random(22);
  for (int round = 0; round < 4; ++round) {
    for (const JointVector& q : base) {
      JointVector visit = q;
      for (int j = 0; j < visit.size(); ++j) visit[j] += 0.003 * random.uniform(-1.0, 1.0);
      poses.push_back(visit);
    }
  }
  GeometricParameters truth = randomTruth(identifiedOn(poses), random);
  MeasurementCampaign campaign = simulateGeometricCampaign(ur10Model(), truth, poses, kNoise, 23, kNominalTarget);
  for (std::size_t k = 0; k < campaign.size(); ++k) campaign.time[k] = 10.0 * static_cast<double>(k);  // 600 s a round
  const CalibrationRun noise_only = runCalibration(ur10Model(), campaign, {}, {});
  ASSERT_TRUE(noise_only.pose.computed);
  EXPECT_LT(noise_only.pose.smooth_share, 0.2);
  EXPECT_LT(noise_only.pose.median_distance_other_times, 0.02);
  for (std::size_t k = 0; k < campaign.size(); ++k) {
    const JointVector& q = campaign.command[k];
    campaign.position[k] +=
        2e-4 * Eigen::Vector3d(std::sin(3.0 * q[0] + 2.0 * q[1]), std::cos(4.0 * q[2] - q[3]), std::sin(5.0 * q[4]));
  }
  const CalibrationRun with_field = runCalibration(ur10Model(), campaign, {}, {});
  ASSERT_TRUE(with_field.pose.computed);
  EXPECT_GT(with_field.pose.smooth_share, 0.8);
  const std::string summary = calibrationSummary(with_field, {});
  EXPECT_THAT(summary, ::testing::HasSubstr("What the calibration leaves. As a function of the pose"));
  EXPECT_THAT(summary, ::testing::HasSubstr("of its variance is a function of the pose"));
  const nlohmann::ordered_json report = calibrationReportJson(with_field, {}, {});
  EXPECT_NEAR(report["pose_predictability"]["smooth_share"].get<double>(), with_field.pose.smooth_share, 1e-15);
}

TEST(GeometricCalibration, HeldOutCampaignRefitsOnlyItsFrame) {
  const std::vector<JointVector> poses = randomPoses(200, 13);
  DeterministicRandom random(5);
  GeometricParameters truth = randomTruth(identifiedOn(poses), random);
  const MeasurementCampaign a = simulateGeometricCampaign(ur10Model(), truth, poses, kNoise, 1, kNominalTarget);
  const GeometricCalibrationResult result = calibrateGeometry(ur10Model(), a);
  // Series "B": other poses, another tracker set-up.
  GeometricParameters truth_b = truth;
  truth_b.setInstrumentFromBase(trackerFrame(random));
  const MeasurementCampaign b =
      simulateGeometricCampaign(ur10Model(), truth_b, randomPoses(150, 14), kNoise, 2, kNominalTarget);
  const HoldoutEvaluation after = evaluateOnCampaign(ur10Model(), result.estimate, b, true);
  const HoldoutEvaluation before = evaluateOnCampaign(ur10Model(), nominalParameters(ur10Model(), b), b, true);
  const HoldoutEvaluation shared = evaluateOnCampaign(ur10Model(), result.estimate, b, false);
  EXPECT_LT(after.statistics.rms, 2.0 * std::sqrt(3.0) * kNoise);
  EXPECT_GT(before.statistics.rms, 10.0 * after.statistics.rms);
  EXPECT_GT(shared.statistics.rms, 0.1);  // the frame of A is not B's
  EXPECT_LT((after.parameters.instrumentFromBase().matrix() - truth_b.instrumentFromBase().matrix()).norm(), 1e-4);
  // Everything but the frame is what the calibration found.
  EXPECT_EQ(after.parameters.toVector().tail(57 - 6), result.estimate.toVector().tail(57 - 6));
}

TEST(GeometricCalibration, RowResidualsAreTheErrorAndJointErrorsThatExplainIt) {
  const std::vector<JointVector> poses = randomPoses(60, 21);
  DeterministicRandom random(8);
  GeometricParameters truth = nominalParameters(ur10Model(), MeasurementCampaign{});
  truth.setInstrumentFromBase(trackerFrame(random));
  truth.target = kNominalTarget;
  GeometricParameters model = truth;
  truth.offset[2] = 2e-4;  // a joint-3 error the model does not have
  const MeasurementCampaign campaign = simulateGeometricCampaign(ur10Model(), truth, poses, 0.0, 1, kNominalTarget);
  const std::vector<RowResidual> residuals = rowResiduals(ur10Model(), model, campaign);
  const HoldoutEvaluation evaluation = evaluateOnCampaign(ur10Model(), model, campaign, false);
  ASSERT_EQ(residuals.size(), evaluation.error.size());
  for (std::size_t k = 0; k < residuals.size(); ++k) {
    const RowResidual& r = residuals[k];
    EXPECT_EQ(r.row, evaluation.row[k]);
    EXPECT_NEAR(r.error.norm(), evaluation.error[k], 1e-12);
    EXPECT_GT(r.error.norm(), 1e-5);
    // The mapped joint errors explain the residual: moving the commands by them removes it to first order
    // (the error is 2e-4 rad, so what is left is of order 1e-8 m).
    const JointVector moved = campaign.command[static_cast<std::size_t>(r.row)] + r.joint_error;
    const Eigen::Vector3d predicted =
        predictMeasurement(*ur10(), model, moved, JointVector::Zero(6), JointVector::Zero(6));
    EXPECT_LT((campaign.position[static_cast<std::size_t>(r.row)] - predicted).norm(), 0.01 * r.error.norm());
    // ... and they are the smallest such (no larger than the true joint-3 error that also explains it).
    EXPECT_LE(r.joint_error.norm(), 2e-4 * (1.0 + 1e-3));
  }
}

}  // namespace
}  // namespace jointcomp

namespace jointcomp {
namespace {

// A campaign carries the robot it was measured on, as a parameter file does (issue 41: calibrate --urdf
// ur10.urdf on a campaign of "# robot: rx170" "calibrated" the UR10 to 0.285 mm and said nothing).
TEST(GeometricCalibration, ACampaignOfAnotherRobotIsRefusedNamingBoth) {
  GeometricParameters truth = GeometricParameters::zero(6);
  truth.target = kNominalTarget;
  MeasurementCampaign campaign =
      simulateGeometricCampaign(ur10Model(), truth, randomPoses(40, 5), kNoise, 5, kNominalTarget);
  EXPECT_NO_THROW(calibrateGeometry(ur10Model(), campaign));
  campaign.robot = "rx170";
  campaign.source = "rx170_campaign.csv";
  try {
    calibrateGeometry(ur10Model(), campaign);
    ADD_FAILURE() << "a campaign of another robot was calibrated";
  } catch (const MeasurementError& error) {
    EXPECT_THAT(error.what(), ::testing::HasSubstr("rx170_campaign.csv: the campaign is of robot 'rx170', the "
                                                   "model of 'ur10'"));
  }
  // Two campaigns used together: of one robot (here, neither is of the model's).
  MeasurementCampaign other = campaign;
  other.robot = "ur10";
  other.source = "ur10_campaign.csv";
  EXPECT_THROW(calibrateGeometry(ur10Model(), std::vector<MeasurementCampaign>{other, campaign}), InvalidArgument);
}

}  // namespace
}  // namespace jointcomp
