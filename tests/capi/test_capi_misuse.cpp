// Misuse of the C API: every entry point called with a NULL handle, a handle of the other kind, a pointer
// that was never a handle and (outside sanitizer builds) a freed handle; NULL arrays, wrong, negative and
// huge lengths, NaN and infinities, plant calls in an unusual order. Each call must return the documented
// error status with a message naming the entry point, leave its outputs untouched, and leave other
// handles working: after every test a healthy robot and plant give the same results, bit for bit, as
// before it.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <jointcomp/jointcomp.h>

namespace {

const std::string kUrdf = std::string(JOINTCOMP_DATA_DIR) + "/robots/rx170.urdf";
const std::string kParameters = std::string(JOINTCOMP_DATA_DIR) + "/params/rx170.json";
constexpr int kDof = 6;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::int32_t kHugeLength = std::numeric_limits<std::int32_t>::max();
constexpr std::int32_t kMostNegativeLength = std::numeric_limits<std::int32_t>::min();
constexpr double kPosture[kDof] = {0.1, -0.4, 0.3, 0.2, 0.5, -0.1};
// Written into outputs before a call that must fail: they must still hold it afterwards.
constexpr double kUntouched = 12345.678;

// Lengths that are wrong for an array that must hold exactly `good` values.
std::vector<std::int32_t> wrongLengths(std::int32_t good) {
  return {0, good - 1, good + 1, -1, -good, kMostNegativeLength, kHugeLength};
}

std::string lastError() { return jc_last_error(); }

// The call failed with `status`, and the message names the entry point and contains `fragment`.
::testing::AssertionResult failsWith(jc_status got, jc_status expected, const char* function, const char* fragment) {
  const std::string message = lastError();
  if (got != expected) {
    return ::testing::AssertionFailure() << function << " returned " << jc_status_name(got) << ", expected "
                                         << jc_status_name(expected) << " (message: " << message << ")";
  }
  if (message.find(function) == std::string::npos || message.find(fragment) == std::string::npos) {
    return ::testing::AssertionFailure() << function << ": the message '" << message << "' does not name " << function
                                         << " or does not contain '" << fragment << "'";
  }
  return ::testing::AssertionSuccess();
}
#define EXPECT_FAILS(expected, function, fragment, call) EXPECT_TRUE(failsWith((call), (expected), function, fragment))
#define EXPECT_INVALID(function, fragment, call) EXPECT_FAILS(JC_ERROR_INVALID_ARGUMENT, function, fragment, call)

// Arrays big enough for every call, filled with kUntouched.
struct Buffers {
  Buffers() { fill(); }
  void fill() {
    for (auto* v : {&a, &b, &c, &d}) v->assign(4096, kUntouched);
    for (auto& x : counts) x = 777;
    integer = 777;
    text.assign(256, 'x');
  }
  bool untouched() const {
    for (const auto* v : {&a, &b, &c, &d}) {
      for (double x : *v) {
        if (x != kUntouched) return false;
      }
    }
    for (auto x : counts) {
      if (x != 777) return false;
    }
    return integer == 777 && text == std::string(256, 'x');
  }
  std::vector<double> a, b, c, d;
  std::int64_t counts[5];
  std::int32_t integer;
  std::string text;
};

// One entry point with valid arguments except the handle.
struct RobotCall {
  const char* name;
  std::function<jc_status(jc_robot*, Buffers&)> call;
  const char* handle = "robot";  // the robot parameter's name in the header
};

// An identification call with its outputs: a handle must never come out of a failed call.
jc_status identification(Buffers& b, const std::function<jc_status(jc_robot**, jc_report**)>& call) {
  jc_robot* robot = nullptr;
  jc_report* report = nullptr;
  const jc_status status = call(&robot, &report);
  if (robot || report) b.integer = -1;
  return status;
}
struct PlantCall {
  const char* name;
  std::function<jc_status(jc_plant*, Buffers&)> call;
};

double* pose16() {
  static double pose[16] = {1, 0, 0, 1.2, 0, -1, 0, 0, 0, 0, -1, 0.2, 0, 0, 0, 1};
  return pose;
}

std::vector<RobotCall> everyRobotCall() {
  const double com[3] = {0, 0, 0.1};
  const double wrench[6] = {1, 2, 3, 0.1, 0.2, 0.3};
  return {
      {"jc_robot_dof", [](jc_robot* r, Buffers& b) { return jc_robot_dof(r, &b.integer); }},
      {"jc_robot_name", [](jc_robot* r, Buffers& b) { return jc_robot_name(r, &b.text[0], 256, &b.integer); }},
      {"jc_robot_joint_limits",
       [](jc_robot* r, Buffers& b) { return jc_robot_joint_limits(r, b.a.data(), kDof, b.b.data(), kDof); }},
      {"jc_robot_has_drives", [](jc_robot* r, Buffers& b) { return jc_robot_has_drives(r, &b.integer); }},
      {"jc_robot_tool_target",
       [](jc_robot* r, Buffers& b) { return jc_robot_tool_target(r, b.a.data(), 3, &b.integer); }},
      {"jc_robot_base_frame",
       [](jc_robot* r, Buffers& b) { return jc_robot_base_frame(r, b.a.data(), 16, &b.integer); }},
      {"jc_robot_parameters_json",
       [](jc_robot* r, Buffers& b) { return jc_robot_parameters_json(r, &b.text[0], 256, &b.integer); }},
      {"jc_robot_set_payload", [com](jc_robot* r, Buffers&) { return jc_robot_set_payload(r, 10.0, com, 3); }},
      {"jc_robot_set_tool_wrench", [wrench](jc_robot* r, Buffers&) { return jc_robot_set_tool_wrench(r, wrench, 6); }},
      {"jc_forward_kinematics",
       [](jc_robot* r, Buffers& b) { return jc_forward_kinematics(r, kPosture, kDof, b.a.data(), 16); }},
      {"jc_inverse_kinematics",
       [](jc_robot* r, Buffers& b) {
         return jc_inverse_kinematics(r, pose16(), 16, kPosture, kDof, b.a.data(), kDof, &b.integer);
       }},
      {"jc_inverse_kinematics_all",
       [](jc_robot* r, Buffers& b) {
         return jc_inverse_kinematics_all(r, pose16(), 16, kPosture, kDof, b.a.data(), 8 * kDof, &b.integer);
       }},
      {"jc_jacobian", [](jc_robot* r, Buffers& b) { return jc_jacobian(r, kPosture, kDof, b.a.data(), 6 * kDof); }},
      {"jc_gravity_torques",
       [](jc_robot* r, Buffers& b) { return jc_gravity_torques(r, kPosture, kDof, b.a.data(), kDof); }},
      {"jc_predict_joint_errors",
       [](jc_robot* r, Buffers& b) {
         return jc_predict_joint_errors(r, nullptr, kPosture, kDof, nullptr, 0, b.a.data(), kDof);
       }},
      {"jc_compensate_point",
       [](jc_robot* r, Buffers& b) {
         return jc_compensate_point(r, nullptr, kPosture, kDof, nullptr, 0, b.a.data(), kDof, &b.integer);
       }},
      {"jc_compensate_trajectory",
       [](jc_robot* r, Buffers& b) {
         return jc_compensate_trajectory(r, nullptr, kPosture, kDof, nullptr, 0, b.a.data(), kDof, &b.integer,
                                         b.b.data());
       }},
      {"jc_spiral_sample_count", [](jc_robot* r, Buffers& b) { return jc_spiral_sample_count(r, &b.integer); }},
      {"jc_spiral_plan",
       [](jc_robot* r, Buffers& b) { return jc_spiral_plan(r, b.a.data(), 1, nullptr, 0, nullptr, 0, nullptr, 0); }},
      {"jc_spiral_experiment",
       [](jc_robot* r, Buffers& b) { return jc_spiral_experiment(r, 0, b.a.data(), 15, nullptr, 0); }},
      {"jc_plant_create",
       [](jc_robot* r, Buffers& b) {
         jc_plant* plant = nullptr;
         const jc_status status = jc_plant_create(r, &plant);
         if (plant) b.integer = -1;  // a handle must never come out of a failed call
         return status;
       }},
      {"jc_robot_save", [](jc_robot* r, Buffers&) { return jc_robot_save(r, nullptr, "/nonexistent/p.json"); }},
      {"jc_simulate_campaign",
       [](jc_robot* r, Buffers&) { return jc_simulate_campaign(r, R"({"protocol": "random"})", "/nonexistent/c.csv"); },
       "truth"},
      {"jc_identify_stiffness",
       [](jc_robot* r, Buffers& b) {
         return identification(
             b, [r](jc_robot** o, jc_report** p) { return jc_identify_stiffness(r, "c.csv", nullptr, o, p); });
       },
       "nominal"},
      {"jc_identify_transmission_error",
       [](jc_robot* r, Buffers& b) {
         return identification(
             b, [r](jc_robot** o, jc_report** p) { return jc_identify_transmission_error(r, "c.csv", nullptr, o, p); });
       },
       "nominal"},
      {"jc_calibrate",
       [](jc_robot* r, Buffers& b) {
         return identification(
             b, [r](jc_robot** o, jc_report** p) { return jc_calibrate(r, "c.csv", nullptr, nullptr, o, p); });
       },
       "nominal"},
      {"jc_discover",
       [](jc_robot* r, Buffers& b) {
         return identification(
             b, [r](jc_robot** o, jc_report** p) { return jc_discover(r, "c.csv", nullptr, nullptr, o, p); });
       },
       "nominal"},
      {"jc_spiral_experiment_truth",
       [](jc_robot* r, Buffers& b) { return jc_spiral_experiment_truth(r, r, 0, b.a.data(), 15, nullptr, 0); },
       "nominal"},
      {"jc_identify_and_compensate",
       [](jc_robot* r, Buffers& b) {
         return identification(b, [r, &b](jc_robot** o, jc_report** p) {
           return jc_identify_and_compensate(r, r, nullptr, b.a.data(), 15, o, p);
         });
       },
       "nominal"},
      {"jc_robot_free", [](jc_robot* r, Buffers&) { return jc_robot_free(r); }},
  };
}

std::vector<PlantCall> everyPlantCall() {
  return {
      {"jc_plant_dof", [](jc_plant* p, Buffers& b) { return jc_plant_dof(p, &b.integer); }},
      {"jc_plant_reset", [](jc_plant* p, Buffers&) { return jc_plant_reset(p, kPosture, kDof, 0.0); }},
      {"jc_plant_set_reference",
       [](jc_plant* p, Buffers&) { return jc_plant_set_reference(p, kPosture, kDof, kPosture, kDof); }},
      {"jc_plant_set_tool_wrench", [](jc_plant* p, Buffers&) { return jc_plant_set_tool_wrench(p, kPosture, 6); }},
      {"jc_plant_set_payload", [](jc_plant* p, Buffers&) { return jc_plant_set_payload(p, 1.0, kPosture, 3); }},
      {"jc_plant_advance", [](jc_plant* p, Buffers&) { return jc_plant_advance(p, 1.0); }},
      {"jc_plant_time", [](jc_plant* p, Buffers& b) { return jc_plant_time(p, b.a.data()); }},
      {"jc_plant_link_positions", [](jc_plant* p, Buffers& b) { return jc_plant_link_positions(p, b.a.data(), kDof); }},
      {"jc_plant_link_velocities",
       [](jc_plant* p, Buffers& b) { return jc_plant_link_velocities(p, b.a.data(), kDof); }},
      {"jc_plant_motor_positions",
       [](jc_plant* p, Buffers& b) { return jc_plant_motor_positions(p, b.a.data(), kDof); }},
      {"jc_plant_motor_velocities",
       [](jc_plant* p, Buffers& b) { return jc_plant_motor_velocities(p, b.a.data(), kDof); }},
      {"jc_plant_motor_torques", [](jc_plant* p, Buffers& b) { return jc_plant_motor_torques(p, b.a.data(), kDof); }},
      {"jc_plant_state", [](jc_plant* p, Buffers& b) { return jc_plant_state(p, b.a.data(), 5 * kDof); }},
      {"jc_plant_statistics", [](jc_plant* p, Buffers& b) { return jc_plant_statistics(p, b.counts, 5); }},
      {"jc_plant_snapshot_size", [](jc_plant* p, Buffers& b) { return jc_plant_snapshot_size(p, &b.integer); }},
      {"jc_plant_save", [](jc_plant* p, Buffers& b) { return jc_plant_save(p, b.a.data(), 10 * kDof + 14); }},
      {"jc_plant_restore", [](jc_plant* p, Buffers& b) { return jc_plant_restore(p, b.b.data(), 10 * kDof + 14); }},
      {"jc_plant_free", [](jc_plant* p, Buffers&) { return jc_plant_free(p); }},
  };
}

// What the healthy handles compute: taken before each test and compared after it.
struct HealthyResults {
  double pose[16];
  double reference[kDof];
  double link_positions[kDof];
  double state[5 * kDof];
};

class CapiMisuse : public ::testing::Test {
protected:
  void SetUp() override {
    ASSERT_EQ(jc_robot_load(kUrdf.c_str(), kParameters.c_str(), &robot_), JC_OK) << lastError();
    ASSERT_EQ(jc_plant_create(robot_, &plant_), JC_OK) << lastError();
    ASSERT_EQ(jc_robot_load(kUrdf.c_str(), kParameters.c_str(), &healthy_robot_), JC_OK) << lastError();
    ASSERT_EQ(jc_plant_create(healthy_robot_, &healthy_plant_), JC_OK) << lastError();
    computeHealthy(before_);
  }

