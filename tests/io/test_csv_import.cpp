// Importing a user's own tracker export: a spreadsheet's ';'-separated file with decimal commas, metadata
// lines, its own column names, radians and metres becomes the campaign a hand-written file in the format
// says (independently written below), and reads back through the campaign reader to the same values; a
// plain ',' export with the campaign's names needs no options; mistakes name the line, the column and
// what the header holds.
#include <cmath>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/io/csv_import.hpp"
#include "model/io/measurement_campaign.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

constexpr double kPi = 3.14159265358979323846;

const char* kSpreadsheetExport =
    "Tracker export v2.1\n"
    "Operator;A. N. Other\n"
    "\n"
    "Zeit [s];A1 [rad];A2 [rad];X [m];Y [m];Z [m];Temperatur\n"
    "0,0;0,1;-0,25;1,2005;0,0031;0,75;21,5\n"
    "1,5;0,2;-0,5;1,1;0,01;0,8;21,6\n"
    "3,0;0,3;-0,75;1,0;0,02;0,85;\n";

CsvImportOptions spreadsheetOptions() {
  CsvImportOptions options;
  options.columns = parseColumnMapping("t=Zeit [s],q1=A1 [rad],q2=A2 [rad],x=X [m],y=Y [m],z=Z [m],temp=Temperatur");
  options.angles_in_radians = true;
  options.lengths_in_metres = true;
  options.robot = "two_link";
  return options;
}

TEST(CsvImport, ASpreadsheetExportBecomesTheCampaignItDescribes) {
  const MeasurementCampaign imported = importCsv(kSpreadsheetExport, "export.csv", spreadsheetOptions());
  // The same campaign written by hand in the format: degrees and millimetres.
  const MeasurementCampaign expected = parseCampaign(
      "# format: jointcomp-measurements/1\n"
      "# robot: two_link\n"
      "t,q1,q2,x,y,z,temp\n"
      "0,5.729577951308232,-14.32394487827058,1200.5,3.1,750,21.5\n"
      "1.5,11.459155902616464,-28.64788975654116,1100,10,800,21.6\n"
      "3,17.188733853924695,-42.97183463481174,1000,20,850,\n",
      "expected.csv");
  ASSERT_EQ(imported.size(), 3u);
  EXPECT_EQ(imported.dof, 2);
  EXPECT_EQ(imported.robot, "two_link");
  EXPECT_EQ(imported.metadata.at("separator"), "';'");
  EXPECT_EQ(imported.metadata.at("decimal_mark"), ",");
  EXPECT_EQ(imported.metadata.at("imported_preamble_lines"), "3");
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(imported.time[k], expected.time[k]);
    EXPECT_NEAR((imported.command[k] - expected.command[k]).norm(), 0.0, 1e-15);
    EXPECT_NEAR((imported.position[k] - expected.position[k]).norm(), 0.0, 1e-15);
  }
  EXPECT_EQ(imported.temperature[1], 21.6);
  EXPECT_TRUE(std::isnan(imported.temperature[2]));
  // Written in the format and read back: the same numbers (the format keeps 17 digits).
  const MeasurementCampaign again = parseCampaign(campaignToText(imported), "again.csv");
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR((again.command[k] - imported.command[k]).norm(), 0.0, 1e-15);
    EXPECT_NEAR((again.position[k] - imported.position[k]).norm(), 0.0, 1e-15);
  }
}

TEST(CsvImport, APlainExportWithTheCampaignsNamesNeedsNoOptions) {
  const MeasurementCampaign c =
      importCsv("T,Q1,Q2,Q3,X,Y,Z\n0,10,20,30,100,200,300\n1,11,21,31,101,201,301\n", "plain.csv", {});
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.dof, 3);
  EXPECT_NEAR(c.command[1][2], 31 * kPi / 180, 1e-15);
  EXPECT_NEAR(c.position[0].z(), 0.3, 1e-15);
  // Without a time column, the row index is the time, and the metadata says so.
  const MeasurementCampaign untimed = importCsv("q1\tq2\tx\ty\tz\n1\t2\t3\t4\t5\n6\t7\t8\t9\t10\n", "tabs.csv", {});
  EXPECT_EQ(untimed.time[1], 1.0);
  EXPECT_EQ(untimed.metadata.at("separator"), "tab");
  EXPECT_EQ(untimed.metadata.count("time_from"), 1u);
}

void expectRefused(const std::string& text, const CsvImportOptions& options, const std::string& fragment) {
  try {
    importCsv(text, "bad.csv", options);
    ADD_FAILURE() << "accepted: " << text;
  } catch (const MeasurementError& error) {
    EXPECT_THAT(error.what(), HasSubstr(fragment));
  }
}

