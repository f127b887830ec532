// Measurement campaigns (shared/formats/measurements.md): a good file is read with its values in SI
// units, empty cells as "not measured", unknown columns and metadata kept or ignored as the format says;
// write -> read gives the campaign back within 1e-12; and every kind of broken file (tests/data/campaigns)
// is rejected with the file, the line and the column named.
#include <cmath>
#include <functional>
#include <limits>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/common/random.hpp"
#include "model/io/measurement_campaign.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

constexpr double kDegree = 3.14159265358979323846 / 180.0;

std::string campaignFile(const std::string& name) {
  return std::string(JOINTCOMP_TEST_DATA_DIR) + "/campaigns/" + name;
}

TEST(MeasurementCampaign, GoodFileInSiUnits) {
  const MeasurementCampaign c = readCampaignFile(campaignFile("good.csv"));
  EXPECT_EQ(c.source, campaignFile("good.csv"));
  EXPECT_EQ(c.robot, "rx170");
  EXPECT_EQ(c.frame, MeasurementFrame::Base);
  EXPECT_TRUE(c.has_target);
  EXPECT_NEAR((c.target_in_flange - Eigen::Vector3d(0.1, 0.0, 0.15)).norm(), 0.0, 1e-15);
  EXPECT_NEAR(c.position_noise, 15e-6, 1e-18);
  EXPECT_NEAR(c.angle_noise, 0.0014 * kDegree, 1e-18);
  EXPECT_EQ(c.metadata.at("operator"), "kept and ignored");
  EXPECT_EQ(c.metadata.at("format"), "jointcomp-measurements/1");
  ASSERT_EQ(c.dof, 6);
  ASSERT_EQ(c.size(), 4u);  // never drops a row
  EXPECT_EQ(c.time[3], 10.0);
  EXPECT_NEAR(c.command[0][1], 40 * kDegree, 1e-15);
  EXPECT_NEAR(c.command[3][1], 41 * kDegree, 1e-15);
  EXPECT_TRUE(c.has_position);
  EXPECT_NEAR(c.position[0].x(), 1.69581, 1e-15);
  EXPECT_NEAR(c.position[0].z(), 0.917925, 1e-15);
  EXPECT_TRUE(std::isnan(c.position[2].x()) && std::isnan(c.position[2].y()) && std::isnan(c.position[2].z()));
  EXPECT_TRUE(c.has_measured_angles);
  EXPECT_NEAR(c.measured_angles[0][2], 50.001 * kDegree, 1e-15);
  EXPECT_TRUE(std::isnan(c.measured_angles[1][2]));
  EXPECT_TRUE(std::isnan(c.measured_angles[0][0]));  // no qm1 column
  EXPECT_EQ(c.temperature[0], 20.5);
  EXPECT_TRUE(std::isnan(c.temperature[2]));
  EXPECT_EQ(c.wrench[1][1], 63.1);
  EXPECT_EQ(c.wrench[1][5], -5.7);
  EXPECT_TRUE(c.wrench[3].isZero(0.0));  // empty wrench cells: no force
  EXPECT_EQ(c.payload[2], 2.5);
  EXPECT_EQ(c.payload[3], 0.0);
  EXPECT_NO_THROW(c.validate());
}

TEST(MeasurementCampaign, ByteOrderMarkAndWindowsLineEnds) {
  const std::string text =
      "\xEF\xBB\xBF# format: jointcomp-measurements/1\r\nt,q1,x,y,z\r\n0,10,1,2,3\r\n1,11,1,2,3\r\n";
  const MeasurementCampaign c = parseCampaign(text, "bom.csv");
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.dof, 1);
  EXPECT_NEAR(c.command[1][0], 11 * kDegree, 1e-15);
}

