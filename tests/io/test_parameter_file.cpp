// Parameter files: the shipped RX170 file loads with the values it holds (read back independently as
// plain JSON), survives write -> read bit for bit, and every kind of broken file gives a ParameterError
// whose message names the file and the JSON path of the field at fault. Broken files are a few committed
// ones (tests/data/params) plus a table of edits of the good file.
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/effects/compliance.hpp"
#include "model/effects/periodic_table.hpp"
#include "model/effects/registry.hpp"
#include "model/effects/spring_balancer.hpp"
#include "model/effects/transmission_error.hpp"
#include "model/io/atomic_file.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

std::string rx170ParametersPath() { return std::string(JOINTCOMP_DATA_DIR) + "/params/rx170.json"; }
std::string brokenFile(const std::string& name) { return std::string(JOINTCOMP_TEST_DATA_DIR) + "/params/" + name; }

std::shared_ptr<const Robot> rx170() {
  static const std::shared_ptr<const Robot> robot =
      std::make_shared<const Robot>(loadRobotFromUrdfFile(std::string(JOINTCOMP_DATA_DIR) + "/robots/rx170.urdf"));
  return robot;
}

std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

nlohmann::json goodJson() { return nlohmann::json::parse(readText(rx170ParametersPath())); }

bool bitIdentical(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

// Everything a model holds, compared exactly.
void expectSameModel(const JointErrorModel& a, const JointErrorModel& b) {
  EXPECT_EQ(a.notes, b.notes);
  ASSERT_EQ(a.gears().dof(), b.gears().dof());
  for (int j = 0; j < a.gears().dof(); ++j) {
    EXPECT_TRUE(bitIdentical(a.gears().stageRatios(j), b.gears().stageRatios(j))) << "joint " << j;
  }
  EXPECT_EQ(a.gears().motorFromJoint(), b.gears().motorFromJoint());
  ASSERT_EQ(a.effectCount(), b.effectCount());
  for (int i = 0; i < a.effectCount(); ++i) {
    EXPECT_EQ(a.effect(i).type(), b.effect(i).type());
    EXPECT_EQ(a.effect(i).parameterNames(), b.effect(i).parameterNames());
    const std::vector<double> pa = a.effect(i).parameters();
    const std::vector<double> pb = b.effect(i).parameters();
    EXPECT_TRUE(bitIdentical(pa, pb)) << a.effect(i).type();
    for (std::size_t k = 0; k < pa.size() && k < pb.size(); ++k) {
      if (pa[k] != pb[k]) {
        ADD_FAILURE() << a.effect(i).parameterNames()[k] << ": " << std::hexfloat << pa[k] << " became " << pb[k];
      }
    }
    EXPECT_EQ(a.effect(i).estimate_note, b.effect(i).estimate_note);
  }
}

// ---- the shipped file ------------------------------------------------------------------------------

TEST(ParameterFile, Rx170LoadsWithTheValuesOfTheFile) {
  const JointErrorModel model = loadParameterFile(rx170ParametersPath(), rx170());
  const nlohmann::json file = goodJson();
  ASSERT_EQ(model.effectCount(), 3);
  EXPECT_EQ(model.effect(0).type(), "compliance");
  EXPECT_EQ(model.effect(1).type(), "spring_balancer");
  EXPECT_EQ(model.effect(2).type(), "transmission_error");
  EXPECT_EQ(model.notes, file.at("notes").get<std::string>());
  const nlohmann::json& joints = file.at("gears").at("joints");
  ASSERT_EQ(static_cast<int>(joints.size()), model.robot().dof());
  for (int j = 0; j < model.robot().dof(); ++j) {
    const std::vector<double> ratios = joints[j].at("stage_ratios").get<std::vector<double>>();
    EXPECT_EQ(model.gears().stageRatios(j), ratios) << "joint " << j;
    double total = 1.0;
    for (double r : ratios) total *= r;
    EXPECT_EQ(model.gears().totalRatio(j), total) << "joint " << j;
  }
  // The one coupling: motor 6 from joint 5.
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      if (r == c) continue;
      const double expected =
          (r == 5 && c == 4) ? file.at("gears").at("coupling")[0].at("motor_rad_per_joint_rad").get<double>() : 0.0;
      EXPECT_EQ(model.gears().motorFromJoint()(r, c), expected) << r << "," << c;
    }
  }
  EXPECT_EQ(model.effect(0).parameters(), file.at("effects")[0].at("stiffness_nm_per_rad").get<std::vector<double>>());
  const nlohmann::json& spring = file.at("effects")[1];
  EXPECT_EQ(model.effect(1).parameters(),
            (std::vector<double>{spring.at("anchor_distance_before_m"), spring.at("anchor_distance_after_m"),
                                 spring.at("angle_at_zero_rad"), spring.at("stiffness_n_per_m"),
                                 spring.at("free_length_m"), spring.at("preload_n")}));
  EXPECT_EQ(model.effect(1).estimate_note, spring.at("estimate").get<std::string>());
  const nlohmann::json& harmonics = file.at("effects")[2].at("harmonics");
  const std::vector<double> te = model.effect(2).parameters();
  ASSERT_EQ(te.size(), 2 * harmonics.size());
  for (std::size_t i = 0; i < harmonics.size(); ++i) {
    const double degrees = harmonics[i].at("amplitude_deg").get<double>();
    EXPECT_NEAR(te[2 * i], degrees * 3.14159265358979323846 / 180.0, 1e-20) << "harmonic " << i;
    EXPECT_EQ(te[2 * i + 1], harmonics[i].at("phase_rad").get<double>()) << "harmonic " << i;
  }
}

