// Shared helpers of the kinematic-calibration tests: the shipped UR10, seeded random poses, a true
// parameter set moved from nominal by realistic amounts, and the IPA UR10 data of ../shared.
#pragma once

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "model/common/random.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/identify/geometric_calibration.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp {
namespace calibration_test {

constexpr double kPi = 3.14159265358979323846;

inline std::shared_ptr<const Robot> ur10() {
  static const std::shared_ptr<const Robot> robot =
      std::make_shared<const Robot>(loadRobotFromUrdfFile(std::string(JOINTCOMP_DATA_DIR) + "/robots/ur10.urdf"));
  return robot;
}

inline JointErrorModel ur10Model() { return JointErrorModel(ur10(), GearTrain::direct(6), {}); }

// Poses spread over the workspace (joints 2 and 3 kept to the upper half-space side of the arm).
inline std::vector<JointVector> randomPoses(int count, std::uint64_t seed) {
  DeterministicRandom random(seed);
  std::vector<JointVector> poses;
  for (int k = 0; k < count; ++k) {
    JointVector q(6);
    q << random.uniform(-kPi, kPi), random.uniform(-2.6, -0.5), random.uniform(-2.4, 2.4), random.uniform(-kPi, kPi),
        random.uniform(-kPi, kPi), random.uniform(-kPi, kPi);
    poses.push_back(q);
  }
  return poses;
}

// An instrument frame a few metres away, turned about z (like a tracker on the floor) and tilted a little.
inline Eigen::Isometry3d trackerFrame(DeterministicRandom& random) {
  Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();
  frame.linear() = (Eigen::AngleAxisd(random.uniform(-kPi, kPi), Eigen::Vector3d::UnitZ()) *
                    Eigen::AngleAxisd(random.uniform(-0.02, 0.02), Eigen::Vector3d::UnitX()) *
                    Eigen::AngleAxisd(random.uniform(-0.02, 0.02), Eigen::Vector3d::UnitY()))
                       .toRotationMatrix();
  frame.translation() = Eigen::Vector3d(random.uniform(1.5, 3.0), random.uniform(-2.0, 2.0), random.uniform(-1.0, 0.5));
  return frame;
}

}  // namespace calibration_test
}  // namespace jointcomp
