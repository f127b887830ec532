// The IPA UR10 importer on the real files (shared/data/ipa-ur10): row counts, the first rows' values in
// SI units, the T-Mac target about 109 mm along the flange z axis, Series A's time from its timestamps
// (the rows that go back in time held and counted), Series B's from the row order; the result survives
// the campaign format; broken files are rejected naming file, line and column.
#include <cmath>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/io/ipa_ur10_import.hpp"
#include "tests/support/shared_data.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

std::string ipaFile(const std::string& name) { return test::sharedFile("data/ipa-ur10/" + name); }
std::string brokenFile(const std::string& name) { return std::string(JOINTCOMP_TEST_DATA_DIR) + "/campaigns/" + name; }

TEST(IpaImport, SeriesA) {
  JOINTCOMP_REQUIRE_SHARED_FILE("the IPA UR10 data", "data/ipa-ur10/Series_A/measurements_grid.csv");
  const MeasurementCampaign c =
      importIpaUr10(ipaFile("Series_A/measurements_grid.csv"), ipaFile("Series_A/Trafo_TM_F_init.txt"));
  // Every data row of the file (its README says 11,910; the file holds 11,911 rows after the header).
  ASSERT_EQ(c.size(), 11911u);
  EXPECT_EQ(c.robot, "ur10");
  EXPECT_EQ(c.frame, MeasurementFrame::Instrument);
  EXPECT_EQ(c.dof, 6);
  // First row: 20200714163904; joints -1,5708;-1,5708;0,0;-1,5708;0,0;0,0 rad; T-Mac at
  // 2361,9831;-1368,5474;119,39713 mm; 23,6800003051758 degC.
  const double expected_q[6] = {-1.5708, -1.5708, 0.0, -1.5708, 0.0, 0.0};
  for (int j = 0; j < 6; ++j) EXPECT_DOUBLE_EQ(c.command[0][j], expected_q[j]) << "joint " << j + 1;
  EXPECT_NEAR(c.position[0].x(), 2.3619831, 1e-12);
  EXPECT_NEAR(c.position[0].y(), -1.3685474, 1e-12);
  EXPECT_NEAR(c.position[0].z(), 0.11939713, 1e-12);
  EXPECT_DOUBLE_EQ(c.temperature[0], 23.6800003051758);
  EXPECT_EQ(c.time[0], 0.0);
  // Second row 20 s later (20200714163924).
  EXPECT_EQ(c.time[1], 20.0);
  EXPECT_NEAR(c.command[1][0], -2.14055, 1e-15);
  // The T-Mac 109 mm along the flange z axis.
  ASSERT_TRUE(c.has_target);
  EXPECT_NEAR(c.target_in_flange.z(), 0.109, 1e-6);
  EXPECT_LT(c.target_in_flange.head<2>().norm(), 1e-6);
  // Time from the timestamps; about 100 hours; ten rows go back in time and are held.
  EXPECT_EQ(c.metadata.at("time_from"), "timestamps (s since the first row)");
  EXPECT_EQ(c.metadata.at("time_held_rows"), "10");
  for (std::size_t k = 1; k < c.size(); ++k) ASSERT_GE(c.time[k], c.time[k - 1]) << "row " << k;
  // The last nine rows were measured in earlier sessions (2020-07-14 and -15, and -17) and appended at the
  // end: they keep the latest time, 100.8 hours after the first row.
  EXPECT_NEAR(c.time[11901] / 3600.0, 100.81, 0.01);
  EXPECT_EQ(c.time.back(), c.time[11901]);
  EXPECT_LT(c.time[1358], c.time[1360]);
  // Room temperature 23.68 -> 22.93 degC over the night.
  EXPECT_GT(c.temperature[0], c.temperature.back());
}