TEST(ParameterFile, MinimalFileHasDirectGearsAndNoEffects) {
  const JointErrorModel model = loadParameterFile(brokenFile("minimal.json"), rx170());
  EXPECT_EQ(model.effectCount(), 0);
  EXPECT_EQ(model.gears().motorFromJoint(), JointMatrix::Identity(6, 6));
  EXPECT_EQ(model.notes, "");
}

TEST(ParameterFile, RoundTripsBitForBit) {
  const JointErrorModel original = loadParameterFile(rx170ParametersPath(), rx170());
  const std::string text = parametersToJson(original);
  const JointErrorModel again = parseParameters(text, "round trip", rx170());
  expectSameModel(original, again);
  // And the text is a fixed point: writing what was read gives the same text.
  EXPECT_EQ(parametersToJson(again), text);
}

// A result that is not finite is never written (nlohmann would write NaN as null, which reads back as a
// rigid joint or fails far from the fit that made it): the writer names the value and writes nothing.
TEST(ParameterFile, ANonFiniteResultIsNotWritten) {
  const JointErrorModel model = loadParameterFile(rx170ParametersPath(), rx170());
  std::vector<DriveParameters> drives = loadDriveParameters(rx170ParametersPath(), *rx170());
  drives[1].kp_nm_per_rad = std::nan("");
  const std::string path = ::testing::TempDir() + "/jointcomp_not_finite.json";
  std::filesystem::remove(path);
  try {
    saveParameterFile(model, path, drives);
    ADD_FAILURE() << "a NaN drive gain was written";
  } catch (const ParameterError& error) {
    EXPECT_THAT(error.what(), ::testing::HasSubstr("parameters.plant.joints[1].kp_nm_per_rad is nan"));
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  drives[1].kp_nm_per_rad = 1e5;
  saveParameterFile(model, path, drives);  // with a finite gain the same set is written
  EXPECT_TRUE(std::filesystem::exists(path));
  std::filesystem::remove(path);
}

TEST(ParameterFile, RoundTripsArbitraryValuesBitForBit) {
  // Values with all 53 bits in use, so that any lossy conversion on the way shows.
  JointErrorModel model = loadParameterFile(rx170ParametersPath(), rx170());
  for (int i = 0; i < model.effectCount(); ++i) {
    std::vector<double> values = model.effect(i).parameters();
    for (std::size_t k = 0; k < values.size(); ++k)
      values[k] = (values[k] + 0.01) * (1.0 + std::sqrt(2.0) * 1e-3 * (k + 1));  // within the reader's ranges
    model.effect(i).setParameters(values);
  }
  const JointErrorModel again = parseParameters(parametersToJson(model), "round trip", rx170());
  expectSameModel(model, again);
}

// The reader's 0.1 rad bound on a stated joint error (kMaxStatedJointError) holds for every way an effect
// gets its values: a harmonic and a table at the bound are written and read back bit for bit; one ulp
// beyond it no effect takes (a fit reaching it is refused, naming the effect, the joint and the part).
TEST(ParameterFile, ValuesAtTheStatedJointErrorBoundRoundTripAndBeyondItAreRefused) {
  JointErrorModel model = loadParameterFile(rx170ParametersPath(), rx170());
  const double bound = kMaxStatedJointError;
  model.addEffect(std::make_unique<TransmissionErrorEffect>(
      *rx170(), model.gears(), std::vector<Harmonic>{{2, 1, 3.0, bound, -0.25}, {3, 1, 2.0, 0.0, 1.0}}));
  model.addEffect(std::make_unique<PeriodicTableEffect>(
      *rx170(), model.gears(), std::vector<PeriodicTable>{{4, 1, {bound, -bound, 0.5 * bound, 0.0}}}));
  const JointErrorModel again = parseParameters(parametersToJson(model), "at the bound", rx170());
  expectSameModel(model, again);

  const double beyond = std::nextafter(bound, 1.0);
  Effect& harmonics = model.effect(model.effectCount() - 2);
  std::vector<double> values = harmonics.parameters();
  values[0] = beyond;
  try {
    harmonics.setParameters(values);
    ADD_FAILURE() << "a harmonic beyond the bound was taken";
  } catch (const ParameterError& error) {
    EXPECT_THAT(error.what(), HasSubstr("transmission_error: joint_3.harmonic_motor_x3.amplitude_rad is 0.1 rad, "
                                        "beyond the plausible +-0.1 rad"));
  }
  values[0] = -beyond;
  EXPECT_THROW(harmonics.setParameters(values), ParameterError);
  Effect& table = model.effect(model.effectCount() - 1);
  values = table.parameters();
  values[1] = -beyond;
  try {
    table.setParameters(values);
    ADD_FAILURE() << "a table coefficient beyond the bound was taken";
  } catch (const ParameterError& error) {
    EXPECT_THAT(error.what(), HasSubstr("periodic_table: joint_5.periodic_motor.c1_rad is -0.1 rad, beyond"));
  }
  // A refused value leaves the effect as it was, and it still writes a file that reads back.
  expectSameModel(model, parseParameters(parametersToJson(model), "after refusals", rx170()));

  // A negative amplitude (a Monte Carlo draw) is the harmonic turned by pi: written so, as the reader wants
  // amplitudes, and the same joint error read back.
  values = harmonics.parameters();
  values[0] = -0.5 * bound;
  harmonics.setParameters(values);
  const JointErrorModel turned = parseParameters(parametersToJson(model), "negative amplitude", rx170());
  const Effect& reread = turned.effect(turned.effectCount() - 2);
  EXPECT_EQ(reread.parameters()[0], 0.5 * bound);
  EXPECT_NEAR(reread.parameters()[1], -0.25 + 3.14159265358979323846, 1e-15);
  JointContext ctx(6);
  for (double angle : {0.0, 0.3, 1.7, -2.9}) {
    ctx.motor = JointVector::Constant(6, angle);
    JointVector written = JointVector::Zero(6), read = JointVector::Zero(6);
    harmonics.addJointError(*rx170(), ctx, written);
    reread.addJointError(*rx170(), ctx, read);
    EXPECT_NEAR((written - read).norm(), 0.0, 1e-15) << angle;
    EXPECT_GT(std::abs(written[2]), 0.0) << angle;
  }
}

// No command writes a file its own reader refuses: what the writer would write goes through the reader first
// (here one compliance listed twice, which the reader refuses as summed), and nothing is written.
TEST(ParameterFile, AFileItsReaderWouldRefuseIsNotWritten) {
  JointErrorModel model = loadParameterFile(rx170ParametersPath(), rx170());
  const int springs = model.jointSprings();
  ASSERT_GE(springs, 0);
  model.addEffect(model.effect(springs).clone());
  const std::string path = ::testing::TempDir() + "/jointcomp_refused_by_reader.json";
  std::filesystem::remove(path);
  try {
    saveParameterFile(model, path);
    ADD_FAILURE() << "a file the reader refuses was written";
  } catch (const ParameterError& error) {
    EXPECT_THAT(error.what(), HasSubstr("refusing to write a parameter file its own reader refuses"));
    EXPECT_THAT(error.what(), HasSubstr("list each effect of a joint once"));
  }
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(ParameterFile, SaveWritesAFileThatLoadsBack) {
  const JointErrorModel original = loadParameterFile(rx170ParametersPath(), rx170());
  const std::filesystem::path directory = std::filesystem::path(::testing::TempDir()) / "jointcomp_parameter_file_test";
  std::filesystem::create_directories(directory);
  const std::string path = (directory / "saved_rx170.json").string();
  std::filesystem::remove(path);
  saveParameterFile(original, path);
  ASSERT_TRUE(std::filesystem::exists(path));
  const JointErrorModel loaded = loadParameterFile(path, rx170());
  expectSameModel(original, loaded);
  EXPECT_EQ(readText(path), parametersToJson(original));
  // Saving again over the file replaces it whole.
  JointErrorModel changed = original;
  std::vector<double> k = changed.effect(0).parameters();
  k[1] = 777777.0;
  changed.effect(0).setParameters(k);
  saveParameterFile(changed, path);
  EXPECT_EQ(loadParameterFile(path, rx170()).effect(0).parameters()[1], 777777.0);
  // No temporary files are left beside it.
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(directory)) {
    (void)entry;
    ++files;
  }
  EXPECT_EQ(files, 1);
  std::filesystem::remove_all(directory);
}

TEST(ParameterFile, MissingFileNamesIt) {
  const std::string path = brokenFile("there_is_no_such_file.json");
  try {
    loadParameterFile(path, rx170());
    FAIL() << "loaded a file that does not exist";
  } catch (const ParameterError& error) {
    EXPECT_THAT(error.what(), HasSubstr("there_is_no_such_file.json"));
  }
}

// ---- committed broken files ------------------------------------------------------------------------

struct BrokenFile {
  const char* file;
  const char* path;  // JSON path of the field at fault; "" when there is none (malformed JSON)
  const char* also;  // something else the message must say
};

// Test names in gtest's output instead of a byte dump.
void PrintTo(const BrokenFile& c, std::ostream* os) { *os << c.file; }

class CommittedBrokenFile : public ::testing::TestWithParam<BrokenFile> {};

TEST_P(CommittedBrokenFile, GivesParameterErrorNamingFileAndField) {
  const BrokenFile& c = GetParam();
  const std::string file = brokenFile(c.file);
  try {
    loadParameterFile(file, rx170());
    FAIL() << c.file << " was accepted";
  } catch (const ParameterError& error) {
    const std::string message = error.what();
    EXPECT_THAT(message, HasSubstr(file));
    if (*c.path != '\0') {
      EXPECT_THAT(message, HasSubstr(file + ": " + c.path));
    }
    EXPECT_THAT(message, HasSubstr(c.also));
  } catch (const std::exception& error) {
    FAIL() << c.file << " threw something else than ParameterError: " << error.what();
  }
}

INSTANTIATE_TEST_SUITE_P(Files, CommittedBrokenFile,
                         ::testing::Values(BrokenFile{"truncated.json", "", "JSON"},
                                           BrokenFile{"huge_number.json", "", "1e400"},
                                           BrokenFile{"unknown_top_level_key.json", "colour", "unknown"},
                                           BrokenFile{"wrong_format.json", "format", "jointcomp-parameters/1"},
                                           BrokenFile{"robot_mismatch.json", "robot", "rx160"}),
                         [](const ::testing::TestParamInfo<BrokenFile>& param_info) {
                           std::string name = param_info.param.file;
                           return name.substr(0, name.find('.'));
                         });

// ---- edits of the good file ------------------------------------------------------------------------

struct Edit {
  const char* name;
  std::function<void(nlohmann::json&)> apply;
  const char* path;  // expected JSON path in the message
};

// A periodic table of joint 2's output with one coefficient of `value` rad.
nlohmann::json tableOf(double value) {
  return {{"type", "periodic_table"},
          {"tables", {{{"joint", "joint_2"}, {"of", "output"}, {"coefficients_rad", {0.0, value, 0.0, 0.0}}}}}};
}

std::vector<Edit> edits() {
  using nlohmann::json;
  return {
      {"UnknownKeyInEffect", [](json& j) { j["effects"][1]["lever_m"] = 0.2; }, "effects[1].lever_m"},
      {"UnknownKeyInHarmonic", [](json& j) { j["effects"][2]["harmonics"][1]["order"] = 2; },
       "effects[2].harmonics[1].order"},
      {"UnknownKeyInGearJoint", [](json& j) { j["gears"]["joints"][0]["backlash_deg"] = 0.01; },
       "gears.joints[0].backlash_deg"},
      {"UnknownKeyInGears", [](json& j) { j["gears"]["efficiency"] = 0.9; }, "gears.efficiency"},
      {"MissingPreload", [](json& j) { j["effects"][1].erase("preload_n"); }, "effects[1].preload_n"},
      {"MissingPhase", [](json& j) { j["effects"][2]["harmonics"][3].erase("phase_rad"); },
       "effects[2].harmonics[3].phase_rad"},
      {"MissingStiffnesses", [](json& j) { j["effects"][0].erase("stiffness_nm_per_rad"); },
       "effects[0].stiffness_nm_per_rad"},
      {"MissingEffects", [](json& j) { j.erase("effects"); }, "effects"},
      {"MissingFormat", [](json& j) { j.erase("format"); }, "format"},
      {"MissingRobot", [](json& j) { j.erase("robot"); }, "robot"},
      {"MissingEffectType", [](json& j) { j["effects"][1].erase("type"); }, "effects[1].type"},
      {"StiffnessIsText", [](json& j) { j["effects"][0]["stiffness_nm_per_rad"][2] = "stiff"; },
       "effects[0].stiffness_nm_per_rad[2]"},
      {"StiffnessesNotAnArray", [](json& j) { j["effects"][0]["stiffness_nm_per_rad"] = 5000.0; },
       "effects[0].stiffness_nm_per_rad"},
      {"PreloadIsText", [](json& j) { j["effects"][1]["preload_n"] = "100"; }, "effects[1].preload_n"},
      {"AmplitudeIsBoolean", [](json& j) { j["effects"][2]["harmonics"][0]["amplitude_deg"] = true; },
       "effects[2].harmonics[0].amplitude_deg"},
      {"PhaseIsNull", [](json& j) { j["effects"][2]["harmonics"][2]["phase_rad"] = nullptr; },
       "effects[2].harmonics[2].phase_rad"},
      {"StageRatiosNotAnArray", [](json& j) { j["gears"]["joints"][1]["stage_ratios"] = 120.0; },
       "gears.joints[1].stage_ratios"},
      {"EffectsIsAnObject", [](json& j) { j["effects"] = json::object(); }, "effects"},
      {"EffectIsANumber", [](json& j) { j["effects"][1] = 3; }, "effects[1]"},
      {"NotesIsANumber", [](json& j) { j["notes"] = 12; }, "notes"},
      {"ZeroStiffness", [](json& j) { j["effects"][0]["stiffness_nm_per_rad"][4] = 0.0; },
       "effects[0].stiffness_nm_per_rad[4]"},
      {"NegativeStiffness", [](json& j) { j["effects"][0]["stiffness_nm_per_rad"][1] = -850000.0; },
       "effects[0].stiffness_nm_per_rad[1]"},
      {"NegativeSpringStiffness", [](json& j) { j["effects"][1]["stiffness_n_per_m"] = -20000.0; },
       "effects[1].stiffness_n_per_m"},
      {"ZeroAnchorDistance", [](json& j) { j["effects"][1]["anchor_distance_before_m"] = 0.0; },
       "effects[1].anchor_distance_before_m"},
      {"NegativeAmplitude", [](json& j) { j["effects"][2]["harmonics"][1]["amplitude_deg"] = -0.004; },
       "effects[2].harmonics[1].amplitude_deg"},
      {"ZeroCycles", [](json& j) { j["effects"][2]["harmonics"][0]["cycles_per_revolution"] = 0; },
       "effects[2].harmonics[0].cycles_per_revolution"},
      {"ZeroGearRatio", [](json& j) { j["gears"]["joints"][2]["stage_ratios"][1] = 0.0; },
       "gears.joints[2].stage_ratios[1]"},
      {"FiveStiffnesses", [](json& j) { j["effects"][0]["stiffness_nm_per_rad"].erase(5); },
       "effects[0].stiffness_nm_per_rad"},
      {"SevenStiffnesses", [](json& j) { j["effects"][0]["stiffness_nm_per_rad"].push_back(1000.0); },
       "effects[0].stiffness_nm_per_rad"},
      {"FiveGearJoints", [](json& j) { j["gears"]["joints"].erase(5); }, "gears.joints"},
      {"RobotNameMismatch", [](json& j) { j["robot"] = "rx160"; }, "robot"},
      {"WrongFormat", [](json& j) { j["format"] = "jointcomp-parameters/0"; }, "format"},
      {"FormatNotAString", [](json& j) { j["format"] = 1; }, "format"},
      {"UnknownEffectType", [](json& j) { j["effects"][1]["type"] = "friction"; }, "effects[1].type"},
      {"UnknownSpringJoint", [](json& j) { j["effects"][1]["joint"] = "joint_9"; }, "effects[1].joint"},
      {"UnknownHarmonicJoint", [](json& j) { j["effects"][2]["harmonics"][2]["joint"] = "wrist"; },
       "effects[2].harmonics[2].joint"},
      {"UnknownCouplingMotor", [](json& j) { j["gears"]["coupling"][0]["motor_of"] = "joint_7"; },
       "gears.coupling[0].motor_of"},
      {"UnknownCouplingJoint", [](json& j) { j["gears"]["coupling"][0]["joint"] = "joint_0"; },
       "gears.coupling[0].joint"},
      {"GearJointOutOfOrder", [](json& j) { j["gears"]["joints"][0]["joint"] = "joint_2"; }, "gears.joints[0].joint"},
      {"OfStageBeyondTheTrain", [](json& j) { j["effects"][2]["harmonics"][0]["of"] = "stage_3"; },
       "effects[2].harmonics[0].of"},
      {"OfStageZero", [](json& j) { j["effects"][2]["harmonics"][1]["of"] = "stage_0"; }, "effects[2].harmonics[1].of"},
      {"OfUnknownPart", [](json& j) { j["effects"][2]["harmonics"][2]["of"] = "gearbox"; },
       "effects[2].harmonics[2].of"},
      {"OfStageWithoutNumber", [](json& j) { j["effects"][2]["harmonics"][3]["of"] = "stage_"; },
       "effects[2].harmonics[3].of"},
      {"OfStageWithTrailingText", [](json& j) { j["effects"][2]["harmonics"][3]["of"] = "stage_2b"; },
       "effects[2].harmonics[3].of"},
      {"OfStageNegative", [](json& j) { j["effects"][2]["harmonics"][3]["of"] = "stage_-1"; },
       "effects[2].harmonics[3].of"},
      {"OfStageHuge", [](json& j) { j["effects"][2]["harmonics"][3]["of"] = "stage_99999999999999999999"; },
       "effects[2].harmonics[3].of"},
      {"OfSingleStageJointStage2",
       [](json& j) {
         j["effects"][2]["harmonics"][0]["joint"] = "joint_4";  // one stage: stage_2 is its output, named "output"
       },
       "effects[2].harmonics[0].of"},
      // Values no robot has, and one quantity stated twice (summed silently before): issue 41.
      {"HarmonicOf1e300Degrees", [](json& j) { j["effects"][2]["harmonics"][1]["amplitude_deg"] = 1e300; },
       "effects[2].harmonics[1].amplitude_deg"},
      {"TableOf1e300Rad", [](json& j) { j["effects"].push_back(tableOf(1e300)); },
       "effects[3].tables[0].coefficients_rad"},
      {"ComplianceListedTwice", [](json& j) { j["effects"].push_back(j["effects"][0]); }, "effects[3]"},
      {"HarmonicListedTwice", [](json& j) { j["effects"][2]["harmonics"].push_back(j["effects"][2]["harmonics"][0]); },
       "effects[2]"},
      {"TableListedTwice",
       [](json& j) {
         j["effects"].push_back(tableOf(0.001));
         j["effects"].push_back(tableOf(0.002));
       },
       "effects[4]"},
  };
}

TEST(ParameterFileEdits, TheUneditedFileParses) {
  // The edits below start from a file that is fine: each failure is the edit's doing.
  const JointErrorModel model = parseParameters(goodJson().dump(), "edited.json", rx170());
  EXPECT_EQ(model.effectCount(), 3);
}

TEST(ParameterFileEdits, EachBrokenEditGivesParameterErrorNamingFileAndField) {
  const std::string source = "edited_rx170.json";
  for (const Edit& edit : edits()) {
    nlohmann::json json = goodJson();
    edit.apply(json);
    try {
      parseParameters(json.dump(2), source, rx170());
      ADD_FAILURE() << edit.name << " was accepted";
    } catch (const ParameterError& error) {
      EXPECT_THAT(error.what(), HasSubstr(source + ": " + edit.path)) << edit.name;
    } catch (const std::exception& error) {
      ADD_FAILURE() << edit.name << " threw something else than ParameterError: " << error.what();
    }
  }
}

TEST(ParameterFileEdits, MessagesSayWhatIsWrong) {
  // A few messages checked for the offending value, not only the place.
  struct Case {
    std::function<void(nlohmann::json&)> apply;
    const char* says;
  };
  const std::vector<Case> cases = {
      {[](nlohmann::json& j) { j["effects"][1]["type"] = "friction"; }, "friction"},
      {[](nlohmann::json& j) { j["effects"][1]["joint"] = "joint_9"; }, "joint_9"},
      {[](nlohmann::json& j) { j["effects"][2]["harmonics"][0]["of"] = "gearbox"; }, "gearbox"},
      {[](nlohmann::json& j) { j["robot"] = "rx160"; }, "rx160"},
      {[](nlohmann::json& j) { j["effects"][0]["stiffness_nm_per_rad"].erase(5); }, "5"},
      {[](nlohmann::json& j) { j["effects"][1].erase("preload_n"); }, "missing"},
      {[](nlohmann::json& j) { j["effects"][2]["harmonics"][1]["order"] = 2; }, "unknown"},
      {[](nlohmann::json& j) { j["effects"].push_back(tableOf(-1e300)); }, "-1e+300 rad, beyond the plausible"},
      {[](nlohmann::json& j) { j["effects"].push_back(j["effects"][0]); },
       "compliance states joint_1.stiffness_nm_per_rad, which effects[0] (compliance) states already"},
  };
  for (const Case& c : cases) {
    nlohmann::json json = goodJson();
    c.apply(json);
    try {
      parseParameters(json.dump(), "edited.json", rx170());
      ADD_FAILURE() << "accepted; expected a message saying " << c.says;
    } catch (const ParameterError& error) {
      EXPECT_THAT(error.what(), HasSubstr(c.says));
    }
  }
}

TEST(ParameterFileEdits, ValidEditsAreAccepted) {
  // The checks are not simply rejecting everything unusual: these are all fine.
  const std::vector<std::function<void(nlohmann::json&)>> fine = {
      [](nlohmann::json& j) { j.erase("notes"); },
      [](nlohmann::json& j) {  // direct drives have one stage: the harmonics of stage 2 must go too
        j.erase("gears");
        j["effects"].erase(2);
      },
      [](nlohmann::json& j) { j["gears"].erase("coupling"); },
      [](nlohmann::json& j) { j["effects"] = nlohmann::json::array(); },
      [](nlohmann::json& j) { j["effects"][2]["harmonics"][0]["of"] = "motor"; },
      [](nlohmann::json& j) { j["effects"][2]["harmonics"][0]["of"] = "output"; },
      [](nlohmann::json& j) { j["effects"][2]["harmonics"][0]["of"] = "stage_1"; },
      [](nlohmann::json& j) { j["effects"][2]["harmonics"] = nlohmann::json::array(); },
      [](nlohmann::json& j) { j["effects"][1]["preload_n"] = -50.0; },
      [](nlohmann::json& j) { j["effects"][1].erase("estimate"); },
      [](nlohmann::json& j) { j["effects"][0]["estimate"] = "from a test"; },
      [](nlohmann::json& j) { j["effects"].push_back(tableOf(0.09)); },  // within the plausible 0.1 rad
  };
  for (std::size_t i = 0; i < fine.size(); ++i) {
    nlohmann::json json = goodJson();
    fine[i](json);
    EXPECT_NO_THROW(parseParameters(json.dump(), "edited.json", rx170())) << "edit " << i;
  }
}

TEST(ParameterFileEdits, StageOneIsTheMotor) {
  // "stage_1" (input of stage 1) and "motor" name the same part: same errors.
  nlohmann::json motor = goodJson();
  motor["effects"][2]["harmonics"][0]["of"] = "motor";
  nlohmann::json stage1 = goodJson();
  stage1["effects"][2]["harmonics"][0]["of"] = "stage_1";
  const JointErrorModel a = parseParameters(motor.dump(), "a.json", rx170());
  const JointErrorModel b = parseParameters(stage1.dump(), "b.json", rx170());
  JointContext ctx(6);
  ctx.command << 0.3, -0.2, 0.5, 1.0, -0.4, 2.0;
  updateMotorAngles(a, ctx);
  JointVector dqa = JointVector::Zero(6);
  JointVector dqb = JointVector::Zero(6);
  a.effect(2).addJointError(a.robot(), ctx, dqa);
  b.effect(2).addJointError(b.robot(), ctx, dqb);
  EXPECT_EQ(dqa, dqb);
  EXPECT_NE(dqa[0], 0.0);
}

// The parameter set is the file read once: its model equals what the model-only reader gives, its drives
// what the plant reader gives, and a file without "plant" has no drives.
TEST(ParameterSet, ReadsTheModelAndTheDrivesOnce) {
  const ParameterSet set = loadParameterSet(rx170ParametersPath(), rx170());
  expectSameModel(set.model, loadParameterFile(rx170ParametersPath(), rx170()));
  ASSERT_TRUE(set.hasDrives());
  EXPECT_TRUE(
      bitIdentical(driveParameters(set.drives), driveParameters(loadDriveParameters(rx170ParametersPath(), *rx170()))));
  nlohmann::json without = goodJson();
  without.erase("plant");
  const ParameterSet model_only =
      parseParameterSet(without.dump(), "no_plant.json", rx170(), EffectRegistry::builtin());
  EXPECT_FALSE(model_only.hasDrives());
  expectSameModel(model_only.model, set.model);
}

// A malformed "plant" object is an error for every reader of the file, named by file and field.
TEST(ParameterSet, AMalformedPlantIsAnErrorEvenForTheModelAlone) {
  nlohmann::json bad = goodJson();
  bad["plant"]["joints"][2]["motor_inertia_kgm2"] = -1.0;
  try {
    parseParameters(bad.dump(), "bad_plant.json", rx170());
    ADD_FAILURE() << "a negative motor inertia was accepted";
  } catch (const ParameterError& e) {
    EXPECT_THAT(e.what(), HasSubstr("bad_plant.json: plant"));
    EXPECT_THAT(e.what(), HasSubstr("motor_inertia_kgm2"));
  }
  bad = goodJson();
  bad["plant"]["joints"][0]["gain"] = 1.0;
  EXPECT_THROW(parseParameterSet(bad.dump(), "bad_plant.json", rx170(), EffectRegistry::builtin()), ParameterError);
}

// ---- bounded input ---------------------------------------------------------------------------------

TEST(ParameterFile, ARepeatedKeyIsAnErrorNamingIt) {
  const std::string text = readText(rx170ParametersPath());
  const std::size_t brace = text.find('{');
  const std::string repeated = text.substr(0, brace + 1) + "\"notes\": \"first\", " + text.substr(brace + 1);
  try {
    parseParameters(repeated, "repeated.json", rx170());
    ADD_FAILURE() << "a repeated key was accepted";
  } catch (const ParameterError& error) {
    EXPECT_THAT(error.what(), HasSubstr("repeated.json"));
    EXPECT_THAT(error.what(), HasSubstr("'notes' appears twice"));
  }
}

TEST(ParameterFile, AnOversizedFileIsRefusedBeforeItIsRead) {
  const std::filesystem::path directory = std::filesystem::path(::testing::TempDir()) / "jointcomp_parameter_size_test";
  std::filesystem::create_directories(directory);
  const std::string path = (directory / "huge.json").string();
  {
    // A number string longer than any parameter file: the file is sparse, nothing is written but its end.
    std::ofstream out(path, std::ios::binary);
    out << "{\"format\": 1";
    out.seekp(static_cast<std::streamoff>(kMaxJsonFileBytes) + 10);
    out << "}";
  }
  try {
    loadParameterFile(path, rx170());
    ADD_FAILURE() << "an oversized file was read";
  } catch (const ParameterError& error) {
    EXPECT_THAT(error.what(), HasSubstr("larger than 16 MiB"));
    EXPECT_LT(std::string(error.what()).size(), 400u);
  }
  std::filesystem::remove(path);
  // A device that never ends is read up to the limit and refused, never past it.
  EXPECT_THROW(loadParameterFile("/dev/zero", rx170()), ParameterError);
}

}  // namespace
}  // namespace jointcomp
