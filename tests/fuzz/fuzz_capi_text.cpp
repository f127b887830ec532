// libFuzzer target: the C API's entry points that take text (not a path) from the caller. Any text
// yields JC_OK or an error status with a message, never a crash:
// - as the parameters of jc_robot_load_json (RX170 URDF); a robot that loads gives its parameters back as
//   JSON, and that JSON loads again and gives the same JSON;
// - as the `effects` selection of jc_predict_joint_errors, jc_compensate_point and jc_compensate_trajectory
//   on the shipped RX170 model;
// - as the options_json of every identification call and as the newline-separated campaign lists of
//   jc_calibrate and jc_discover (the campaigns named do not exist, so every call ends at the first file
//   it reads: options are checked before any file is opened); a failure leaves the outputs untouched.
// The text is the input up to its first NUL byte, as a C caller would pass it.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "jointcomp/jointcomp.h"

namespace {

constexpr const char* kUrdf = JOINTCOMP_DATA_DIR "/robots/rx170.urdf";
constexpr const char* kParameters = JOINTCOMP_DATA_DIR "/params/rx170.json";
constexpr int kDof = 6;
constexpr double kPosture[kDof] = {0.1, -0.4, 0.3, 0.2, 0.5, -0.1};

[[noreturn]] void die(const char* what) {
  std::fprintf(stderr, "fuzz_capi_text: %s (last error: %s)\n", what, jc_last_error());
  std::abort();
}

// A failed call must say why.
void expectFailureExplained(jc_status status) {
  if (status != JC_OK && jc_last_error()[0] == '\0') die("an error status without a message");
}

std::string parametersJson(jc_robot* robot) {
  std::int32_t length = 0;
  if (jc_robot_parameters_json(robot, nullptr, 0, &length) != JC_OK || length < 0) die("no parameter JSON length");
  std::string json(static_cast<std::size_t>(length) + 1, '\0');
  if (jc_robot_parameters_json(robot, json.data(), length + 1, &length) != JC_OK) die("no parameter JSON");
  json.resize(static_cast<std::size_t>(length));
  return json;
}

void fuzzParameters(const char* text) {
  jc_robot* robot = nullptr;
  const jc_status status = jc_robot_load_json(kUrdf, text, &robot);
  expectFailureExplained(status);
  if (status != JC_OK) {
    if (robot) die("jc_robot_load_json failed but returned a handle");
    return;
  }
  const std::string json = parametersJson(robot);
  jc_robot* again = nullptr;
  if (jc_robot_load_json(kUrdf, json.c_str(), &again) != JC_OK) die("the parameters a robot gives back do not load");
  if (parametersJson(again) != json) die("the parameters a robot gives back change when loaded again");
  // The loaded model is used, whatever it predicts (a solver may fail on absurd parameters).
  double errors[kDof];
  expectFailureExplained(jc_predict_joint_errors(robot, nullptr, kPosture, kDof, nullptr, 0, errors, kDof));
  if (jc_robot_free(again) != JC_OK || jc_robot_free(robot) != JC_OK) die("jc_robot_free failed");
}

void fuzzEffects(jc_robot* robot, const char* effects) {
  double errors[kDof], reference[kDof];
  std::int32_t iterations = 0;
  const jc_status predicted = jc_predict_joint_errors(robot, effects, kPosture, kDof, nullptr, 0, errors, kDof);
  expectFailureExplained(predicted);
  const jc_status compensated =
      jc_compensate_point(robot, effects, kPosture, kDof, nullptr, 0, reference, kDof, &iterations);
  expectFailureExplained(compensated);
  // A selection is valid or not whatever the call: the three calls agree on it.
  double planned[2 * kDof], references[2 * kDof];
  for (int k = 0; k < 2 * kDof; ++k) planned[k] = kPosture[k % kDof];
  const jc_status trajectory =
      jc_compensate_trajectory(robot, effects, planned, 2 * kDof, nullptr, 0, references, 2 * kDof, nullptr, nullptr);
  expectFailureExplained(trajectory);
  if ((predicted == JC_ERROR_INVALID_ARGUMENT) != (compensated == JC_ERROR_INVALID_ARGUMENT) ||
      (compensated == JC_ERROR_INVALID_ARGUMENT) != (trajectory == JC_ERROR_INVALID_ARGUMENT)) {
    die("the effect selection is accepted by one call and refused by another");
  }
  if (compensated == JC_OK) {
    for (int j = 0; j < kDof; ++j) {
      if (!std::isfinite(reference[j])) die("a compensated reference is not finite");
    }
  }
}

void expectUntouched(jc_status status, jc_robot* robot, jc_report* report) {
  expectFailureExplained(status);
  if (status == JC_OK) die("an identification call succeeded on a campaign that does not exist");
  if (robot || report) die("a failed identification call returned a handle");
}

void fuzzIdentificationText(jc_robot* robot, const char* text) {
  const char* missing = "/nonexistent/jointcomp-fuzz/campaign.csv";
  jc_robot* out = nullptr;
  jc_report* report = nullptr;
  expectUntouched(jc_identify_stiffness(robot, missing, text, &out, &report), out, report);
  expectUntouched(jc_identify_transmission_error(robot, missing, text, &out, &report), out, report);
  expectUntouched(jc_calibrate(robot, missing, text, text, &out, &report), out, report);
  expectUntouched(jc_discover(robot, text, nullptr, nullptr, &out, &report), out, report);
  expectUntouched(jc_discover(robot, missing, text, text, &out, &report), out, report);
  // Simulation writes a file when its options are valid: only invalid options reach it here, so that
  // the fuzzer never writes anywhere (a valid protocol is caught before: the path's folder is missing).
  const jc_status simulated = jc_simulate_campaign(robot, text, missing);
  expectFailureExplained(simulated);
  if (simulated == JC_OK) die("jc_simulate_campaign wrote into a folder that does not exist");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static jc_robot* const shipped = [] {
    jc_robot* robot = nullptr;
    if (jc_robot_load(kUrdf, kParameters, &robot) != JC_OK) die("cannot load the shipped RX170");
    return robot;
  }();
  const std::string text(reinterpret_cast<const char*>(data), size);
  fuzzParameters(text.c_str());
  fuzzEffects(shipped, text.c_str());
  fuzzIdentificationText(shipped, text.c_str());
  return 0;
}
