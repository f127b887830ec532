// Vector and matrix types sized for serial arms. Joint-space objects have a compile-time maximum size,
// so they live on the stack and the hot paths never touch the heap, whatever the robot's dof.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace jointcomp {

// Largest number of joints a chain may have. Industrial arms have 6 or 7.
constexpr int kMaxJoints = 12;

using JointVector = Eigen::Matrix<double, Eigen::Dynamic, 1, Eigen::ColMajor, kMaxJoints, 1>;
using JointMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::ColMajor, kMaxJoints, kMaxJoints>;
// Geometric Jacobian: rows 0-2 linear velocity of the tool point, rows 3-5 angular velocity, both in
// the base frame.
using Jacobian = Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::ColMajor, 6, kMaxJoints>;
// Wrench or twist: force (or linear velocity) first, then moment (or angular velocity).
using Vector6 = Eigen::Matrix<double, 6, 1>;

}  // namespace jointcomp