  void TearDown() override {
    if (healthy_robot_ && healthy_plant_) {
      HealthyResults after;
      computeHealthy(after);
      EXPECT_EQ(std::memcmp(&before_, &after, sizeof before_), 0)
          << "the healthy handles give other results after the misuse";
    }
    EXPECT_EQ(jc_plant_free(plant_), JC_OK);
    EXPECT_EQ(jc_robot_free(robot_), JC_OK);
    EXPECT_EQ(jc_plant_free(healthy_plant_), JC_OK);
    EXPECT_EQ(jc_robot_free(healthy_robot_), JC_OK);
  }

  void computeHealthy(HealthyResults& results) {
    std::memset(&results, 0, sizeof results);
    int32_t iterations = 0;
    ASSERT_EQ(jc_forward_kinematics(healthy_robot_, kPosture, kDof, results.pose, 16), JC_OK) << lastError();
    ASSERT_EQ(
        jc_compensate_point(healthy_robot_, nullptr, kPosture, kDof, nullptr, 0, results.reference, kDof, &iterations),
        JC_OK)
        << lastError();
    ASSERT_EQ(jc_plant_reset(healthy_plant_, kPosture, kDof, 0.0), JC_OK) << lastError();
    const double at_rest[kDof] = {};
    ASSERT_EQ(jc_plant_set_reference(healthy_plant_, results.reference, kDof, at_rest, kDof), JC_OK) << lastError();
    ASSERT_EQ(jc_plant_advance(healthy_plant_, 0.02), JC_OK) << lastError();
    ASSERT_EQ(jc_plant_link_positions(healthy_plant_, results.link_positions, kDof), JC_OK) << lastError();
    ASSERT_EQ(jc_plant_state(healthy_plant_, results.state, 5 * kDof), JC_OK) << lastError();
  }

