// Stiffness identification: simulated campaigns with known true stiffness and stated noise, identified
// by the local (axis-by-axis, joint 3 by two levels) and the global method; the estimates recover the
// truth within the uncertainty the noise implies, the reported 95 % intervals cover the truth at about
// that rate over seeds, the updated parameter file holds them, and campaigns that cannot give stiffness
// (too few points, degenerate poses, no loads, a target on the axis, another frame or robot, NaN) give
// the documented errors.
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/effects/perturbation.hpp"
#include "model/experiment/campaign_simulation.hpp"
#include "model/identify/identification_report.hpp"
#include "model/identify/identification_statistics.hpp"
#include "model/identify/stiffness_identification.hpp"
#include "tests/identify/identify_test_support.hpp"

namespace jointcomp {
namespace {

using namespace identify_test;
using ::testing::HasSubstr;

// ---- the statistics underneath -----------------------------------------------------------------------

TEST(IdentificationStatistics, StudentTQuantilesMatchTables) {
  EXPECT_NEAR(studentTQuantile(0.975, 1), 12.706204736, 1e-7);
  EXPECT_NEAR(studentTQuantile(0.975, 10), 2.228138852, 1e-8);
  EXPECT_NEAR(studentTQuantile(0.975, 20), 2.085963447, 1e-8);
  EXPECT_NEAR(studentTQuantile(0.995, 5), 4.032142984, 1e-8);
  EXPECT_NEAR(studentTQuantile(0.025, 10), -2.228138852, 1e-8);
  EXPECT_NEAR(normalQuantile(0.975), 1.959963985, 1e-9);
  EXPECT_NEAR(fTail2(3.0, 10.0), std::pow(1.6, -5.0), 1e-15);  // P(F(2, 10) > 3)
  EXPECT_NEAR(fTail2(3.0, 10.0), 1.0 - incompleteBeta(6.0 / 16.0, 1.0, 5.0), 1e-12);
  EXPECT_NEAR(incompleteBeta(0.3, 2.0, 3.0), 0.3483, 1e-12);
}

TEST(IdentificationStatistics, WeightedLeastSquaresAndRank) {
  // y = 2 + 3 x exactly at three points: the fit is exact, the rank full.
  Eigen::MatrixXd a(3, 2);
  a << 1, 0, 1, 1, 1, 2;
  const Eigen::Vector3d y(2, 5, 8);
  const LinearFit fit = weightedLeastSquares(a, y, Eigen::Vector3d::Ones());
  ASSERT_EQ(fit.rank, 2);
  EXPECT_NEAR(fit.coefficients[0], 2.0, 1e-12);
  EXPECT_NEAR(fit.coefficients[1], 3.0, 1e-12);
  EXPECT_EQ(fit.dof, 1);
  // Two identical columns: rank 1, and the null direction says which.
  Eigen::MatrixXd b(3, 2);
  b << 1, 1, 2, 2, 3, 3;
  const LinearFit degenerate = weightedLeastSquares(b, y, Eigen::Vector3d::Ones());
  EXPECT_EQ(degenerate.rank, 1);
  EXPECT_NEAR(std::abs(degenerate.null_direction[0]), std::abs(degenerate.null_direction[1]), 1e-9);
  EXPECT_THROW(weightedLeastSquares(a, y, Eigen::Vector3d(1, 0, 1)), InvalidArgument);
}

// ---- round trips -------------------------------------------------------------------------------------

TEST(StiffnessIdentification, RecoversTheTruthWithinTheNoise) {
  const JointErrorModel nominal = rx170Model();
  const JointErrorModel truth = truthModel(2012);
  const MeasurementCampaign campaign = simulateCampaign(truth, CampaignSimulationSpec());
  const StiffnessIdentificationResult result = identifyStiffness(nominal, campaign);
  ASSERT_EQ(result.local.size(), 6u);
  EXPECT_EQ(result.local_groups, 6);
  EXPECT_EQ(result.global_groups, 8);
  EXPECT_FALSE(result.global_shares_rows);
  EXPECT_EQ(result.local[2].method, "levels");
  for (int j = 0; j < 6; ++j) {
    const double k = stiffnessOf(truth, j);
    for (const StiffnessEstimate* e : {&result.local[j], &result.global[j]}) {
      ASSERT_TRUE(e->identified) << "joint " << j + 1 << ": " << e->reason;
      EXPECT_LT(std::abs(e->stiffness - k), 4.0 * e->stiffness_se) << "joint " << j + 1 << " " << e->method;
      EXPECT_GT(e->stiffness_high, e->stiffness);
      EXPECT_LT(e->stiffness_low, e->stiffness);
      // The residuals are the stated noise: the reduced chi-square is near 1.
      EXPECT_GT(e->reduced_chi2, 0.4) << "joint " << j + 1 << " " << e->method;
      EXPECT_LT(e->reduced_chi2, 2.0) << "joint " << j + 1 << " " << e->method;
    }
    EXPECT_TRUE(std::isfinite(result.z_score[j]));
  }
  // The noise implies: joints 1 and 2 to better than 1 %, joint 3 (levels) to about 1 %.
  EXPECT_LT(result.local[0].stiffness_se / result.local[0].stiffness, 0.01);
  EXPECT_LT(result.local[1].stiffness_se / result.local[1].stiffness, 0.01);
  EXPECT_LT(result.local[2].stiffness_se / result.local[2].stiffness, 0.02);
}

TEST(StiffnessIdentification, ExactDataGiveTheTruth) {
  const JointErrorModel nominal = rx170Model();
  const JointErrorModel truth = truthModel(7);
  CampaignSimulationSpec spec;
  spec.noise = false;
  const StiffnessIdentificationResult result = identifyStiffness(nominal, simulateCampaign(truth, spec));
  for (int j = 0; j < 6; ++j) {
    const double k = stiffnessOf(truth, j);
    // What is left: second-order terms, and the cross-talk correction made with the nominal compliance.
    EXPECT_NEAR(result.local[j].stiffness / k, 1.0, 2e-3) << "joint " << j + 1;
    // Joint 4 is seen weakly by the global poses (15 % standard error with noise), so second-order
    // terms weigh more in it: 0.5 %, a thirtieth of its uncertainty.
    EXPECT_NEAR(result.global[j].stiffness / k, 1.0, j == 3 ? 1e-2 : 2e-3) << "joint " << j + 1;
  }
}

TEST(StiffnessIdentification, IntervalsCoverTheTruthAtTheStatedRate) {
  const JointErrorModel nominal = rx170Model();
  int covered_local = 0, covered_global = 0, trials = 0;
  int per_joint[6] = {0, 0, 0, 0, 0, 0};
  const int seeds = 40;
  for (int seed = 1; seed <= seeds; ++seed) {
    const JointErrorModel truth = truthModel(1000 + static_cast<std::uint64_t>(seed));
    CampaignSimulationSpec spec;
    spec.seed = static_cast<std::uint64_t>(seed);
    const StiffnessIdentificationResult result = identifyStiffness(nominal, simulateCampaign(truth, spec));
    for (int j = 0; j < 6; ++j) {
      const double k = stiffnessOf(truth, j);
      const StiffnessEstimate& l = result.local[j];
      const StiffnessEstimate& g = result.global[j];
      ASSERT_TRUE(l.identified && g.identified);
      ++trials;
      const bool local_covers = k >= l.stiffness_low && k <= l.stiffness_high;
      covered_local += local_covers ? 1 : 0;
      per_joint[j] += local_covers ? 1 : 0;
      covered_global += k >= g.stiffness_low && k <= g.stiffness_high ? 1 : 0;
    }
  }
  const double local_rate = static_cast<double>(covered_local) / trials;
  const double global_rate = static_cast<double>(covered_global) / trials;
  std::printf("95 %% intervals over %d seeds x 6 joints: local covers the truth %.1f %%, global %.1f %%\n", seeds,
              100 * local_rate, 100 * global_rate);
  std::printf("local per joint:");
  for (int j = 0; j < 6; ++j) std::printf(" %d/%d", per_joint[j], seeds);
  std::printf("\n");
  EXPECT_GE(local_rate, 0.88);
  EXPECT_LE(local_rate, 0.99);
  EXPECT_GE(global_rate, 0.88);
  EXPECT_LE(global_rate, 0.99);
  for (int j = 0; j < 6; ++j) EXPECT_GE(per_joint[j], 32) << "joint " << j + 1;  // 80 %: no joint far off
}

TEST(StiffnessIdentification, LocalTestsAloneStillGiveBothMethods) {
  const JointErrorModel truth = truthModel(3);
  CampaignSimulationSpec spec;
  spec.stiffness.global_poses = 0;
  const StiffnessIdentificationResult result = identifyStiffness(rx170Model(), simulateCampaign(truth, spec));
  EXPECT_TRUE(result.global_shares_rows);
  ASSERT_FALSE(result.notes.empty());
  EXPECT_THAT(result.notes[0], HasSubstr("not independent"));
  for (int j = 0; j < 6; ++j) {
    EXPECT_TRUE(result.local[j].identified);
    EXPECT_LT(std::abs(result.local[j].stiffness - stiffnessOf(truth, j)), 4.0 * result.local[j].stiffness_se);
  }
}

TEST(StiffnessIdentification, UpdatedParameterFileHoldsTheEstimates) {
  const JointErrorModel nominal = rx170Model();
  const JointErrorModel truth = truthModel(2012);
  const StiffnessIdentificationResult result =
      identifyStiffness(nominal, simulateCampaign(truth, CampaignSimulationSpec()));
  const JointErrorModel updated = withIdentifiedStiffness(nominal, result, false, "campaign.csv");
  TemporaryDirectory directory("stiffness_update");
  saveParameterFile(updated, directory.file("params.json"));
  const JointErrorModel back = loadParameterFile(directory.file("params.json"), rx170());
  for (int j = 0; j < 6; ++j) EXPECT_EQ(stiffnessOf(back, j), result.local[j].stiffness);
  EXPECT_THAT(back.notes, HasSubstr("identified from campaign.csv"));
  // The other effects are untouched.
  ASSERT_EQ(back.effectCount(), nominal.effectCount());
  for (int i = 0; i < nominal.effectCount(); ++i) {
    if (nominal.effect(i).type() != "compliance") {
      EXPECT_EQ(back.effect(i).parameters(), nominal.effect(i).parameters());
    }
  }
  const JointErrorModel global = withIdentifiedStiffness(nominal, result, true, "campaign.csv");
  for (int j = 0; j < 6; ++j) EXPECT_EQ(stiffnessOf(global, j), result.global[j].stiffness);
  // The report compares with the truth.
  const nlohmann::ordered_json report = stiffnessReportJson(result, ReportSources{}, &truth);
  EXPECT_EQ(report["joints"][1]["true_stiffness_nm_per_rad"].get<double>(), stiffnessOf(truth, 1));
  EXPECT_TRUE(report["joints"][1]["local"].contains("interval_covers_truth"));
  EXPECT_THAT(stiffnessSummary(result, ReportSources{}, &truth), HasSubstr("joint_6"));
}

// ---- errors ------------------------------------------------------------------------------------------

TEST(StiffnessIdentification, TooFewPointsInALocalTest) {
  const JointErrorModel truth = truthModel(2012);
  CampaignSimulationSpec spec;
  spec.stiffness.joints = {0};
  spec.stiffness.global_poses = 0;
  MeasurementCampaign campaign = simulateCampaign(truth, spec);
  // The ladder cut down to rows 1-3 (loads 0.25, 0.5, 0.75 of the maximum), two of them not measured.
  MeasurementCampaign cut = campaign;
  for (auto* column : {&cut.time, &cut.temperature, &cut.payload})
    *column = {column->at(1), column->at(2), column->at(3)};
  cut.command = {campaign.command[1], campaign.command[2], campaign.command[3]};
  cut.position = {campaign.position[1], campaign.position[2], campaign.position[3]};
  cut.wrench = {campaign.wrench[1], campaign.wrench[2], campaign.wrench[3]};
  cut.measured_angles.assign(3, JointVector::Constant(6, std::numeric_limits<double>::quiet_NaN()));
  cut.position[0].setConstant(std::numeric_limits<double>::quiet_NaN());
  cut.position[2].setConstant(std::numeric_limits<double>::quiet_NaN());
  expectMeasurementError([&] { identifyStiffnessLocal(rx170Model(), cut); },
                         "joint_1: 1 measured points for 2 unknowns");
}

TEST(StiffnessIdentification, DegeneratePosesAreNamed) {
  // One pose, forces along x only: the global fit cannot tell the joints apart.
  const JointErrorModel truth = truthModel(2012);
  CampaignSimulationSpec spec;
  spec.stiffness.joints = {1};
  spec.stiffness.global_poses = 1;
  MeasurementCampaign campaign = simulateCampaign(truth, spec);
  MeasurementCampaign degenerate = campaign;
  for (std::size_t k = 0; k < degenerate.size(); ++k) {
    const double fx = degenerate.wrench[k][0];
    degenerate.wrench[k].setZero();
    degenerate.wrench[k][0] = fx;
  }
  expectMeasurementError([&] { identifyStiffnessGlobal(rx170Model(), degenerate, {}, true); }, "degenerate poses");
  // The local test of joint 2 alone has one joint: the global fit of it alone cannot separate anything
  // but joint 2 ... and the others' torques do not vary there, so they are simply not identified.
  spec.stiffness.global_poses = 0;
  const std::vector<StiffnessEstimate> global =
      identifyStiffnessGlobal(rx170Model(), simulateCampaign(truth, spec), {}, true);
  EXPECT_TRUE(global[1].identified);
  EXPECT_FALSE(global[0].identified);
  EXPECT_THAT(global[0].reason, HasSubstr("does not vary"));
}

TEST(StiffnessIdentification, NoLoadsNoTestsWrongFrameOrRobot) {
  const JointErrorModel nominal = rx170Model();
  const JointErrorModel truth = truthModel(2012);
  CampaignSimulationSpec spec;
  spec.protocol = CampaignProtocol::RandomPoses;
  spec.random.count = 20;
  const MeasurementCampaign unloaded = simulateCampaign(truth, spec);
  expectMeasurementError([&] { identifyStiffness(nominal, unloaded); }, "nothing to identify stiffness from");
  expectMeasurementError([&] { identifyStiffnessLocal(nominal, unloaded); }, "no local stiffness test");
  expectMeasurementError([&] { identifyStiffnessGlobal(nominal, unloaded); }, "at least two");

  MeasurementCampaign campaign = simulateCampaign(truth, CampaignSimulationSpec());
  campaign.frame = MeasurementFrame::Instrument;
  expectMeasurementError([&] { identifyStiffness(nominal, campaign); }, "base frame");
  campaign.frame = MeasurementFrame::Base;
  campaign.robot = "ur10";
  EXPECT_THROW(identifyStiffness(nominal, campaign), InvalidArgument);
  campaign.robot = "rx170";
  campaign.command[5][1] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(identifyStiffness(nominal, campaign), MeasurementError);
}

TEST(StiffnessIdentification, TargetOnTheTestedAxis) {
  // A target on the flange axis cannot show joint 6 turning.
  const JointErrorModel truth = truthModel(2012);
  CampaignSimulationSpec spec;
  spec.target_in_flange = Eigen::Vector3d(0.0, 0.0, 0.15);
  spec.stiffness.joints = {5};
  spec.stiffness.global_poses = 0;
  expectMeasurementError([&] { identifyStiffnessLocal(rx170Model(), simulateCampaign(truth, spec)); },
                         "within 1 mm of the joint's axis");
}

TEST(StiffnessIdentification, RowsNotMeasuredAreLeftOutAndCounted) {
  const JointErrorModel truth = truthModel(2012);
  MeasurementCampaign campaign = simulateCampaign(truth, CampaignSimulationSpec());
  for (std::size_t k = 3; k < campaign.size(); k += 10)
    campaign.position[k].setConstant(std::numeric_limits<double>::quiet_NaN());
  const StiffnessIdentificationResult result = identifyStiffness(rx170Model(), campaign);
  EXPECT_EQ(result.rows_without_position, 21);
  for (int j = 0; j < 6; ++j) EXPECT_TRUE(result.local[j].identified);
  // A partial NaN in a position is an error, not a missing measurement.
  campaign.position[4].x() = std::numeric_limits<double>::quiet_NaN();
  expectMeasurementError([&] { identifyStiffness(rx170Model(), campaign); }, "row 5");
}

}  // namespace
}  // namespace jointcomp