// A campaign with every kind of column, random values and holes.
MeasurementCampaign randomCampaign() {
  DeterministicRandom random(42);
  MeasurementCampaign c;
  c.source = "random";
  c.robot = "rx170";
  c.frame = MeasurementFrame::Instrument;
  c.has_target = true;
  c.target_in_flange = Eigen::Vector3d(0.0123456789, -0.1, 0.10900007);
  c.position_noise = 16.97e-6;
  c.angle_noise = 0.0014142 * kDegree;
  c.metadata["protocol"] = "random";
  c.dof = 6;
  c.has_position = true;
  c.has_measured_angles = true;
  double t = 0.0;
  for (int k = 0; k < 200; ++k) {
    t += random.uniform(0.0, 3.0);
    c.time.push_back(k == 7 ? c.time.back() : t);  // a repeated time is allowed
    JointVector q(6), qm(6);
    for (int j = 0; j < 6; ++j) {
      q[j] = random.uniform(-3.0, 3.0);
      qm[j] = random.uniform() < 0.7 ? std::numeric_limits<double>::quiet_NaN() : q[j] + random.normal() * 1e-4;
    }
    c.command.push_back(q);
    c.measured_angles.push_back(qm);
    c.position.push_back(random.uniform() < 0.1
                             ? Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN())
                             : Eigen::Vector3d(random.uniform(-2, 2), random.uniform(-2, 2), random.uniform(0, 2)));
    c.temperature.push_back(random.uniform() < 0.5 ? std::numeric_limits<double>::quiet_NaN() : random.uniform(18, 25));
    Vector6 w;
    for (int a = 0; a < 6; ++a) w[a] = random.normal() * 100.0;
    c.wrench.push_back(w);
    c.payload.push_back(random.uniform(0.0, 10.0));
  }
  return c;
}

void expectSameValue(double a, double b, double tolerance, const std::string& what) {
  if (std::isnan(a) || std::isnan(b)) {
    EXPECT_TRUE(std::isnan(a) && std::isnan(b)) << what;
  } else {
    EXPECT_NEAR(a, b, tolerance) << what;
  }
}

TEST(MeasurementCampaign, WriteReadRoundTripWithin1e12) {
  const MeasurementCampaign c = randomCampaign();
  const std::string path = ::testing::TempDir() + "jointcomp_round_trip.csv";
  writeCampaignFile(c, path);
  const MeasurementCampaign back = readCampaignFile(path);
  EXPECT_EQ(back.robot, c.robot);
  EXPECT_EQ(back.frame, c.frame);
  EXPECT_TRUE(back.has_target);
  EXPECT_LT((back.target_in_flange - c.target_in_flange).norm(), 1e-12);
  EXPECT_NEAR(back.position_noise, c.position_noise, 1e-12);
  EXPECT_NEAR(back.angle_noise, c.angle_noise, 1e-12);
  EXPECT_EQ(back.metadata.at("protocol"), "random");
  ASSERT_EQ(back.size(), c.size());
  ASSERT_EQ(back.dof, c.dof);
  for (std::size_t k = 0; k < c.size(); ++k) {
    const std::string row = "row " + std::to_string(k);
    EXPECT_EQ(back.time[k], c.time[k]) << row;
    for (int j = 0; j < 6; ++j) {
      expectSameValue(back.command[k][j], c.command[k][j], 1e-12, row);
      expectSameValue(back.measured_angles[k][j], c.measured_angles[k][j], 1e-12, row);
    }
    for (int a = 0; a < 3; ++a) expectSameValue(back.position[k][a], c.position[k][a], 1e-12, row);
    for (int a = 0; a < 6; ++a) expectSameValue(back.wrench[k][a], c.wrench[k][a], 1e-12, row);
    expectSameValue(back.temperature[k], c.temperature[k], 1e-12, row);
    expectSameValue(back.payload[k], c.payload[k], 1e-12, row);
  }
}

// campaignRows: a subset and its complement hold every row once, in order, each with all its columns, and
// both keep the campaign's metadata and validate; the odd rows of the even rows' complement round-trip.
TEST(MeasurementCampaign, RowsAndTheirComplementPartitionTheCampaign) {
  const MeasurementCampaign c = randomCampaign();
  const auto even = [](std::size_t k) { return k % 2 == 0; };
  const MeasurementCampaign kept = campaignRows(c, even);
  const MeasurementCampaign rest = campaignRows(c, [&](std::size_t k) { return !even(k); });
  ASSERT_EQ(kept.size() + rest.size(), c.size());
  EXPECT_NO_THROW(kept.validate());
  EXPECT_NO_THROW(rest.validate());
  EXPECT_EQ(kept.metadata, c.metadata);
  EXPECT_EQ(kept.target_in_flange, c.target_in_flange);
  for (std::size_t k = 0; k < c.size(); ++k) {
    const MeasurementCampaign& part = even(k) ? kept : rest;
    const std::size_t i = k / 2;
    EXPECT_EQ(part.time[i], c.time[k]);
    EXPECT_EQ(part.command[i], c.command[k]);
    EXPECT_EQ(part.payload[i], c.payload[k]);
    EXPECT_EQ(part.wrench[i], c.wrench[k]);
    EXPECT_TRUE(part.position[i].isApprox(c.position[k]) || (part.position[i].hasNaN() && c.position[k].hasNaN()));
    EXPECT_EQ(std::isnan(part.temperature[i]), std::isnan(c.temperature[k]));
  }
  EXPECT_EQ(campaignRows(c, [](std::size_t) { return false; }).size(), 0u);
}