  jc_robot* robot_ = nullptr;
  jc_plant* plant_ = nullptr;
  jc_robot* healthy_robot_ = nullptr;
  jc_plant* healthy_plant_ = nullptr;
  HealthyResults before_;
};

// ---- Handles ---------------------------------------------------------------------------------------------

TEST_F(CapiMisuse, NullHandlesAreInvalidArguments) {
  Buffers buffers;
  for (const RobotCall& c : everyRobotCall()) {
    if (std::string(c.name) == "jc_robot_free") {
      EXPECT_EQ(jc_robot_free(nullptr), JC_OK) << "freeing NULL is a no-op";
      continue;
    }
    EXPECT_INVALID(c.name, (std::string(c.handle) + " is NULL").c_str(), c.call(nullptr, buffers));
    EXPECT_TRUE(buffers.untouched()) << c.name << " wrote an output although it failed";
  }
  for (const PlantCall& c : everyPlantCall()) {
    if (std::string(c.name) == "jc_plant_free") {
      EXPECT_EQ(jc_plant_free(nullptr), JC_OK) << "freeing NULL is a no-op";
      continue;
    }
    EXPECT_INVALID(c.name, "plant is NULL", c.call(nullptr, buffers));
    EXPECT_TRUE(buffers.untouched()) << c.name << " wrote an output although it failed";
  }
}

TEST_F(CapiMisuse, HandlesOfTheOtherKindAreRefused) {
  Buffers buffers;
  for (const RobotCall& c : everyRobotCall()) {
    EXPECT_FAILS(JC_ERROR_WRONG_HANDLE, c.name, "got a jc_plant", c.call(reinterpret_cast<jc_robot*>(plant_), buffers));
    EXPECT_TRUE(buffers.untouched()) << c.name;
  }
  for (const PlantCall& c : everyPlantCall()) {
    EXPECT_FAILS(JC_ERROR_WRONG_HANDLE, c.name, "got a jc_robot", c.call(reinterpret_cast<jc_plant*>(robot_), buffers));
    EXPECT_TRUE(buffers.untouched()) << c.name;
  }
  // Both handles are still alive and of their own kind.
  int32_t dof = 0;
  EXPECT_EQ(jc_robot_dof(robot_, &dof), JC_OK);
  EXPECT_EQ(jc_plant_dof(plant_, &dof), JC_OK);
}

TEST_F(CapiMisuse, PointersThatWereNeverHandlesAreRefused) {
  Buffers buffers;
  // Readable memory of another meaning: zeros, a pattern, text.
  std::vector<std::vector<unsigned char>> garbage = {std::vector<unsigned char>(64, 0),
                                                     std::vector<unsigned char>(64, 0xab)};
  const std::string text = "jcrobot1 jcplant1 is not a handle, only text about one";
  garbage.emplace_back(text.begin(), text.end());
  for (auto& bytes : garbage) {
    for (const RobotCall& c : everyRobotCall()) {
      EXPECT_FAILS(JC_ERROR_WRONG_HANDLE, c.name, "not a live jointcomp handle",
                   c.call(reinterpret_cast<jc_robot*>(bytes.data()), buffers));
    }
    for (const PlantCall& c : everyPlantCall()) {
      EXPECT_FAILS(JC_ERROR_WRONG_HANDLE, c.name, "not a live jointcomp handle",
                   c.call(reinterpret_cast<jc_plant*>(bytes.data()), buffers));
    }
  }
  EXPECT_TRUE(buffers.untouched());
}

// A use after free, recognised from the table of live handles without reading the freed memory (the
// header's rule 2), under sanitizers too.
TEST_F(CapiMisuse, FreedHandlesAreRecognisedWhileTheirMemoryIsNotReused) {
  Buffers buffers;
  for (const RobotCall& c : everyRobotCall()) {
    jc_robot* freed = nullptr;
    ASSERT_EQ(jc_robot_load(kUrdf.c_str(), kParameters.c_str(), &freed), JC_OK);
    ASSERT_EQ(jc_robot_free(freed), JC_OK);
    EXPECT_FAILS(JC_ERROR_WRONG_HANDLE, c.name, "already freed", c.call(freed, buffers));
  }
  for (const PlantCall& c : everyPlantCall()) {
    jc_plant* freed = nullptr;
    ASSERT_EQ(jc_plant_create(robot_, &freed), JC_OK);
    ASSERT_EQ(jc_plant_free(freed), JC_OK);
    EXPECT_FAILS(JC_ERROR_WRONG_HANDLE, c.name, "already freed", c.call(freed, buffers));
  }
  EXPECT_TRUE(buffers.untouched());
}

// ---- Loading ---------------------------------------------------------------------------------------------

TEST_F(CapiMisuse, LoadingRefusesNullPathsBrokenTextAndKeepsTheOutputHandle) {
  jc_robot* const sentinel = reinterpret_cast<jc_robot*>(&before_);  // never dereferenced by a failing load
  jc_robot* robot = sentinel;
  EXPECT_INVALID("jc_robot_load", "robot", jc_robot_load(kUrdf.c_str(), kParameters.c_str(), nullptr));
  EXPECT_INVALID("jc_robot_load", "urdf_path", jc_robot_load(nullptr, kParameters.c_str(), &robot));
  EXPECT_FAILS(JC_ERROR_FILE, "jc_robot_load", "", jc_robot_load("/nonexistent/robot.urdf", nullptr, &robot));
  EXPECT_FAILS(JC_ERROR_FILE, "jc_robot_load", "", jc_robot_load(kUrdf.c_str(), "/nonexistent/params.json", &robot));
  EXPECT_FAILS(JC_ERROR_FILE, "jc_robot_load", "", jc_robot_load("", nullptr, &robot));
  // A folder is not a file.
  EXPECT_FAILS(JC_ERROR_FILE, "jc_robot_load", "", jc_robot_load(JOINTCOMP_DATA_DIR, nullptr, &robot));
  EXPECT_INVALID("jc_robot_load_json", "urdf_path", jc_robot_load_json(nullptr, "{}", &robot));
  EXPECT_INVALID("jc_robot_load_json", "robot", jc_robot_load_json(kUrdf.c_str(), "{}", nullptr));
  for (const char* broken : {"", "{", "null", "[]", "{}", "{\"format\": 1}", "\xff\xfe", "{\"effects\": [{}]}"}) {
    EXPECT_FAILS(JC_ERROR_FILE, "jc_robot_load_json", "", jc_robot_load_json(kUrdf.c_str(), broken, &robot))
        << "parameters '" << broken << "'";
  }
  EXPECT_EQ(robot, sentinel) << "a failed load wrote the output handle";
}

TEST_F(CapiMisuse, PlantsNeedDrives) {
  jc_robot* kinematic_only = nullptr;
  ASSERT_EQ(jc_robot_load(kUrdf.c_str(), nullptr, &kinematic_only), JC_OK);
  jc_plant* plant = nullptr;
  EXPECT_INVALID("jc_plant_create", "plant", jc_plant_create(kinematic_only, &plant));
  EXPECT_EQ(plant, nullptr);
  EXPECT_INVALID("jc_plant_create", "plant", jc_plant_create(robot_, nullptr));
  EXPECT_EQ(jc_robot_free(kinematic_only), JC_OK);
}

// Plant options: an unknown name, a value of the wrong type or out of range, text that is not a JSON object:
// each refused with the option named, and no plant made.
TEST_F(CapiMisuse, PlantOptionsAreCheckedByName) {
  const std::pair<const char*, const char*> bad[] = {
      {"{\"step_past\": 0.01}", "step_past"},
      {"{\"step_past_updates_s\": 2.0}", "step_past_updates_s"},
      {"{\"step_past_updates_s\": -0.001}", "step_past_updates_s"},
      {"{\"step_past_tolerance_rad\": -1e-6}", "step_past_tolerance_rad"},
      {"{\"max_order\": 2.5}", "max_order"},
      {"{\"max_order\": 9}", "max_order"},
      {"{\"even_steps\": 1}", "even_steps"},
      {"{\"relative_tolerance\": 0}", "tolerances"},
      {"{\"jacobian_reuse_steps\": 0}", "jacobian_reuse_steps"},
      {"{\"max_steps_per_advance\": 4294967301}", "max_steps_per_advance"},  // 2^32 + 5 would wrap to 5
      {"{\"tracking_envelope_rad\": \"wide\"}", "tracking_envelope_rad"},
      {"[1, 2]", "JSON object"},
      {"{\"max_order\": 3", "options_json"},
  };
  for (const auto& [options, fragment] : bad) {
    jc_plant* plant = nullptr;
    EXPECT_INVALID("jc_plant_create_with_options", fragment, jc_plant_create_with_options(robot_, options, &plant))
        << options;
    EXPECT_EQ(plant, nullptr) << options;
  }
}

// ---- Arrays, lengths, values -------------------------------------------------------------------------------

TEST_F(CapiMisuse, TextOutputsRefuseBadBuffers) {
  using TextCall = jc_status (*)(jc_robot*, char*, int32_t, int32_t*);
  const std::pair<const char*, TextCall> calls[] = {{"jc_robot_name", jc_robot_name},
                                                    {"jc_robot_parameters_json", jc_robot_parameters_json}};
  for (const auto& [name, call] : calls) {
    std::string buffer(8, 'x');
    int32_t length = 777;
    EXPECT_INVALID(name, "length", call(robot_, &buffer[0], 8, nullptr));
    EXPECT_INVALID(name, "capacity", call(robot_, &buffer[0], -1, &length));
    EXPECT_INVALID(name, "capacity", call(robot_, &buffer[0], kMostNegativeLength, &length));
    EXPECT_INVALID(name, "buffer", call(robot_, nullptr, 8, &length));
    EXPECT_INVALID(name, "buffer", call(robot_, &buffer[0], 1, &length));  // too small for any name
    EXPECT_EQ(buffer, std::string(8, 'x')) << name;
    EXPECT_EQ(length, 777) << name;
    // Asking for the length only works.
    EXPECT_EQ(call(robot_, nullptr, 0, &length), JC_OK) << name;
    EXPECT_GT(length, 0) << name;
  }
}

TEST_F(CapiMisuse, JointArraysRefuseNullWrongLengthsAndNonFiniteValues) {
  // Every function with one joint input q (n) and one output (`out_len` values).
  struct JointCall {
    const char* name;
    int32_t out_len;
    std::function<jc_status(const double*, int32_t, double*, int32_t)> call;
  };
  const std::vector<JointCall> calls = {
      {"jc_forward_kinematics", 16,
       [this](const double* q, int32_t n, double* out, int32_t len) {
         return jc_forward_kinematics(robot_, q, n, out, len);
       }},
      {"jc_jacobian", 6 * kDof,
       [this](const double* q, int32_t n, double* out, int32_t len) { return jc_jacobian(robot_, q, n, out, len); }},
      {"jc_gravity_torques", kDof,
       [this](const double* q, int32_t n, double* out, int32_t len) {
         return jc_gravity_torques(robot_, q, n, out, len);
       }},
      {"jc_predict_joint_errors", kDof,
       [this](const double* q, int32_t n, double* out, int32_t len) {
         return jc_predict_joint_errors(robot_, nullptr, q, n, nullptr, 0, out, len);
       }},
      {"jc_compensate_point", kDof,
       [this](const double* q, int32_t n, double* out, int32_t len) {
         return jc_compensate_point(robot_, nullptr, q, n, nullptr, 0, out, len, nullptr);
       }},
  };
  Buffers buffers;
  for (const JointCall& c : calls) {
    EXPECT_INVALID(c.name, "NULL", c.call(nullptr, kDof, buffers.a.data(), c.out_len));
    EXPECT_INVALID(c.name, "NULL", c.call(kPosture, kDof, nullptr, c.out_len));
    for (int32_t length : wrongLengths(kDof)) {
      EXPECT_INVALID(c.name, "_len", c.call(kPosture, length, buffers.a.data(), c.out_len)) << "q_len " << length;
    }
    for (int32_t length : wrongLengths(c.out_len)) {
      EXPECT_INVALID(c.name, "_len", c.call(kPosture, kDof, buffers.a.data(), length)) << "output length " << length;
    }
    for (double bad : {kNaN, kInf, -kInf}) {
      for (int j = 0; j < kDof; ++j) {
        double q[kDof];
        std::memcpy(q, kPosture, sizeof q);
        q[j] = bad;
        EXPECT_INVALID(c.name, "", c.call(q, kDof, buffers.a.data(), c.out_len)) << "q[" << j << "] = " << bad;
      }
    }
    EXPECT_TRUE(buffers.untouched()) << c.name;
  }
}

TEST_F(CapiMisuse, OptionalVelocitiesMustBeConsistent) {
  Buffers buffers;
  const double nan_velocity[kDof] = {0, 0, kNaN, 0, 0, 0};
  EXPECT_INVALID("jc_predict_joint_errors", "velocity",
                 jc_predict_joint_errors(robot_, nullptr, kPosture, kDof, nullptr, kDof, buffers.a.data(), kDof));
  EXPECT_INVALID("jc_predict_joint_errors", "velocity",
                 jc_predict_joint_errors(robot_, nullptr, kPosture, kDof, kPosture, 3, buffers.a.data(), kDof));
  EXPECT_INVALID("jc_predict_joint_errors", "velocity",
                 jc_predict_joint_errors(robot_, nullptr, kPosture, kDof, nan_velocity, kDof, buffers.a.data(), kDof));
  EXPECT_INVALID(
      "jc_compensate_point", "velocity",
      jc_compensate_point(robot_, nullptr, kPosture, kDof, kPosture, -kDof, buffers.a.data(), kDof, nullptr));
  EXPECT_TRUE(buffers.untouched());
}

TEST_F(CapiMisuse, EffectSelectionsNameRegisteredTypes) {
  Buffers buffers;
  for (const char* effects : {"stiffness", "compliance,", "compliance;transmission_error", "COMPLIANCE", "\t x"}) {
    const std::string text = effects;
    const bool only_separators_and_known = text == "compliance,";
    const jc_status status =
        jc_compensate_point(robot_, effects, kPosture, kDof, nullptr, 0, buffers.a.data(), kDof, nullptr);
    if (only_separators_and_known) {
      EXPECT_EQ(status, JC_OK) << "an empty item in the list is skipped: " << lastError();
    } else {
      EXPECT_INVALID("jc_compensate_point", "not an effect type", status) << "effects '" << effects << "'";
    }
  }
}

TEST_F(CapiMisuse, TrajectoriesRefuseBadShapes) {
  Buffers buffers;
  std::vector<double> planned;
  for (int k = 0; k < 4; ++k) planned.insert(planned.end(), kPosture, kPosture + kDof);
  const auto trajectory = [&](const double* p, int32_t p_len, const double* v, int32_t v_len, double* out,
                              int32_t out_len) {
    return jc_compensate_trajectory(robot_, nullptr, p, p_len, v, v_len, out, out_len, nullptr, nullptr);
  };
  const int32_t good = 4 * kDof;
  EXPECT_INVALID("jc_compensate_trajectory", "planned", trajectory(nullptr, good, nullptr, 0, buffers.a.data(), good));
  EXPECT_INVALID("jc_compensate_trajectory", "references", trajectory(planned.data(), good, nullptr, 0, nullptr, good));
  for (int32_t length : {0, 1, kDof - 1, good - 1, good + 1, -kDof, -good, kMostNegativeLength, kHugeLength}) {
    EXPECT_INVALID("jc_compensate_trajectory", "_len",
                   trajectory(planned.data(), length, nullptr, 0, buffers.a.data(), length))
        << "planned_len = references_len = " << length;
  }
  for (int32_t length : wrongLengths(good)) {
    EXPECT_INVALID("jc_compensate_trajectory", "_len",
                   trajectory(planned.data(), good, nullptr, 0, buffers.a.data(), length))
        << "references_len " << length;
    EXPECT_INVALID("jc_compensate_trajectory", "velocities",
                   trajectory(planned.data(), good, planned.data(), length, buffers.a.data(), good))
        << "velocities_len " << length;
  }
  EXPECT_INVALID("jc_compensate_trajectory", "velocities",
                 trajectory(planned.data(), good, nullptr, good, buffers.a.data(), good));
  std::vector<double> with_nan = planned;
  with_nan[good - 1] = kNaN;
  EXPECT_INVALID("jc_compensate_trajectory", "planned",
                 trajectory(with_nan.data(), good, nullptr, 0, buffers.a.data(), good));
  EXPECT_INVALID("jc_compensate_trajectory", "velocities",
                 trajectory(planned.data(), good, with_nan.data(), good, buffers.a.data(), good));
  EXPECT_TRUE(buffers.untouched());
}

TEST_F(CapiMisuse, PosesMustBeFiniteRigidTransforms) {
  Buffers buffers;
  double pose[16];
  ASSERT_EQ(jc_forward_kinematics(robot_, kPosture, kDof, pose, 16), JC_OK);
  const auto ik = [&](const double* p, int32_t p_len) {
    return jc_inverse_kinematics(robot_, p, p_len, kPosture, kDof, buffers.a.data(), kDof, nullptr);
  };
  const auto ik_all = [&](const double* p, int32_t p_len) {
    return jc_inverse_kinematics_all(robot_, p, p_len, kPosture, kDof, buffers.a.data(), 8 * kDof, &buffers.integer);
  };
  for (const auto& call : {std::function<jc_status(const double*, int32_t)>(ik),
                           std::function<jc_status(const double*, int32_t)>(ik_all)}) {
    EXPECT_EQ(call(nullptr, 16), JC_ERROR_INVALID_ARGUMENT);
    for (int32_t length : wrongLengths(16)) EXPECT_EQ(call(pose, length), JC_ERROR_INVALID_ARGUMENT) << length;
    for (int k : {0, 3, 5, 11, 15}) {
      double bad[16];
      std::memcpy(bad, pose, sizeof bad);
      bad[k] = kNaN;
      EXPECT_EQ(call(bad, 16), JC_ERROR_INVALID_ARGUMENT) << "NaN at " << k;
      bad[k] = pose[k] + 0.5;  // rotation part no longer orthonormal, or bottom row not 0 0 0 1
      if (k != 3 && k != 11) {
        EXPECT_EQ(call(bad, 16), JC_ERROR_INVALID_ARGUMENT) << "skewed at " << k;
      }
    }
  }
  // Too small for the eight solutions: refused before anything is written.
  EXPECT_INVALID(
      "jc_inverse_kinematics_all", "solutions",
      jc_inverse_kinematics_all(robot_, pose, 16, kPosture, kDof, buffers.a.data(), 8 * kDof - 1, &buffers.integer));
  EXPECT_INVALID("jc_inverse_kinematics_all", "solutions",
                 jc_inverse_kinematics_all(robot_, pose, 16, kPosture, kDof, buffers.a.data(), kMostNegativeLength,
                                           &buffers.integer));
  EXPECT_INVALID("jc_inverse_kinematics_all", "count",
                 jc_inverse_kinematics_all(robot_, pose, 16, kPosture, kDof, buffers.a.data(), 8 * kDof, nullptr));
  EXPECT_TRUE(buffers.untouched());
}

TEST_F(CapiMisuse, ConditionsRefuseNonFiniteOrNegativeValues) {
  const double com[3] = {0, 0, 0.1};
  const double nan_com[3] = {0, kNaN, 0.1};
  double wrench[6] = {1, 2, 3, 0.1, 0.2, 0.3};
  EXPECT_INVALID("jc_robot_set_payload", "mass", jc_robot_set_payload(robot_, kNaN, com, 3));
  EXPECT_INVALID("jc_robot_set_payload", "mass", jc_robot_set_payload(robot_, kInf, com, 3));
  EXPECT_INVALID("jc_robot_set_payload", "mass", jc_robot_set_payload(robot_, -1.0, com, 3));
  EXPECT_INVALID("jc_robot_set_payload", "com", jc_robot_set_payload(robot_, 1.0, nan_com, 3));
  EXPECT_INVALID("jc_robot_set_payload", "com", jc_robot_set_payload(robot_, 1.0, nullptr, 3));
  EXPECT_INVALID("jc_plant_set_payload", "mass", jc_plant_set_payload(plant_, -kInf, com, 3));
  EXPECT_INVALID("jc_plant_set_payload", "mass", jc_plant_set_payload(plant_, -0.5, com, 3));
  for (int32_t length : wrongLengths(3)) {
    EXPECT_INVALID("jc_robot_set_payload", "com", jc_robot_set_payload(robot_, 1.0, com, length));
    EXPECT_INVALID("jc_plant_set_payload", "com", jc_plant_set_payload(plant_, 1.0, com, length));
  }
  for (int32_t length : wrongLengths(6)) {
    EXPECT_INVALID("jc_robot_set_tool_wrench", "wrench", jc_robot_set_tool_wrench(robot_, wrench, length));
    EXPECT_INVALID("jc_plant_set_tool_wrench", "wrench", jc_plant_set_tool_wrench(plant_, wrench, length));
  }
  wrench[4] = kInf;
  EXPECT_INVALID("jc_robot_set_tool_wrench", "wrench", jc_robot_set_tool_wrench(robot_, wrench, 6));
  EXPECT_INVALID("jc_plant_set_tool_wrench", "wrench", jc_plant_set_tool_wrench(plant_, wrench, 6));
  // The refused conditions changed nothing: the robot still predicts what a fresh one does.
  double errors[kDof], fresh_errors[kDof];
  ASSERT_EQ(jc_predict_joint_errors(robot_, nullptr, kPosture, kDof, nullptr, 0, errors, kDof), JC_OK);
  ASSERT_EQ(jc_predict_joint_errors(healthy_robot_, nullptr, kPosture, kDof, nullptr, 0, fresh_errors, kDof), JC_OK);
  EXPECT_EQ(std::memcmp(errors, fresh_errors, sizeof errors), 0);
}

// ---- The plant ---------------------------------------------------------------------------------------------

TEST_F(CapiMisuse, PlantCallsBeforeResetAreSafe) {
  // Before the first reset the plant is at rest at zero, at t = 0; nothing may crash or produce NaN.
  double time = -1.0, values[5 * kDof];
  EXPECT_EQ(jc_plant_time(plant_, &time), JC_OK);
  EXPECT_EQ(time, 0.0);
  EXPECT_EQ(jc_plant_state(plant_, values, 5 * kDof), JC_OK);
  for (double x : values) EXPECT_TRUE(std::isfinite(x));
  const jc_status advanced = jc_plant_advance(plant_, 0.01);
  if (advanced != JC_OK) {
    EXPECT_FALSE(lastError().empty());
  }
  EXPECT_EQ(jc_plant_link_positions(plant_, values, kDof), JC_OK);
  for (int j = 0; j < kDof; ++j) EXPECT_TRUE(std::isfinite(values[j]));
  EXPECT_EQ(jc_plant_motor_torques(plant_, values, kDof), JC_OK);
  for (int j = 0; j < kDof; ++j) EXPECT_TRUE(std::isfinite(values[j]));
}

TEST_F(CapiMisuse, PlantRefusesBadTimesAndInputs) {
  Buffers buffers;
  ASSERT_EQ(jc_plant_reset(plant_, kPosture, kDof, 1.0), JC_OK);
  for (double end : {kNaN, kInf, -kInf, 1.0, 0.5, -1e300}) {
    EXPECT_INVALID("jc_plant_advance", "", jc_plant_advance(plant_, end)) << "end_time " << end;
  }
  double time = 0.0;
  ASSERT_EQ(jc_plant_time(plant_, &time), JC_OK);
  EXPECT_EQ(time, 1.0) << "a refused advance moved the plant";
  EXPECT_INVALID("jc_plant_reset", "start_time", jc_plant_reset(plant_, kPosture, kDof, kNaN));
  EXPECT_INVALID("jc_plant_reset", "command", jc_plant_reset(plant_, nullptr, kDof, 0.0));
  for (int32_t length : wrongLengths(kDof)) {
    EXPECT_INVALID("jc_plant_reset", "command", jc_plant_reset(plant_, kPosture, length, 0.0));
    EXPECT_INVALID("jc_plant_set_reference", "position",
                   jc_plant_set_reference(plant_, kPosture, length, kPosture, kDof));
    EXPECT_INVALID("jc_plant_set_reference", "velocity",
                   jc_plant_set_reference(plant_, kPosture, kDof, kPosture, length));
    EXPECT_INVALID("jc_plant_link_positions", "values", jc_plant_link_positions(plant_, buffers.a.data(), length));
    EXPECT_INVALID("jc_plant_motor_torques", "values", jc_plant_motor_torques(plant_, buffers.a.data(), length));
  }
  const double nan_position[kDof] = {0, kNaN, 0, 0, 0, 0};
  EXPECT_INVALID("jc_plant_set_reference", "position",
                 jc_plant_set_reference(plant_, nan_position, kDof, kPosture, kDof));
  EXPECT_INVALID("jc_plant_set_reference", "velocity",
                 jc_plant_set_reference(plant_, kPosture, kDof, nan_position, kDof));
  for (int32_t length : wrongLengths(5 * kDof)) {
    EXPECT_INVALID("jc_plant_state", "state", jc_plant_state(plant_, buffers.a.data(), length));
  }
  for (int32_t length : wrongLengths(5)) {
    EXPECT_INVALID("jc_plant_statistics", "counts", jc_plant_statistics(plant_, buffers.counts, length));
  }
  EXPECT_INVALID("jc_plant_statistics", "counts", jc_plant_statistics(plant_, nullptr, 5));
  EXPECT_INVALID("jc_plant_time", "time", jc_plant_time(plant_, nullptr));
  EXPECT_INVALID("jc_plant_dof", "dof", jc_plant_dof(plant_, nullptr));
  EXPECT_TRUE(buffers.untouched());
  ASSERT_EQ(jc_plant_time(plant_, &time), JC_OK);
  EXPECT_EQ(time, 1.0);
}

TEST_F(CapiMisuse, SnapshotsRefuseForeignOrDamagedData) {
  int32_t size = 0;
  ASSERT_EQ(jc_plant_snapshot_size(plant_, &size), JC_OK);
  ASSERT_EQ(size, 10 * kDof + 14);
  ASSERT_EQ(jc_plant_reset(plant_, kPosture, kDof, 0.0), JC_OK);
  ASSERT_EQ(jc_plant_advance(plant_, 0.01), JC_OK);
  std::vector<double> snapshot(static_cast<std::size_t>(size));
  ASSERT_EQ(jc_plant_save(plant_, snapshot.data(), size), JC_OK);
  for (int32_t length : wrongLengths(size)) {
    EXPECT_INVALID("jc_plant_save", "snapshot", jc_plant_save(plant_, snapshot.data(), length));
    EXPECT_INVALID("jc_plant_restore", "snapshot", jc_plant_restore(plant_, snapshot.data(), length));
  }
  EXPECT_INVALID("jc_plant_save", "snapshot", jc_plant_save(plant_, nullptr, size));
  EXPECT_INVALID("jc_plant_restore", "snapshot", jc_plant_restore(plant_, nullptr, size));
  // Damage every field in turn: a NaN anywhere, a wrong format, a wrong joint count, a negative mass.
  std::vector<std::vector<double>> damaged;
  for (std::size_t k = 0; k < snapshot.size(); ++k) {
    damaged.push_back(snapshot);
    damaged.back()[k] = kNaN;
  }
  for (double format : {0.0, 2.0, -1.0, 1e308}) {
    damaged.push_back(snapshot);
    damaged.back()[0] = format;
  }
  for (double dof : {0.0, 5.0, 7.0, -6.0}) {
    damaged.push_back(snapshot);
    damaged.back()[1] = dof;
  }
  damaged.push_back(snapshot);
  damaged.back()[static_cast<std::size_t>(size) - 4] = -1.0;  // payload mass
  double before[5 * kDof], after[5 * kDof];
  ASSERT_EQ(jc_plant_state(plant_, before, 5 * kDof), JC_OK);
  for (const std::vector<double>& bad : damaged) {
    EXPECT_INVALID("jc_plant_restore", "snapshot", jc_plant_restore(plant_, bad.data(), size));
  }
  ASSERT_EQ(jc_plant_state(plant_, after, 5 * kDof), JC_OK);
  EXPECT_EQ(std::memcmp(before, after, sizeof before), 0) << "a refused restore changed the plant";
  EXPECT_EQ(jc_plant_restore(plant_, snapshot.data(), size), JC_OK) << lastError();
}

TEST_F(CapiMisuse, SpiralCallsRefuseBadOutputs) {
  int32_t m = 0;
  ASSERT_EQ(jc_spiral_sample_count(robot_, &m), JC_OK);
  ASSERT_GT(m, 0);
  Buffers buffers;
  EXPECT_INVALID("jc_spiral_sample_count", "count", jc_spiral_sample_count(robot_, nullptr));
  // Two lengths only: each refused call plans the whole spiral first (seconds under sanitizers).
  for (int32_t length : {m - 1, kHugeLength}) {
    EXPECT_INVALID("jc_spiral_plan", "time",
                   jc_spiral_plan(robot_, buffers.a.data(), length, nullptr, 0, nullptr, 0, nullptr, 0));
  }
  EXPECT_INVALID("jc_spiral_plan", "time", jc_spiral_plan(robot_, nullptr, m, nullptr, 0, nullptr, 0, nullptr, 0));
  for (int32_t length : wrongLengths(15)) {
    EXPECT_INVALID("jc_spiral_experiment", "metrics",
                   jc_spiral_experiment(robot_, 0, buffers.a.data(), length, nullptr, 0));
  }
  for (int32_t use_plant : {-1, 2, kHugeLength}) {
    EXPECT_INVALID("jc_spiral_experiment", "use_plant",
                   jc_spiral_experiment(robot_, use_plant, buffers.a.data(), 15, nullptr, 0));
  }
  EXPECT_TRUE(buffers.untouched());
}

// ---- Library queries -----------------------------------------------------------------------------------

TEST_F(CapiMisuse, QueriesNeverFail) {
  for (jc_status status : {0, -1, -7, -8, 1, 12345, std::numeric_limits<int32_t>::min()}) {
    const char* name = jc_status_name(status);
    ASSERT_NE(name, nullptr);
    EXPECT_GT(std::strlen(name), 0u);
  }
  EXPECT_STREQ(jc_status_name(-999), "JC_UNKNOWN_STATUS");
  EXPECT_EQ(jc_abi_version(), JC_ABI_VERSION);
  ASSERT_NE(jc_version(), nullptr);
  // A successful call clears the message of the last failed one.
  int32_t dof = 0;
  EXPECT_NE(jc_robot_dof(nullptr, &dof), JC_OK);
  EXPECT_FALSE(lastError().empty());
  EXPECT_EQ(jc_robot_dof(robot_, &dof), JC_OK);
  EXPECT_EQ(lastError(), "");
}

}  // namespace
