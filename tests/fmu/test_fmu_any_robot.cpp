// An FMU of any robot (issue 39): `jointcomp export-fmu` writes the FMU of a URDF and a parameter file,
// and that FMU goes through the importer's whole sequence (instantiate, initialise, step, get/set and
// serialise the state, terminate) with its compensation reducing the links' error on the demo move. Robots:
// the shipped RX170, a 7-joint arm (tests/data/arm7), the UR10 as calibrated and as discovered from the
// IPA Series A (JOINTCOMP_SHARED); and robots an FMU cannot represent, refused at export with the reason.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "fmu/description/variable_table.hpp"
#include "tests/fmu/fmu_master.hpp"
#include "tests/support/child_process.hpp"
#include "tests/support/shared_data.hpp"

namespace jointcomp::fmutest {
namespace {

namespace fs = std::filesystem;

std::string scratchFolder(const std::string& name) {
  const std::string folder = std::string(JOINTCOMP_FMU_SCRATCH_DIR) + "/any robot/" + name;
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

// Exports and unzips an FMU of the robot; returns the unzipped folder ("" after a failed assertion).
std::string exportFmu(const std::string& name, int version, const std::vector<std::string>& robot_options) {
  const std::string scratch = scratchFolder(name + "_fmi" + std::to_string(version));
  std::vector<std::string> arguments = {JOINTCOMP_CLI, "export-fmu"};
  arguments.insert(arguments.end(), robot_options.begin(), robot_options.end());
  arguments.insert(arguments.end(), {"--fmi", std::to_string(version), "--out", scratch + "/" + name + ".fmu"});
  const test::ChildResult exported = test::runChild(arguments);
  EXPECT_EQ(exported.exit_code, 0) << exported.output;
  if (exported.exit_code != 0) return "";
  const std::string unzipped_fmu = scratch + "/unzipped";
  fs::create_directories(unzipped_fmu);
  const test::ChildResult unzipped_run =
      test::runChild({"/usr/bin/unzip", "-q", scratch + "/" + name + ".fmu", "-d", unzipped_fmu});
  EXPECT_EQ(unzipped_run.exit_code, 0) << unzipped_run.output;
  return unzipped_fmu;
}

// The demo move at 10 ms steps with the compensation mode given: the largest |q_link - q_planned| of any joint
// after the first second (the start-up transient), over `seconds`.
double demoMoveError(Master& m, int mode, double seconds) {
  EXPECT_TRUE(m.instantiate()) << m.log();
  EXPECT_EQ(m.enterInitialization(), kOK) << m.log();
  EXPECT_EQ(m.setEnumeration(m.vr("compensation"), mode), kOK) << m.log();
  EXPECT_EQ(m.exitInitialization(), kOK) << m.log();
  const std::vector<std::uint32_t> link = m.roleVrs("q_link"), planned = m.roleVrs("q_planned");
  std::vector<double> q, plan;
  double worst = 0.0, t = 0.0;
  for (int k = 0; t < seconds - 1e-9; ++k, t += 0.01) {
    if (m.doStep(t, 0.01) != kOK) {
      ADD_FAILURE() << "step at t = " << t << ":\n" << m.log();
      return NAN;
    }
    EXPECT_EQ(m.getReals(link, q), kOK);
    EXPECT_EQ(m.getReals(planned, plan), kOK);
    for (std::size_t j = 0; j < q.size() && t > 1.0; ++j) worst = std::max(worst, std::abs(q[j] - plan[j]));
  }
  return worst;
}

// The state taken at 1 s, serialised and read back, then restored after more steps: the steps after it are
// the same, bit for bit.
void expectStateRoundTrip(Master& m) {
  ASSERT_TRUE(m.instantiate()) << m.log();
  ASSERT_EQ(m.enterInitialization(), kOK);
  ASSERT_EQ(m.exitInitialization(), kOK) << m.log();
  double t = 0.0;
  for (int k = 0; k < 100; ++k, t += 0.01) ASSERT_EQ(m.doStep(t, 0.01), kOK) << m.log();
  void* state = nullptr;
  std::vector<unsigned char> bytes;
  ASSERT_EQ(m.getState(&state), kOK);
  ASSERT_EQ(m.serialize(state, bytes), kOK);
  const std::vector<std::uint32_t> link = m.roleVrs("q_link");
  std::vector<double> first, second;
  for (int k = 0; k < 20; ++k) ASSERT_EQ(m.doStep(t + 0.01 * k, 0.01), kOK);
  ASSERT_EQ(m.getReals(link, first), kOK);
  void* read_back = nullptr;
  ASSERT_EQ(m.deserialize(bytes, &read_back), kOK) << m.log();
  ASSERT_EQ(m.setState(read_back), kOK) << m.log();
  for (int k = 0; k < 20; ++k) ASSERT_EQ(m.doStep(t + 0.01 * k, 0.01), kOK);
  ASSERT_EQ(m.getReals(link, second), kOK);
  for (std::size_t j = 0; j < first.size(); ++j) EXPECT_EQ(first[j], second[j]) << "joint " << j;
  EXPECT_EQ(m.freeState(&state), kOK);
  EXPECT_EQ(m.freeState(&read_back), kOK);
  EXPECT_EQ(m.terminate(), kOK);
}

// Everything an importer does with the robot's FMU, for both FMI versions.
void expectAWorkingFmu(const std::string& name, const std::vector<std::string>& robot_options, int joints,
                       const std::vector<std::string>& joint_names) {
  for (int version : {2, 3}) {
    SCOPED_TRACE(name + ", FMI " + std::to_string(version));
    const std::string folder = exportFmu(name, version, robot_options);
    ASSERT_FALSE(folder.empty());
    const std::string schema = test::sharedFile("fmi-schema");
    if (!schema.empty() && fs::exists(schema)) {
      const test::ChildResult valid =
          test::runChild({"/usr/bin/bash", std::string(JOINTCOMP_TESTS_DIR) + "/fmu/check_schema.sh",
                          std::to_string(version), folder + "/modelDescription.xml"});
      EXPECT_EQ(valid.exit_code, 0) << valid.output;
    }
    auto without = makeMaster(version, folder);
    ASSERT_EQ(static_cast<int>(without->roleVrs("q_desired").size()), joints);
    for (const std::string& joint : joint_names) EXPECT_NO_THROW(without->vr("q_link." + joint)) << joint;
    const double error_without = demoMoveError(*without, 0, 4.0);
    auto with = makeMaster(version, folder);
    const double error_with = demoMoveError(*with, 2, 4.0);
    std::printf("%s FMI %d: demo move, largest link error %.3g rad without, %.3g rad with compensation\n", name.c_str(),
                version, error_without, error_with);
    EXPECT_GT(error_without, 1e-7) << "the robot's joints deflect on the demo move";
    EXPECT_LT(error_with, 0.5 * error_without);
    auto again = makeMaster(version, folder);
    expectStateRoundTrip(*again);
  }
}

std::string dataFile(const std::string& relative) { return std::string(JOINTCOMP_DATA_DIR) + "/" + relative; }
std::string testData(const std::string& relative) { return std::string(JOINTCOMP_TEST_DATA_DIR) + "/" + relative; }

TEST(FmuOfAnyRobot, TheShippedRx170) {
  expectAWorkingFmu("rx170", {"--urdf", dataFile("robots/rx170.urdf"), "--params", dataFile("params/rx170.json")}, 6,
                    {"joint_1", "joint_6"});
}

TEST(FmuOfAnyRobot, ASevenJointArm) {
  expectAWorkingFmu("arm7",
                    {"--urdf", testData("arm7/arm7.urdf"), "--params", testData("arm7/arm7_truth.json"), "--drives",
                     testData("fmu/arm7_drives.json")},
                    7, {"joint_1", "joint_7"});
}

// The UR10 as `calibrate` and `discover` leave it from the IPA Series A, with drives from a file of its own.
class FmuOfTheUr10 : public ::testing::Test {
protected:
  void SetUp() override {
    JOINTCOMP_REQUIRE_SHARED_FILE("the IPA UR10 Series A", "data/ipa-ur10/Series_A/measurements_grid.csv");
    // Each test its own folder: ctest runs them at once.
    scratch_ = scratchFolder(std::string("ur10_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    campaign_ = scratch_ + "/A.csv";
    const std::string series = test::sharedFile("data/ipa-ur10/Series_A");
    const test::ChildResult imported =
        test::runChild({JOINTCOMP_CLI, "import-ipa", "--in", series + "/measurements_grid.csv", "--trafo",
                        series + "/Trafo_TM_F_init.txt", "--out", campaign_});
    ASSERT_EQ(imported.exit_code, 0) << imported.output;
  }
  void expectExported(const std::string& command, const std::vector<std::string>& options) {
    const std::string out = scratch_ + "/" + command;
    std::vector<std::string> arguments = {JOINTCOMP_CLI, command,   "--urdf", dataFile("robots/ur10.urdf"),
                                          "--campaign",  campaign_, "--out",  out,
                                          "--no-plot"};
    arguments.insert(arguments.end(), options.begin(), options.end());
    const test::ChildResult fitted = test::runChild(arguments);
    ASSERT_EQ(fitted.exit_code, 0) << fitted.output;
    EXPECT_NE(fitted.output.find("export-fmu"), std::string::npos) << "the command that exports the result\n"
                                                                   << fitted.output;
    expectAWorkingFmu("ur10_" + command,
                      {"--urdf", dataFile("robots/ur10.urdf"), "--params", out + "/parameters.json", "--drives",
                       testData("fmu/ur10_compliance_and_drives.json")},
                      6, {"joint_1", "joint_6"});
  }
  std::string scratch_, campaign_;
};

TEST_F(FmuOfTheUr10, AsCalibrated) { expectExported("calibrate", {}); }
TEST_F(FmuOfTheUr10, AsDiscovered) { expectExported("discover", {"--max-steps", "2"}); }

// What an FMU cannot represent is refused at export, with the reason, and leaves no file.
TEST(FmuOfAnyRobot, ARobotTheFmuCannotRepresentIsRefusedWithTheReason) {
  const std::string scratch = scratchFolder("refused");
  struct Case {
    std::vector<std::string> options;
    std::string reason;
  };
  const std::vector<Case> cases = {
      {{"--urdf", dataFile("robots/ur10.urdf"), "--params", testData("fmu/ur10_no_plant.json")}, "plant"},
      {{"--urdf", testData("urdf/prismatic_joint.urdf"), "--params", dataFile("params/rx170.json")}, "prismatic"},
      {{"--urdf", dataFile("robots/rx170.urdf"), "--params", testData("fmu/rx170_soft_joint.json")}, "stiffness"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> arguments = {JOINTCOMP_CLI, "export-fmu"};
    arguments.insert(arguments.end(), c.options.begin(), c.options.end());
    arguments.insert(arguments.end(), {"--out", scratch + "/refused.fmu"});
    const test::ChildResult run = test::runChild(arguments);
    EXPECT_NE(run.exit_code, 0) << run.output;
    EXPECT_NE(run.output.find(c.reason), std::string::npos) << run.output;
    EXPECT_FALSE(fs::exists(scratch + "/refused.fmu"));
  }
}

}  // namespace
}  // namespace jointcomp::fmutest
