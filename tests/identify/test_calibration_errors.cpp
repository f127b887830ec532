// The documented errors of the kinematic calibration: too few points, degenerate poses, rows without a
// measured position (skipped and counted, never a crash), campaigns and files it cannot use, and a solver
// that does not converge.
#include <cmath>
#include <fstream>
#include <limits>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "calibration_test_support.hpp"
#include "model/common/errors.hpp"

namespace jointcomp {
namespace {

using calibration_test::randomPoses;
using calibration_test::ur10;
using calibration_test::ur10Model;
using ::testing::HasSubstr;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const Eigen::Vector3d kTarget(0.0, 0.0, 0.1);

GeometricParameters someTruth() {
  GeometricParameters truth = GeometricParameters::zero(6);
  DeterministicRandom random(4);
  truth.setInstrumentFromBase(calibration_test::trackerFrame(random));
  truth.target = kTarget;
  truth.offset[1] = 1e-3;
  truth.compliance[1] = 8e-6;
  return truth;
}

MeasurementCampaign campaignOf(const std::vector<JointVector>& poses, std::uint64_t seed = 1) {
  return simulateGeometricCampaign(ur10Model(), someTruth(), poses, 20e-6, seed, kTarget);
}

template <typename Error>
std::string messageOf(const std::function<void()>& call) {
  try {
    call();
  } catch (const Error& error) {
    return error.what();
  }
  ADD_FAILURE() << "no exception of the expected type";
  return "";
}

TEST(CalibrationErrors, TooFewRows) {
  const MeasurementCampaign five = campaignOf(randomPoses(5, 1));
  const std::string message = messageOf<InvalidArgument>([&] { calibrateGeometry(ur10Model(), five); });
  EXPECT_THAT(message, HasSubstr("too few points"));
  EXPECT_THAT(message, HasSubstr("5 usable rows"));
  EXPECT_THAT(message, HasSubstr("simulated campaign"));
}

TEST(CalibrationErrors, TooFewResidualsForTheIdentifiableParameters) {
  // 14 rows pass the row minimum, but 42 residuals cannot determine 20 and more parameters honestly.
  const MeasurementCampaign fourteen = campaignOf(randomPoses(14, 2));
  const std::string message = messageOf<InvalidArgument>([&] { calibrateGeometry(ur10Model(), fourteen); });
  EXPECT_THAT(message, HasSubstr("too few points"));
  EXPECT_THAT(message, HasSubstr("identifiable parameters"));
}

TEST(CalibrationErrors, AllRowsAtTheSamePoseAreDegenerate) {
  const std::vector<JointVector> same(60, randomPoses(1, 3).front());
  const std::string message = messageOf<InvalidArgument>([&] { calibrateGeometry(ur10Model(), campaignOf(same)); });
  EXPECT_THAT(message, HasSubstr("degenerate poses"));
  EXPECT_THAT(message, HasSubstr("same joint positions"));
}

TEST(CalibrationErrors, PosesThatOnlyTurnTheLastJointAreDegenerate) {
  // The target sits on the axis of joint 6: every row sees the same point, the frame cannot be fixed.
  std::vector<JointVector> poses = std::vector<JointVector>(40, randomPoses(1, 4).front());
  for (std::size_t k = 0; k < poses.size(); ++k) poses[k][5] = -3.0 + 0.15 * static_cast<double>(k);
  const std::string message = messageOf<InvalidArgument>([&] { calibrateGeometry(ur10Model(), campaignOf(poses)); });
  EXPECT_THAT(message, HasSubstr("degenerate poses"));
}

TEST(CalibrationErrors, PosesTurningOnlyJointOneIdentifyTheFrameAndLittleElse) {
  // The points lie on one circle: enough for the instrument frame, not for the arm's geometry. The fit runs
  // on what is identifiable and says for everything else why it was held.
  std::vector<JointVector> poses(60, randomPoses(1, 5).front());
  for (std::size_t k = 0; k < poses.size(); ++k) poses[k][0] = -3.0 + 0.1 * static_cast<double>(k);
  const GeometricCalibrationResult result = calibrateGeometry(ur10Model(), campaignOf(poses));
  EXPECT_LT(result.free.size(), 12u);
  for (int i = 0; i < 6; ++i) EXPECT_TRUE(result.parameters[static_cast<std::size_t>(i)].identified);
  for (const ParameterEstimate& p : result.parameters) {
    if (!p.identified) {
      EXPECT_FALSE(p.fixed_because.empty()) << p.name;
    }
  }
}

TEST(CalibrationErrors, RowsWithoutAMeasuredPositionAreSkippedAndCounted) {
  MeasurementCampaign campaign = campaignOf(randomPoses(150, 6));
  for (int k : {0, 3, 50, 51, 52, 99, 149})
    campaign.position[static_cast<std::size_t>(k)] = Eigen::Vector3d::Constant(kNaN);
  campaign.position[10].y() = kNaN;  // in part (a reader would refuse it; the calibration skips it)
  campaign.command[20][2] = kNaN;    // a command that is not finite: skipped too
  const GeometricCalibrationResult result = calibrateGeometry(ur10Model(), campaign);
  EXPECT_EQ(result.skipped_rows, 9);
  EXPECT_EQ(result.used_rows, 141);
  EXPECT_EQ(result.row.size(), 141u);
  EXPECT_EQ(std::count(result.row.begin(), result.row.end(), 50), 0);
  EXPECT_LT(result.after.rms, 1e-4);
  for (const ParameterEstimate& p : result.parameters) EXPECT_TRUE(std::isfinite(p.value)) << p.name;
}

TEST(CalibrationErrors, EmptyCellsInACampaignFileAreSkippedAndCounted) {
  MeasurementCampaign campaign = campaignOf(randomPoses(80, 7));
  for (int k : {5, 6, 70}) campaign.position[static_cast<std::size_t>(k)] = Eigen::Vector3d::Constant(kNaN);
  const std::string path = ::testing::TempDir() + "/campaign_with_gaps.csv";
  writeCampaignFile(campaign, path);
  const MeasurementCampaign read = readCampaignFile(path);
  const GeometricCalibrationResult result = calibrateGeometry(ur10Model(), read);
  EXPECT_EQ(result.skipped_rows, 3);
  EXPECT_EQ(result.used_rows, 77);
}

TEST(CalibrationErrors, CampaignsTheCalibrationCannotUse) {
  // Joint angles only, no positions.
  const std::string angles_only =
      "# format: jointcomp-measurements/1\n"
      "t,q1,q2,q3,q4,q5,q6,qm1,qm2,qm3,qm4,qm5,qm6\n"
      "0,0,-90,0,-90,0,0,0,-90,0,-90,0,0\n";
  const MeasurementCampaign angles = parseCampaign(angles_only, "angles.csv");
  std::string message = messageOf<MeasurementError>([&] { calibrateGeometry(ur10Model(), angles); });
  EXPECT_THAT(message, HasSubstr("angles.csv"));
  EXPECT_THAT(message, HasSubstr("no measured positions"));
  // Another robot: three joints.
  const std::string three =
      "# format: jointcomp-measurements/1\n"
      "t,q1,q2,q3,x,y,z\n"
      "0,0,-90,0,100,200,300\n";
  message = messageOf<MeasurementError>([&] { calibrateGeometry(ur10Model(), parseCampaign(three, "three.csv")); });
  EXPECT_THAT(message, HasSubstr("three.csv"));
  EXPECT_THAT(message, HasSubstr("3 joint columns"));
  // Malformed files are the reader's errors, with file, line and column.
  const std::string malformed =
      "# format: jointcomp-measurements/1\n"
      "t,q1,q2,q3,q4,q5,q6,x,y,z\n"
      "0,0,-90,0,-90,0,0,100,abc,300\n";
  message = messageOf<MeasurementError>([&] { parseCampaign(malformed, "malformed.csv"); });
  EXPECT_THAT(message, HasSubstr("malformed.csv:3"));
  EXPECT_THAT(message, HasSubstr("'y'"));
  EXPECT_THROW(readCampaignFile(::testing::TempDir() + "/does_not_exist.csv"), MeasurementError);
  // A parameter named to be fixed that does not exist.
  GeometricCalibrationOptions options;
  options.fixed = {"joint_9.offset_rad"};
  message =
      messageOf<InvalidArgument>([&] { calibrateGeometry(ur10Model(), campaignOf(randomPoses(60, 8)), options); });
  EXPECT_THAT(message, HasSubstr("joint_9.offset_rad"));
}

TEST(CalibrationErrors, NonConvergenceIsASolverError) {
  GeometricCalibrationOptions options;
  options.solver.max_iterations = 1;
  const std::string message =
      messageOf<SolverError>([&] { calibrateGeometry(ur10Model(), campaignOf(randomPoses(100, 9)), options); });
  EXPECT_THAT(message, HasSubstr("did not converge"));
}

TEST(CalibrationErrors, FixedByRequestStaysNominal) {
  GeometricCalibrationOptions options;
  options.fixed = {"joint_2.offset_rad", "target.z_m"};
  const GeometricCalibrationResult result = calibrateGeometry(ur10Model(), campaignOf(randomPoses(100, 10)), options);
  for (const ParameterEstimate& p : result.parameters) {
    if (p.name == "joint_2.offset_rad" || p.name == "target.z_m") {
      EXPECT_FALSE(p.identified);
      EXPECT_EQ(p.value, p.nominal);
      EXPECT_EQ(p.fixed_because, "fixed by request");
    }
  }
}

}  // namespace
}  // namespace jointcomp
