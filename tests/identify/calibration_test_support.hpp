// Shared helpers of the kinematic-calibration tests: the shipped UR10, seeded random poses, a true
// parameter set moved from nominal by realistic amounts, and the IPA UR10 data of ../shared.
#pragma once

#include <algorithm>
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

// The target on the flange the simulated campaigns name.
inline const Eigen::Vector3d kNominalTarget(0.0, 0.0, 0.1);

// The parameters a noise-free calibration on these poses identifies.
inline std::vector<std::string> identifiedOn(const std::vector<JointVector>& poses) {
  DeterministicRandom random(1);
  GeometricParameters truth = GeometricParameters::zero(6);
  truth.setInstrumentFromBase(trackerFrame(random));
  truth.target = kNominalTarget;
  const MeasurementCampaign campaign = simulateGeometricCampaign(ur10Model(), truth, poses, 1e-9, 1, kNominalTarget);
  GeometricCalibrationOptions options;
  options.loss = RobustLoss::None;
  const GeometricCalibrationResult result = calibrateGeometry(ur10Model(), campaign, options);
  std::vector<std::string> names;
  for (const ParameterEstimate& p : result.parameters) {
    // Zero true compliances come out of the noise-free fit as +-1e-12: those held for not being positive
    // are identifiable all the same.
    if (p.identified || p.fixed_because.find("not positive") != std::string::npos) names.push_back(p.name);
  }
  return names;
}

// The truth: a random tracker frame and target, and every identified robot parameter moved by a
// realistic amount (the others stay nominal: what the data cannot see, no calibration can recover).
inline GeometricParameters randomTruth(const std::vector<std::string>& identified, DeterministicRandom& random) {
  const std::vector<std::string> names = geometricParameterNames(*ur10());
  Eigen::VectorXd x = GeometricParameters::zero(6).toVector();
  GeometricParameters frame = GeometricParameters::zero(6);
  frame.setInstrumentFromBase(trackerFrame(random));
  x.head<3>() = frame.frame_translation;
  x.segment<3>(3) = frame.frame_rotation;
  x.segment<3>(6) = kNominalTarget;
  for (std::size_t i = 6; i < names.size(); ++i) {
    if (std::find(identified.begin(), identified.end(), names[i]) == identified.end()) continue;
    const std::string unit = geometricParameterUnit(names[i]);
    const Eigen::Index k = static_cast<Eigen::Index>(i);
    // Compliance: joints 2 and 3 as the UR10's (about 8e-6 rad/(N m)); the wrist joints, which carry
    // little torque, softer, so that the truth stays many sigma above zero.
    if (unit == "rad/(N m)")
      x[k] = names[i].rfind("joint_2", 0) == 0 || names[i].rfind("joint_3", 0) == 0 ? random.uniform(4e-6, 1.2e-5)
                                                                                    : random.uniform(2e-4, 4e-4);
    else if (unit == "rad")
      x[k] += random.uniform(-1e-3, 1e-3);
    else
      x[k] += random.uniform(-1e-3, 1e-3);
  }
  return GeometricParameters::fromVector(x, 6);
}

}  // namespace calibration_test
}  // namespace jointcomp