TEST(MeasurementCampaign, InconsistentCampaignIsNotWritten) {
  MeasurementCampaign c = randomCampaign();
  c.payload.pop_back();
  EXPECT_THROW(campaignToText(c), MeasurementError);
  c = randomCampaign();
  c.time[5] = c.time[4] - 1.0;
  EXPECT_THROW(c.validate(), MeasurementError);
  c = randomCampaign();
  c.command[3][2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(c.validate(), MeasurementError);
}

struct BrokenFile {
  const char* file;
  int line;              // the line the message must name (0: no line number expected)
  const char* fragment;  // and this text (column, reason)
};

class BrokenCampaign : public ::testing::TestWithParam<BrokenFile> {};

TEST_P(BrokenCampaign, IsRejectedNamingFileLineAndColumn) {
  const BrokenFile& broken = GetParam();
  const std::string path = campaignFile(broken.file);
  try {
    readCampaignFile(path);
    FAIL() << broken.file << " was accepted";
  } catch (const MeasurementError& error) {
    const std::string message = error.what();
    EXPECT_THAT(message, HasSubstr(path));
    if (broken.line > 0) {
      EXPECT_THAT(message, HasSubstr(path + ":" + std::to_string(broken.line) + ":"));
    }
    EXPECT_THAT(message, HasSubstr(broken.fragment));
  }
}

INSTANTIATE_TEST_SUITE_P(
    Files, BrokenCampaign,
    ::testing::Values(
        BrokenFile{"missing_format_line.csv", 1, "the first line must be '# format: jointcomp-measurements/1'"},
        BrokenFile{"wrong_format_version.csv", 1, "the first line must be"},
        BrokenFile{"empty.csv", 1, "the file is empty"}, BrokenFile{"no_header.csv", 2, "no header row"},
        BrokenFile{"missing_t.csv", 2, "required column 't' is missing"},
        BrokenFile{"missing_joints.csv", 2, "required columns q1 ... qN are missing"},
        BrokenFile{"no_measurement.csv", 2, "needs measured positions (x, y, z) or measured joint angles"},
        BrokenFile{"non_numeric.csv", 4, "column 'q2': '4O' is not a number"},
        BrokenFile{"non_finite.csv", 4, "column 'x': 'inf' is not finite"},
        BrokenFile{"nan_cell.csv", 4, "column 'y': 'nan' is not finite"},
        BrokenFile{"overflow.csv", 4, "column 'z': '1e999' is not finite"},
        BrokenFile{"absurd_position.csv", 4, "column 'z': 1e+308 mm is beyond the plausible range of +-1e+06 mm"},
        BrokenFile{"absurd_angle.csv", 4, "column 'q2': 40000000 deg is beyond the plausible range"},
        BrokenFile{"decreasing_t.csv", 5, "column 't': time decreases"},
        BrokenFile{"wrong_cell_count.csv", 4, "row has 5 cells, the header has 6"},
        BrokenFile{"semicolon_separated.csv", 2, "the header's columns are separated by ';'"},
        BrokenFile{"tab_separated.csv", 2, "the header's columns are separated by tabs"},
        BrokenFile{"decimal_commas.csv", 4, "row has 8 cells, the header has 6 (decimal commas?"},
        BrokenFile{"partial_xyz_header.csv", 2, "columns x, y and z go together"},
        BrokenFile{"partial_xyz_row.csv", 4, "columns x, y, z: measured in part only"},
        BrokenFile{"q_gap.csv", 2, "column 'q4' but the joints are q1 ... q2"},
        BrokenFile{"q_huge_index.csv", 2, "column 'q99999999999999999999' but the joints are q1 ... q2"},
        BrokenFile{"empty_q_cell.csv", 4, "column 'q2': empty cell in a required column"},
        BrokenFile{"negative_payload.csv", 3, "column 'payload': negative mass"},
        BrokenFile{"duplicate_column.csv", 2, "column 'x' appears twice"},
        BrokenFile{"bad_frame.csv", 0, "metadata 'frame' must be 'base' or 'instrument', is 'tracker'"},
        BrokenFile{"bad_target.csv", 0, "metadata 'target' must be 'x,y,z' in mm"},
        BrokenFile{"no_such_file.csv", 0, "no_such_file.csv"}),
    [](const ::testing::TestParamInfo<BrokenFile>& param) {
      std::string name = param.param.file;
      name = name.substr(0, name.find('.'));
      return name;
    });

}  // namespace
}  // namespace jointcomp

