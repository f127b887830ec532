// Shared helpers of the robot-layer tests: the shipped robots, seeded random configurations, and small
// geometric helpers written independently of the library (rotation vectors, angle wrapping).
#pragma once

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include <Eigen/Geometry>

#include "model/common/types.hpp"
#include "model/robot/load_urdf.hpp"
#include "model/robot/robot.hpp"

namespace jointcomp {
namespace testing_support {

constexpr double kPi = 3.14159265358979323846;

inline std::string rx170Path() { return std::string(JOINTCOMP_DATA_DIR) + "/robots/rx170.urdf"; }
inline std::string ur10Path() { return std::string(JOINTCOMP_DATA_DIR) + "/robots/ur10.urdf"; }
inline std::string urdfTestFile(const std::string& name) {
  return std::string(JOINTCOMP_TEST_DATA_DIR) + "/urdf/" + name;
}

// Loaded once per test binary; Robot is immutable, so sharing it between tests is safe.
inline const Robot& rx170() {
  static const Robot robot = loadRobotFromUrdfFile(rx170Path());
  return robot;
}
inline const Robot& ur10() {
  static const Robot robot = loadRobotFromUrdfFile(ur10Path());
  return robot;
}

// Uniform random configuration within the joint limits shrunk by `margin` on each side (continuous
// joints: within +-pi).
inline JointVector randomConfiguration(const Robot& robot, std::mt19937& rng, double margin = 0.0) {
  JointVector q(robot.dof());
  for (int i = 0; i < robot.dof(); ++i) {
    double lower = robot.joints[i].lower;
    double upper = robot.joints[i].upper;
    if (!std::isfinite(lower)) lower = -kPi;
    if (!std::isfinite(upper)) upper = kPi;
    std::uniform_real_distribution<double> uniform(lower + margin, upper - margin);
    q[i] = uniform(rng);
  }
  return q;
}

inline JointVector randomVector(int size, std::mt19937& rng, double magnitude) {
  std::uniform_real_distribution<double> uniform(-magnitude, magnitude);
  JointVector v(size);
  for (int i = 0; i < size; ++i) v[i] = uniform(rng);
  return v;
}

// Rotation vector (axis times angle) of a rotation matrix, from the quaternion so that it is accurate for
// small angles too.
inline Eigen::Vector3d rotationVector(const Eigen::Matrix3d& rotation) {
  Eigen::Quaterniond quaternion(rotation);
  if (quaternion.w() < 0.0) quaternion.coeffs() = -quaternion.coeffs();
  const Eigen::Vector3d v = quaternion.vec();
  const double s = v.norm();
  if (s < 1e-300) return Eigen::Vector3d::Zero();
  return (2.0 * std::atan2(s, quaternion.w()) / s) * v;
}

// Angle of the rotation taking `a` to `b` (0 for equal rotations).
inline double rotationDistance(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return rotationVector(b * a.transpose()).norm();
}

// a - b wrapped into (-pi, pi].
inline double angleDifference(double a, double b) { return std::remainder(a - b, 2.0 * kPi); }

inline double maxWrappedDifference(const JointVector& a, const JointVector& b) {
  double largest = 0.0;
  for (int i = 0; i < a.size(); ++i) largest = std::max(largest, std::abs(angleDifference(a[i], b[i])));
  return largest;
}

// The RX170 with every joint axis tilted, every placement turned, and gravity off the vertical: for the
// general-axis paths of the kinematics and the dynamics (the shipped robots' axes are all z).
inline Robot tiltedRx170() {
  Robot robot = rx170();
  std::mt19937 rng(205u);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (Joint& joint : robot.joints) {
    joint.axis = Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
    joint.placement.linear() =
        (Eigen::AngleAxisd(0.7 * normal(rng), Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized()) *
         joint.placement.linear())
            .eval();
  }
  robot.gravity = Eigen::Vector3d(1.2, -0.8, -9.7);
  return robot;
}

}  // namespace testing_support
}  // namespace jointcomp