TEST(IpaImport, SeriesBTimeFromRowOrder) {
  JOINTCOMP_REQUIRE_SHARED_FILE("the IPA UR10 data", "data/ipa-ur10/Series_B/measurements_joint_configurations.csv");
  const MeasurementCampaign c =
      importIpaUr10(ipaFile("Series_B/measurements_joint_configurations.csv"), ipaFile("Series_B/Trafo_TM_F_init.txt"));
  ASSERT_EQ(c.size(), 1495u);
  // The timestamps are mangled ("2,02011E+13"): time is the row order, 1 s per row.
  EXPECT_EQ(c.metadata.at("time_from"), "row order (1 s per row)");
  EXPECT_EQ(c.metadata.at("time_held_rows"), "0");
  for (std::size_t k = 0; k < c.size(); ++k) ASSERT_EQ(c.time[k], static_cast<double>(k));
  const double expected_q[6] = {-3.14159, -1.5708, 0.0, -1.5708, 0.0, 0.0};
  for (int j = 0; j < 6; ++j) EXPECT_DOUBLE_EQ(c.command[0][j], expected_q[j]) << "joint " << j + 1;
  EXPECT_NEAR(c.position[0].x(), 0.38376294, 1e-12);
  EXPECT_NEAR(c.position[0].y(), -3.2408734, 1e-12);
  EXPECT_NEAR(c.position[0].z(), 0.20193157, 1e-12);
  EXPECT_DOUBLE_EQ(c.temperature[0], 21.86750031);
  EXPECT_NEAR(c.position[1].x(), -0.50720828e-3, 1e-15);
  EXPECT_NEAR(c.target_in_flange.z(), 0.109, 1e-6);
}

TEST(IpaImport, WithoutTrafoThereIsNoTarget) {
  JOINTCOMP_REQUIRE_SHARED_FILE("the IPA UR10 data", "data/ipa-ur10/Series_B/measurements_joint_configurations.csv");
  const MeasurementCampaign c = importIpaUr10(ipaFile("Series_B/measurements_joint_configurations.csv"));
  EXPECT_FALSE(c.has_target);
}

TEST(IpaImport, SurvivesTheCampaignFormat) {
  JOINTCOMP_REQUIRE_SHARED_FILE("the IPA UR10 data", "data/ipa-ur10/Series_B/measurements_joint_configurations.csv");
  const MeasurementCampaign c =
      importIpaUr10(ipaFile("Series_B/measurements_joint_configurations.csv"), ipaFile("Series_B/Trafo_TM_F_init.txt"));
  const std::string path = ::testing::TempDir() + "jointcomp_ipa_b.csv";
  writeCampaignFile(c, path);
  const MeasurementCampaign back = readCampaignFile(path);
  ASSERT_EQ(back.size(), c.size());
  EXPECT_EQ(back.frame, MeasurementFrame::Instrument);
  EXPECT_EQ(back.robot, "ur10");
  EXPECT_LT((back.target_in_flange - c.target_in_flange).norm(), 1e-12);
  EXPECT_EQ(back.metadata.at("time_from"), c.metadata.at("time_from"));
  for (std::size_t k = 0; k < c.size(); ++k) {
    ASSERT_LT((back.command[k] - c.command[k]).cwiseAbs().maxCoeff(), 1e-12) << "row " << k;
    ASSERT_LT((back.position[k] - c.position[k]).cwiseAbs().maxCoeff(), 1e-12) << "row " << k;
    ASSERT_NEAR(back.temperature[k], c.temperature[k], 1e-12) << "row " << k;
  }
}

template <typename Call>
void expectError(Call call, const std::string& where, const std::string& fragment) {
  try {
    call();
    ADD_FAILURE() << "accepted; expected an error with '" << fragment << "'";
  } catch (const MeasurementError& error) {
    EXPECT_THAT(error.what(), HasSubstr(where));
    EXPECT_THAT(error.what(), HasSubstr(fragment));
  }
}

TEST(IpaImport, BrokenFilesAreRejected) {
  expectError([] { importIpaUr10(brokenFile("ipa_missing_column.csv")); },
              brokenFile("ipa_missing_column.csv") + ":1:", "column 'wrist_3_joint' is missing");
  expectError([] { importIpaUr10(brokenFile("ipa_bad_number.csv")); },
              brokenFile("ipa_bad_number.csv") + ":3:", "column 'measurement_y': 'abc' is not a finite number");
  expectError([] { importIpaUr10(brokenFile("ipa_wrong_cell_count.csv")); },
              brokenFile("ipa_wrong_cell_count.csv") + ":2:", "row has 9 cells, the header has 10");
  expectError([] { importIpaUr10(brokenFile("empty.csv")); }, brokenFile("empty.csv"), "empty");
  expectError([] { importIpaUr10(brokenFile("no_such_file.csv")); }, "no_such_file.csv", "");
  expectError([] { ipaTargetInFlange(brokenFile("ipa_bad_trafo.txt")); }, brokenFile("ipa_bad_trafo.txt"),
              "expected 16 numbers (a 4x4 matrix), found 12");
  expectError([] { ipaTargetInFlange(brokenFile("ipa_not_rotation_trafo.txt")); },
              brokenFile("ipa_not_rotation_trafo.txt"), "the rotation part is not a rotation");
}

}  // namespace
}  // namespace jointcomp