namespace jointcomp {
namespace {

// A 10 MB name in a campaign is quoted as a short excerpt, not echoed whole (issue 41: a message of
// 10,000,067 bytes).
TEST(MeasurementCampaign, LongNamesAreQuotedAsShortExcerpts) {
  const std::string huge(10000000, 'k');
  const std::string format = "# format: jointcomp-measurements/1\n";
  const std::vector<std::string> texts = {
      format + "t,q1," + huge + "," + huge + ",x,y,z\n0,0,0,0,0,0,0\n",         // a column twice
      format + "t,q1,q" + std::string(5000000, '9') + ",x,y,z\n0,0,0,0,0,0\n",  // a joint beyond the robot
      format + "# frame: " + huge + "\nt,q1,x,y,z\n0,0,0,0,0\n",                // an unknown frame
  };
  for (const std::string& text : texts) {
    try {
      parseCampaign(text, "long.csv");
      ADD_FAILURE() << "a campaign with a 10 MB name was read";
    } catch (const MeasurementError& error) {
      EXPECT_LT(std::string(error.what()).size(), 1000u) << std::string(error.what()).substr(0, 300);
      EXPECT_THAT(error.what(), HasSubstr("long.csv"));
    }
  }
}

// The writer applies the reader's rules to the metadata: a newline in a value (import-csv --robot, an
// input path) wrote a header the reader then read as another line.
TEST(MeasurementCampaign, MetadataWithALineBreakIsNotWritten) {
  MeasurementCampaign campaign = readCampaignFile(campaignFile("good.csv"));
  campaign.robot = "rx170\nt,q1,q2";
  try {
    campaignToText(campaign);
    ADD_FAILURE() << "a robot name with a newline was written";
  } catch (const MeasurementError& error) {
    EXPECT_THAT(error.what(), HasSubstr("campaign metadata 'robot': a line break"));
  }
  campaign.robot = "rx170";
  campaign.metadata["source"] = "C:\\data\texport.csv";  // a tab is harmless
  EXPECT_EQ(parseCampaign(campaignToText(campaign), "again.csv").metadata.at("source"), "C:\\data\texport.csv");
  campaign.metadata["a: b"] = "c";
  EXPECT_THROW(campaignToText(campaign), MeasurementError);
}

// The writer applies the reader's rules (issue 41: importers and simulate wrote inf from x = 1.7e308 m,
// times of 2e12 s from --settle 1e9, payload -5 and '# target: -1e+300', which the reader then refused or
// should have).
TEST(MeasurementCampaign, WhatTheReaderWouldRefuseIsNotWritten) {
  const MeasurementCampaign good = readCampaignFile(campaignFile("good.csv"));
  const auto refused = [&](const std::function<void(MeasurementCampaign&)>& spoil, const std::string& phrase) {
    MeasurementCampaign campaign = good;
    spoil(campaign);
    try {
      campaignToText(campaign);
      ADD_FAILURE() << "written: " << phrase;
    } catch (const MeasurementError& error) {
      EXPECT_THAT(error.what(), HasSubstr(phrase));
    }
  };
  ASSERT_TRUE(good.has_position);
  refused([](MeasurementCampaign& c) { c.position[0].x() = 1.7e308; }, "row 1, column 'x': inf mm cannot be written");
  refused([](MeasurementCampaign& c) { c.time.back() = 2e12; }, "column 't': 2000000000000 s cannot be written");
  refused([](MeasurementCampaign& c) { c.command[1][0] = 1e307; }, "row 2, column 'q1'");
  refused([](MeasurementCampaign& c) { c.payload[0] = -5; }, "payload': negative mass");
  refused(
      [](MeasurementCampaign& c) {
        c.has_target = true;
        c.target_in_flange.x() = -1e297;
      },
      "metadata 'target': -1e+300 mm cannot be written");
  // ... and the reader refuses such a target too.
  MeasurementCampaign without_target = good;
  without_target.has_target = false;
  without_target.metadata.erase("target");
  std::string text = campaignToText(without_target);
  text.insert(text.find('\n') + 1, "# target: -1e+300,0,0\n");
  try {
    parseCampaign(text, "target.csv");
    ADD_FAILURE() << "a target of -1e300 mm was read";
  } catch (const MeasurementError& error) {
    EXPECT_THAT(error.what(), HasSubstr("'# target': -1e+300 mm is beyond the plausible range"));
  }
}

}  // namespace
}  // namespace jointcomp