TEST(CsvImport, MistakesNameTheLineTheColumnAndTheHeader) {
  CsvImportOptions mapped;
  mapped.columns = parseColumnMapping("t=Zeit,q1=a1,x=X,y=Y,z=Z");  // names match ignoring case
  expectRefused("time,a1,x,y,z\n0,1,2,3,4\n1,1,2,3,4\n", mapped,
                "bad.csv:1: column 'Zeit' (mapped to t) is not in the header (time, a1, x, y, z)");
  expectRefused("t,a1,x,y,z\n0,1,2,3,4\n1,1,2,3,4\n", {}, "no joint columns");
  expectRefused("t,q1,x,y\n0,1,2,3\n1,1,2,3\n", {}, "columns x, y and z go together");
  expectRefused("t,q1,x,y,z\n0,1,2,3,4\n1,1,2,oops,4\n", {}, "bad.csv:3: column 'y': 'oops' is not a finite number");
  expectRefused("t,q1,x,y,z\n0,1,2,3,4\n1,1,2,3,4\n2,1,2,3\n", {}, "bad.csv:4: row has 4 cells, the header has 5");
  expectRefused("t,q1,x,y,z\n1,1,2,3,4\n0,1,2,3,4\n", {}, "time");
  expectRefused("just one line\n", {}, "no header row");
  CsvImportOptions wrong;
  wrong.columns = {{"speed", "V"}};
  expectRefused("t,q1,x,y,z\n0,1,2,3,4\n1,1,2,3,4\n", wrong, "'speed' is not a campaign column");
  EXPECT_THROW(parseColumnMapping("t=Time,q1"), MeasurementError);
}

TEST(CsvImport, JointKColumnsAndATargetPlusDeviationAreRead) {
  // A tracker's export: joint_1..joint_3 (found as q1..q3), the nominal position and the deviation from it.
  const std::string text =
      "Point;joint_1;joint_2;joint_3;X_target;Y_target;Z_target;dX;dY;dZ\n"
      "1;10;20;30;1000;200;300;0,25;-0,5;1,5\n"
      "2;11;21;31;1001;201;301;-0,25;0,5;-1,5\n";
  CsvImportOptions options;
  options.columns = parseColumnMapping("t=Point,x=X_target+dX,y=Y_target+dY,z=Z_target+dZ");
  options.has_target = true;
  options.target_in_flange = Eigen::Vector3d(0.01, 0.0, 0.08);
  const MeasurementCampaign c = importCsv(text, "tracker.csv", options);
  ASSERT_EQ(c.dof, 3);
  EXPECT_NEAR(c.command[1][2], 31 * kPi / 180, 1e-15);
  EXPECT_NEAR(c.position[0].x(), 1.00025, 1e-12);
  EXPECT_NEAR(c.position[1].z(), 0.2995, 1e-12);
  EXPECT_TRUE(c.has_target);
  EXPECT_EQ(c.target_in_flange, Eigen::Vector3d(0.01, 0.0, 0.08));
  // Written and read back, the target is the campaign's `# target:`.
  const MeasurementCampaign again = parseCampaign(campaignToText(c), "again.csv");
  EXPECT_TRUE(again.has_target);
  EXPECT_NEAR((again.target_in_flange - c.target_in_flange).norm(), 0.0, 1e-15);
}

TEST(CsvImport, NoJointIsDroppedAndNoColumnIsReadTwice) {
  const std::string seven = "t,A1,A2,A3,A4,A5,A6,A7,x,y,z\n0,1,2,3,4,5,6,7,8,9,10\n1,1,2,3,4,5,6,7,8,9,10\n";
  CsvImportOptions six;
  six.columns = parseColumnMapping("q1=A1,q2=A2,q3=A3,q4=A4,q5=A5,q6=A6");
  expectRefused(seven, six, "a column 'A7' that looks like joint 7, but only 6 joints are mapped");
  six.joints = 6;  // said on purpose: six joints
  EXPECT_EQ(importCsv(seven, "seven.csv", six).dof, 6);
  six.joints = 7;
  expectRefused(seven, six, "--joints 7 but 6 joint columns");
  // The next joint's column by the pattern of the last one mapped (A1 -> A2).
  CsvImportOptions one;
  one.columns = parseColumnMapping("q1=A1");
  expectRefused("t,A1,A2,x,y,z\n0,1,2,3,4,5\n1,1,2,3,4,5\n", one, "a column 'A2' that looks like joint 2");
  // A gap in the mapping: q3 missing, q4 mapped.
  CsvImportOptions gap;
  gap.columns = parseColumnMapping("q1=A1,q2=A2,q4=A4");
  expectRefused(seven, gap, "--columns maps q4 but the joints before it are not all mapped (found 2 joints");
  // One header column mapped to two campaign columns.
  CsvImportOptions twice;
  twice.columns = parseColumnMapping("q1=A1,q2=A1");
  expectRefused(seven, twice, "header column 'A1' is mapped to both q1 and q2");
  // Two header columns of one name: which is meant is not known.
  expectRefused("t,q1,x,x,y,z\n0,1,2,3,4,5\n1,1,2,3,4,5\n", {}, "the header has 2 columns named 'x' (columns 3 and 4)");
  // A derived column needs both of its columns.
  CsvImportOptions derived;
  derived.columns = parseColumnMapping("x=X+dX");
  expectRefused("t,q1,X,y,z\n0,1,2,3,4\n1,1,2,3,4\n", derived, "a derived column is NAME+NAME");
}

}  // namespace
}  // namespace jointcomp
