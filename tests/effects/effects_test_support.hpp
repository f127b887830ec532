// Shared helpers of the effects-layer tests: the shipped RX170 with its parameter file, the file read
// again as plain JSON (so that tests take their expected values from the file, not from the library),
// and seeded random configurations.
#pragma once

#include <cmath>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "model/common/types.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/load_urdf.hpp"
#include "model/robot/robot.hpp"

namespace jointcomp {
namespace effects_test {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;

inline std::string rx170UrdfPath() { return std::string(JOINTCOMP_DATA_DIR) + "/robots/rx170.urdf"; }
inline std::string rx170ParametersPath() { return std::string(JOINTCOMP_DATA_DIR) + "/params/rx170.json"; }

inline std::shared_ptr<const Robot> rx170() {
  static const std::shared_ptr<const Robot> robot =
      std::make_shared<const Robot>(loadRobotFromUrdfFile(rx170UrdfPath()));
  return robot;
}

// A fresh copy each time, so that a test may change it.
inline JointErrorModel rx170Model() { return loadParameterFile(rx170ParametersPath(), rx170()); }

// The parameter file as plain JSON, read with nlohmann directly.
inline nlohmann::json rx170Json() {
  std::ifstream in(rx170ParametersPath());
  std::stringstream text;
  text << in.rdbuf();
  return nlohmann::json::parse(text.str());
}

// Index of a joint by name, found without the library.
inline int jointByName(const Robot& robot, const std::string& name) {
  for (int j = 0; j < robot.dof(); ++j) {
    if (robot.joints[j].name == name) return j;
  }
  return -1;
}

// Uniform random configuration within the joint limits shrunk by `margin`.
inline JointVector randomConfiguration(const Robot& robot, std::mt19937& rng, double margin = 0.05) {
  JointVector q(robot.dof());
  for (int i = 0; i < robot.dof(); ++i) {
    std::uniform_real_distribution<double> uniform(robot.joints[i].lower + margin, robot.joints[i].upper - margin);
    q[i] = uniform(rng);
  }
  return q;
}

}  // namespace effects_test
}  // namespace jointcomp
