// `jointcomp export-fmu` as a user runs it (the command-line tool started from an argument vector), its FMU
// unpacked by Python's zipfile and read by independent readers: xmllint against the FMI schemas
// (JOINTCOMP_SHARED/fmi-schema), ElementTree for the variables' names and the URDF's joints. The RX170 with
// its shipped files and the UR10 with test drives, for FMI 2 and 3; robots the FMU cannot represent are
// refused with the reason and leave no file.
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "tests/support/child_process.hpp"
#include "tests/support/shared_data.hpp"

namespace {

namespace fs = std::filesystem;
using jointcomp::test::ChildResult;
using jointcomp::test::runChild;

constexpr const char* kPython = "/usr/bin/python3";
const std::string kData = JOINTCOMP_DATA_DIR;           // model/: robots/ and params/
const std::string kTestData = JOINTCOMP_TEST_DATA_DIR;  // tests/data

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// A fresh folder for one test.
std::string scratch(const std::string& name) {
  const fs::path folder = fs::path(JOINTCOMP_EXPORT_SCRATCH_DIR) / name;
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder.string();
}

std::string writeFile(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

ChildResult exportFmu(std::vector<std::string> arguments) {
  arguments.insert(arguments.begin(), {JOINTCOMP_CLI, "export-fmu"});
  return runChild(arguments, 120);
}

// Unpacks the FMU with zipfile after testzip has checked every entry's CRC; its entries' names.
std::vector<std::string> unpack(const std::string& fmu, const std::string& folder) {
  const ChildResult unzip = runChild({kPython, "-c",
                                      "import json, sys, zipfile\n"
                                      "with zipfile.ZipFile(sys.argv[1]) as z:\n"
                                      "    assert z.testzip() is None, z.testzip()\n"
                                      "    z.extractall(sys.argv[2])\n"
                                      "    print(json.dumps(z.namelist()))\n",
                                      fmu, folder});
  EXPECT_EQ(unzip.exit_code, 0) << unzip.why << unzip.output;
  return nlohmann::json::parse(unzip.output).get<std::vector<std::string>>();
}

// ElementTree's reading of modelDescription.xml: the version, the token, the variables' names.
nlohmann::json describe(const std::string& xml) {
  const ChildResult read =
      runChild({kPython, "-c",
                "import json, sys, xml.etree.ElementTree as ET\n"
                "root = ET.parse(sys.argv[1]).getroot()\n"
                "token = root.get('guid') or root.get('instantiationToken')\n"
                "names = [v.get('name') for v in root.find('ModelVariables')]\n"
                "print(json.dumps({'version': root.get('fmiVersion'), 'token': token, 'names': names}))\n",
                xml});
  EXPECT_EQ(read.exit_code, 0) << read.why << read.output;
  return nlohmann::json::parse(read.output);
}

// The URDF's moving joints, read by ElementTree (not by jointcomp).
std::vector<std::string> movingJoints(const std::string& urdf) {
  const ChildResult read = runChild({kPython, "-c",
                                     "import json, sys, xml.etree.ElementTree as ET\n"
                                     "joints = ET.parse(sys.argv[1]).getroot().findall('joint')\n"
                                     "print(json.dumps([j.get('name') for j in joints if j.get('type') != 'fixed']))\n",
                                     urdf});
  EXPECT_EQ(read.exit_code, 0) << read.why << read.output;
  return nlohmann::json::parse(read.output).get<std::vector<std::string>>();
}

// A UR10 parameter file with the compliance of the test drives' file and no "plant" object.
std::string ur10WithoutDrives(const std::string& folder) {
  nlohmann::json file = nlohmann::json::parse(readFile(kTestData + "/fmu/ur10_compliance_and_drives.json"));
  file.erase("plant");
  return writeFile(folder + "/ur10_no_drives.json", file.dump(2));
}

struct Case {
  std::string robot;
  int fmi;
};

class ExportFmu : public ::testing::TestWithParam<Case> {
protected:
  // Exports the case's robot into a scratch folder; the FMU's path.
  std::string exportCase(const std::string& folder) {
    const Case& c = GetParam();
    urdf_ = kData + "/robots/" + c.robot + ".urdf";
    std::vector<std::string> arguments = {"--urdf", urdf_, "--fmi", std::to_string(c.fmi)};
    if (c.robot == "rx170") {
      params_ = kData + "/params/rx170.json";
      arguments.insert(arguments.end(), {"--params", params_});
    } else {  // the UR10 ships no drives: they come with --drives
      params_ = ur10WithoutDrives(folder);
      arguments.insert(arguments.end(),
                       {"--params", params_, "--drives", kTestData + "/fmu/ur10_compliance_and_drives.json"});
    }
    const std::string fmu = folder + "/" + c.robot + ".fmu";
    arguments.insert(arguments.end(), {"--out", fmu});
    const ChildResult run = exportFmu(arguments);
    EXPECT_EQ(run.exit_code, 0) << run.why << run.output;
    EXPECT_NE(run.output.find("wrote " + fmu), std::string::npos) << run.output;
    return fmu;
  }
  std::string urdf_, params_;
};

TEST_P(ExportFmu, PacksTheRobotWithTheBinaryOfItsVersion) {
  const Case& c = GetParam();
  const std::string folder = scratch(c.robot + "_fmi" + std::to_string(c.fmi) + "_layout");
  const std::string fmu = exportCase(folder);
  const std::vector<std::string> names = unpack(fmu, folder + "/unpacked");
  const std::string platform = c.fmi == 2 ? "linux64" : "x86_64-linux";
  const std::set<std::string> files(names.begin(), names.end());
  for (const std::string& expected :
       {std::string("modelDescription.xml"), "binaries/" + platform + "/jointcomp.so",
        std::string("resources/robot.json"), std::string("resources/parameters.json"), "resources/" + c.robot + ".urdf",
        std::string("documentation/index.html"), std::string("documentation/variables.html"),
        std::string("documentation/licenses/LICENSE.txt")})
    EXPECT_TRUE(files.count(expected)) << expected << " is missing";
  const std::string unpacked = folder + "/unpacked/";
  EXPECT_EQ(readFile(unpacked + "resources/" + c.robot + ".urdf"), readFile(urdf_));
  const nlohmann::json parameters = nlohmann::json::parse(readFile(unpacked + "resources/parameters.json"));
  EXPECT_TRUE(parameters.contains("plant"));  // the FMU's plant needs drives
  if (c.robot == "rx170") {                   // a parameter file with drives travels byte for byte
    EXPECT_EQ(readFile(unpacked + "resources/parameters.json"), readFile(params_));
  } else {  // the test drives joined to the file without them
    EXPECT_EQ(parameters["plant"],
              nlohmann::json::parse(readFile(kTestData + "/fmu/ur10_compliance_and_drives.json"))["plant"]);
    EXPECT_EQ(parameters["effects"], nlohmann::json::parse(readFile(params_))["effects"]);
  }
  const std::string binary = readFile(unpacked + "binaries/" + platform + "/jointcomp.so");
  ASSERT_GT(binary.size(), 4u);
  EXPECT_EQ(binary.substr(0, 4),
            "\x7f"
            "ELF");
}

TEST_P(ExportFmu, NamesTheVariablesAfterTheUrdfsJoints) {
  const Case& c = GetParam();
  const std::string folder = scratch(c.robot + "_fmi" + std::to_string(c.fmi) + "_names");
  unpack(exportCase(folder), folder + "/unpacked");
  const nlohmann::json xml = describe(folder + "/unpacked/modelDescription.xml");
  EXPECT_EQ(xml["version"], c.fmi == 2 ? "2.0" : "3.0");
  const std::vector<std::string> names = xml["names"].get<std::vector<std::string>>();
  const std::set<std::string> variables(names.begin(), names.end());
  EXPECT_EQ(variables.size(), names.size()) << "a variable name appears twice";
  const std::vector<std::string> joints = movingJoints(urdf_);
  ASSERT_EQ(joints.size(), 6u);
  for (const std::string& joint : joints) {
    for (const std::string role : {"q_desired.", "q_ref.", "q_link."})
      EXPECT_TRUE(variables.count(role + joint)) << role + joint << " is not a variable";
  }
}

TEST_P(ExportFmu, ValidatesAgainstTheFmiSchema) {
  const Case& c = GetParam();
  const std::string schema =
      "fmi-schema/fmi" + std::to_string(c.fmi) + "/fmi" + std::to_string(c.fmi) + "ModelDescription.xsd";
  JOINTCOMP_REQUIRE_SHARED_FILE("the FMI schema", schema);
  const std::string folder = scratch(c.robot + "_fmi" + std::to_string(c.fmi) + "_schema");
  unpack(exportCase(folder), folder + "/unpacked");
  const ChildResult lint = runChild({"/usr/bin/xmllint", "--noout", "--schema", jointcomp::test::sharedFile(schema),
                                     folder + "/unpacked/modelDescription.xml"});
  EXPECT_EQ(lint.exit_code, 0) << lint.why << lint.output;
}

TEST_P(ExportFmu, TheSameInputsGiveTheSameBytes) {
  const Case& c = GetParam();
  const std::string first = readFile(exportCase(scratch(c.robot + "_fmi" + std::to_string(c.fmi) + "_first")));
  const std::string second = readFile(exportCase(scratch(c.robot + "_fmi" + std::to_string(c.fmi) + "_second")));
  EXPECT_FALSE(first.empty());
  EXPECT_TRUE(first == second) << "two exports of the same files differ";
}

INSTANTIATE_TEST_SUITE_P(Robots, ExportFmu,
                         ::testing::Values(Case{"rx170", 2}, Case{"rx170", 3}, Case{"ur10", 2}, Case{"ur10", 3}),
                         [](const ::testing::TestParamInfo<Case>& param) {
                           return param.param.robot + "_fmi" + std::to_string(param.param.fmi);
                         });

// The token stands for the robot and its parameters, whatever the FMI version.
TEST(ExportFmuToken, IsTheSameForBothVersionsAndDiffersBetweenRobots) {
  const std::string folder = scratch("token");
  std::vector<std::string> tokens;
  for (const std::string version : {"2", "3"}) {
    for (const std::string robot : {"rx170", "ur10"}) {
      const std::string params =
          robot == "rx170" ? kData + "/params/rx170.json" : kTestData + "/fmu/ur10_compliance_and_drives.json";
      const std::string fmu = folder + "/" + robot + version + ".fmu";
      const ChildResult run = exportFmu(
          {"--urdf", kData + "/robots/" + robot + ".urdf", "--params", params, "--fmi", version, "--out", fmu});
      ASSERT_EQ(run.exit_code, 0) << run.why << run.output;
      unpack(fmu, folder + "/" + robot + version);
      tokens.push_back(describe(folder + "/" + robot + version + "/modelDescription.xml")["token"]);
    }
  }
  EXPECT_EQ(tokens[0], tokens[2]);  // rx170, FMI 2 and 3
  EXPECT_EQ(tokens[1], tokens[3]);  // ur10
  EXPECT_NE(tokens[0], tokens[1]);
}

// Without --drives, a parameter file without drives takes those of the shipped file of its robot's name.
TEST(ExportFmuDrives, DefaultToTheShippedParameterFileOfTheRobot) {
  const std::string folder = scratch("default_drives");
  nlohmann::ordered_json rx170 = nlohmann::ordered_json::parse(readFile(kData + "/params/rx170.json"));
  const nlohmann::ordered_json plant = rx170["plant"];
  rx170.erase("plant");
  const std::string params = writeFile(folder + "/rx170_no_drives.json", rx170.dump(2));
  const ChildResult run =
      exportFmu({"--urdf", kData + "/robots/rx170.urdf", "--params", params, "--out", folder + "/rx170.fmu"});
  ASSERT_EQ(run.exit_code, 0) << run.why << run.output;
  unpack(folder + "/rx170.fmu", folder + "/unpacked");
  const nlohmann::ordered_json packed =
      nlohmann::ordered_json::parse(readFile(folder + "/unpacked/resources/parameters.json"));
  EXPECT_EQ(packed["plant"], plant);
  EXPECT_EQ(packed["effects"], rx170["effects"]);
}

// The words of a printed command line as a shell splits them (plain words and '...' quoting, which is all
// the hint uses).
std::vector<std::string> shellWords(const std::string& line) {
  std::vector<std::string> words;
  std::string word;
  bool quoted = false, any = false;
  for (const char c : line) {
    if (c == '\'') {
      quoted = !quoted;
      any = true;
    } else if (c == ' ' && !quoted) {
      if (any) words.push_back(word);
      word.clear();
      any = false;
    } else {
      word += c;
      any = true;
    }
  }
  if (any) words.push_back(word);
  return words;
}

// calibrate and discover print the export-fmu command of their result; run as printed (with the drives
// file the note asks for), it exports. The seven-joint test arm, whose parameter file has no drives.
class ExportFmuHint : public ::testing::TestWithParam<std::string> {};

TEST_P(ExportFmuHint, RunAsPrintedItExportsTheResult) {
  const std::string command = GetParam();
  const std::string folder = scratch("hint_" + command) + "/out dir";  // a space, so the command quotes
  std::vector<std::string> arguments = {JOINTCOMP_CLI, command,
                                        "--urdf",      kTestData + "/arm7/arm7.urdf",
                                        "--params",    kTestData + "/arm7/arm7.json",
                                        "--campaign",  kTestData + "/arm7/campaign_fit.csv",
                                        "--out",       folder,
                                        "--no-plot",   "--quiet"};
  if (command == "discover") arguments.insert(arguments.end(), {"--max-steps", "1"});
  const ChildResult fitted = runChild(arguments, 240);
  ASSERT_EQ(fitted.exit_code, 0) << fitted.why << fitted.output;
  const std::string marker = "as an FMU: ";
  const std::size_t at = fitted.output.find(marker);
  ASSERT_NE(at, std::string::npos) << fitted.output;
  const std::size_t end = fitted.output.find('\n', at);
  std::vector<std::string> words = shellWords(fitted.output.substr(at + marker.size(), end - at - marker.size()));
  ASSERT_GE(words.size(), 2u);
  ASSERT_EQ(words[0], "jointcomp");
  ASSERT_EQ(words[1], "export-fmu");
  EXPECT_NE(fitted.output.find("no drives", end), std::string::npos) << "the note on the missing drives";
  words[0] = JOINTCOMP_CLI;
  for (std::string& word : words) {
    if (word == "DRIVES.json") word = kTestData + "/fmu/arm7_drives.json";
  }
  const ChildResult exported = runChild(words, 120);
  EXPECT_EQ(exported.exit_code, 0) << exported.why << exported.output;
  EXPECT_TRUE(fs::exists(folder + "/arm7.fmu")) << exported.output;
}

INSTANTIATE_TEST_SUITE_P(Commands, ExportFmuHint, ::testing::Values("calibrate", "discover"));

// What the FMU cannot represent is refused with the reason, exit status 1 (2 for a command line), no file.
TEST(ExportFmuRefuses, WhatTheFmuCannotRepresentWithTheReason) {
  const std::string folder = scratch("refused");
  const std::string fmu = folder + "/refused.fmu";
  const std::string ur10 = kData + "/robots/ur10.urdf";
  const auto refused = [&](const std::vector<std::string>& arguments, int status,
                           const std::vector<std::string>& says) {
    const ChildResult run = exportFmu(arguments);
    EXPECT_EQ(run.exit_code, status) << run.why << run.output;
    for (const std::string& text : says) EXPECT_NE(run.output.find(text), std::string::npos) << run.output;
    EXPECT_FALSE(fs::exists(fmu)) << "a refused export left " << fmu;
  };
  // A parameter file without drives, and none shipped for the UR10.
  const std::string no_drives = ur10WithoutDrives(folder);
  refused({"--urdf", ur10, "--params", no_drives, "--out", fmu}, 1, {"no drives", "\"plant\"", "--drives"});
  // --drives with a file that has none either.
  refused({"--urdf", ur10, "--params", no_drives, "--drives", no_drives, "--out", fmu}, 1, {"no \"plant\" object"});
  // --drives beside a parameter file with drives of its own: which would the FMU use?
  const std::string drives = kTestData + "/fmu/ur10_compliance_and_drives.json";
  refused({"--urdf", ur10, "--params", drives, "--drives", drives, "--out", fmu}, 1, {"drives of its own"});
  // A URDF without a moving joint.
  const std::string statue = writeFile(folder + "/statue.urdf",
                                       "<robot name=\"statue\"><link name=\"base\"/><link name=\"top\"/>"
                                       "<joint name=\"weld\" type=\"fixed\"><parent link=\"base\"/>"
                                       "<child link=\"top\"/></joint></robot>\n");
  refused({"--urdf", statue, "--params", drives, "--out", fmu}, 1, {"statue.urdf", "no revolute joint"});
  // Checked before any work: the name, the version.
  refused({"--urdf", ur10, "--params", drives, "--out", folder + "/robot.zip"}, 2, {"does not end in .fmu"});
  refused({"--urdf", ur10, "--params", drives, "--fmi", "4", "--out", fmu}, 2, {"--fmi"});
  refused({"--urdf", ur10, "--out", fmu}, 2, {"--params"});
}

}  // namespace
