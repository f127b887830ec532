#include "model/robot/inverse_kinematics.hpp"

#include <cmath>
#include <sstream>

#include <Eigen/Cholesky>
#include <Eigen/SVD>

#include "model/common/errors.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kGeometryTolerance = 1e-9;  // m and rad: how exactly the URDF must match the structure

Eigen::Vector3d projectOff(const Eigen::Vector3d& axis, const Eigen::Vector3d& v) { return v - axis * axis.dot(v); }

// Paden-Kahan subproblem 1: the rotation about `axis` (through the origin) that takes p to q's direction.
double rotationTaking(const Eigen::Vector3d& axis, const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  const Eigen::Vector3d pp = projectOff(axis, p);
  const Eigen::Vector3d qq = projectOff(axis, q);
  return std::atan2(axis.dot(pp.cross(qq)), pp.dot(qq));
}

Eigen::Matrix3d rotation(const Eigen::Vector3d& axis, double angle) {
  return Eigen::AngleAxisd(angle, axis).toRotationMatrix();
}

// Closest points of two lines; returns the distance between them and the midpoint.
double lineDistance(const Eigen::Vector3d& p1, const Eigen::Vector3d& d1, const Eigen::Vector3d& p2,
                    const Eigen::Vector3d& d2, Eigen::Vector3d& midpoint) {
  const Eigen::Vector3d n = d1.cross(d2);
  if (n.norm() < kGeometryTolerance) {  // parallel
    midpoint = p1;
    return projectOff(d1, p2 - p1).norm();
  }
  const Eigen::Vector3d w = p2 - p1;
  const double t1 = w.cross(d2).dot(n) / n.squaredNorm();
  const double t2 = w.cross(d1).dot(n) / n.squaredNorm();
  const Eigen::Vector3d a = p1 + t1 * d1;
  const Eigen::Vector3d b = p2 + t2 * d2;
  midpoint = 0.5 * (a + b);
  return (a - b).norm();
}

std::string describe(const Eigen::Isometry3d& target) {
  std::ostringstream text;
  const Eigen::Vector3d p = target.translation();
  text << "target position (" << p.x() << ", " << p.y() << ", " << p.z() << ") m";
  return text.str();
}

}  // namespace

InverseKinematics::InverseKinematics(const Robot& robot, IkOptions options)
    : robot_(robot), options_(options), ws_(robot) {
  if (robot.dof() != 6) return;
  JointVector zero = JointVector::Zero(6);
  forwardKinematics(robot, ws_, zero);
  axis1_ = ws_.axis[0];
  point1_ = ws_.origin[0];
  axis2_ = ws_.axis[1];
  point2_ = ws_.origin[1];
  point3_ = ws_.origin[2];
  tool_at_zero_ = ws_.tool_pose;
  for (int k = 0; k < 3; ++k) wrist_axis_[k] = ws_.axis[3 + k];
  Eigen::Vector3d meet45, meet56;
  const bool parallel23 = axis2_.cross(ws_.axis[2]).norm() < kGeometryTolerance;
  const bool axis1_not_parallel_2 = axis1_.cross(axis2_).norm() > 1e-6;
  const bool wrist_axes_distinct =
      wrist_axis_[0].cross(wrist_axis_[1]).norm() > 1e-6 && wrist_axis_[1].cross(wrist_axis_[2]).norm() > 1e-6;
  const bool wrist_meets =
      wrist_axes_distinct &&
      lineDistance(ws_.origin[3], wrist_axis_[0], ws_.origin[4], wrist_axis_[1], meet45) < kGeometryTolerance &&
      lineDistance(ws_.origin[4], wrist_axis_[1], ws_.origin[5], wrist_axis_[2], meet56) < kGeometryTolerance &&
      (meet45 - meet56).norm() < kGeometryTolerance;
  const bool planar_arm =
      projectOff(axis2_, point3_ - point2_).norm() > 1e-6 && projectOff(axis2_, meet45 - point3_).norm() > 1e-6;
  closed_form_ = parallel23 && axis1_not_parallel_2 && wrist_meets && planar_arm;
  if (!closed_form_) return;
  wrist_centre_ = meet45;

  // Trust the closed form only once it has reproduced a few configurations exactly.
  const IkOptions saved = options_;
  options_.respect_limits = false;
  for (int trial = 0; trial < 4 && closed_form_; ++trial) {
    JointVector q(6);
    for (int i = 0; i < 6; ++i) q[i] = 0.3 + 0.37 * trial - 0.21 * i + 0.05 * i * trial;
    forwardKinematics(robot_, ws_, q);
    std::array<IkSolution, 8> solutions;
    int count = 0;
    try {
      count = allSolutions(ws_.tool_pose, q, solutions);
    } catch (const Error&) {
      count = 0;
    }
    bool found = false;
    for (int s = 0; s < count; ++s) found = found || (solutions[s].q - q).cwiseAbs().maxCoeff() < 1e-7;
    closed_form_ = found;
  }
  options_ = saved;
}

bool InverseKinematics::wrapIntoLimits(JointVector& q, const JointVector& seed) const {
  for (int i = 0; i < q.size(); ++i) {
    // The 2 pi multiple nearest the seed, then the nearest one inside the limits, if any.
    double value = q[i] + 2.0 * kPi * std::round((seed[i] - q[i]) / (2.0 * kPi));
    if (!options_.respect_limits) {
      q[i] = value;
      continue;
    }
    const Joint& joint = robot_.joints[i];
    if (value < joint.lower) value += 2.0 * kPi * std::ceil((joint.lower - value) / (2.0 * kPi));
    if (value > joint.upper) value -= 2.0 * kPi * std::ceil((value - joint.upper) / (2.0 * kPi));
    if (value < joint.lower - 1e-12 || value > joint.upper + 1e-12) return false;
    q[i] = value;
  }
  return true;
}

int InverseKinematics::shoulderAngles(const Eigen::Isometry3d& target, const Eigen::Vector3d& wrist_target,
                                      const JointVector& seed, double q1_candidates[2], bool& singular) const {
  // Joint 1: the component of (wrist - point1) along the rotated axis 2 is fixed by the geometry.
  const Eigen::Vector3d u = wrist_target - point1_;
  const Eigen::Vector3d axis2_perp = projectOff(axis1_, axis2_);
  const double along = axis1_.dot(axis2_);
  const double cos_coefficient = axis2_perp.dot(u);
  const double sin_coefficient = axis1_.cross(axis2_perp).dot(u);
  const double wanted = axis2_.dot(wrist_centre_ - point1_) - along * axis1_.dot(u);
  const double radius = std::hypot(cos_coefficient, sin_coefficient);
  int q1_count = 0;
  if (radius < kGeometryTolerance) {
    if (std::abs(wanted) > 1e-9) throw UnreachableError(describe(target) + " is out of reach (wrist centre)");
    singular = true;  // wrist centre on axis 1: joint 1 is free, keep the seed
    q1_candidates[q1_count++] = seed[0];
  } else {
    const double ratio = wanted / radius;
    if (std::abs(ratio) > 1.0 + 1e-12) throw UnreachableError(describe(target) + " is out of reach (wrist centre)");
    const double phase = std::atan2(sin_coefficient, cos_coefficient);
    const double spread = std::acos(std::max(-1.0, std::min(1.0, ratio)));
    q1_candidates[q1_count++] = phase + spread;
    if (spread > 1e-12) q1_candidates[q1_count++] = phase - spread;
  }
  return q1_count;
}

void InverseKinematics::addWristSolutions(const Eigen::Isometry3d& target, const JointVector& seed,
                                          const std::array<double, 3>& arm, bool arm_singular,
                                          std::array<IkSolution, 8>& solutions, int& count) {
  const Eigen::Matrix3d rotation_zero = tool_at_zero_.linear();
  // Wrist: Rot(u4,q4) Rot(u5,q5) Rot(u6,q6) = desired, with the axes at q = 0 (product of exponentials).
  const Eigen::Matrix3d r123 = rotation(axis1_, arm[0]) * rotation(axis2_, arm[1]) * rotation(axis2_, arm[2]);
  const Eigen::Matrix3d desired = r123.transpose() * target.linear() * rotation_zero.transpose();
  const Eigen::Vector3d& u4 = wrist_axis_[0];
  const Eigen::Vector3d& u5 = wrist_axis_[1];
  const Eigen::Vector3d& u6 = wrist_axis_[2];
  const Eigen::Vector3d p = u6;
  const Eigen::Vector3d goal = desired * u6;
  // Paden-Kahan subproblem 2: Rot(u4,q4) Rot(u5,q5) p = goal through c = Rot(u5,q5) p.
  const double cross45 = u4.dot(u5);
  const double denominator = cross45 * cross45 - 1.0;
  const double alpha = (cross45 * u5.dot(p) - u4.dot(goal)) / denominator;
  const double beta = (cross45 * u4.dot(goal) - u5.dot(p)) / denominator;
  const Eigen::Vector3d normal = u4.cross(u5);
  double gamma_squared =
      (p.squaredNorm() - alpha * alpha - beta * beta - 2.0 * alpha * beta * cross45) / normal.squaredNorm();
  if (gamma_squared < -1e-10) return;  // this wrist cannot reach that orientation
  gamma_squared = std::max(0.0, gamma_squared);
  const double gamma_values[2] = {std::sqrt(gamma_squared), -std::sqrt(gamma_squared)};
  for (int c = 0; c < (gamma_squared > 1e-20 ? 2 : 1); ++c) {
    const Eigen::Vector3d via = alpha * u4 + beta * u5 + gamma_values[c] * normal;
    const double q5 = rotationTaking(u5, p, via);
    bool wrist_singular = projectOff(u4, via).norm() < 1e-9;
    const double q4 = wrist_singular ? seed[3] : rotationTaking(u4, via, goal);
    const Eigen::Matrix3d remaining = (rotation(u4, q4) * rotation(u5, q5)).transpose() * desired;
    const Eigen::Vector3d normal_to_6 = std::abs(u6.x()) < 0.9 ? u6.cross(Eigen::Vector3d::UnitX()).normalized()
                                                               : u6.cross(Eigen::Vector3d::UnitY()).normalized();
    const double q6 = rotationTaking(u6, normal_to_6, remaining * normal_to_6);
    IkSolution solution;
    solution.q.resize(6);
    solution.q << arm[0], arm[1], arm[2], q4, q5, q6;
    solution.singular = arm_singular || wrist_singular;
    if (!wrapIntoLimits(solution.q, seed)) continue;
    forwardKinematics(robot_, ws_, solution.q);
    const Vector6 error = poseError(ws_.tool_pose, target);
    if (error.head<3>().norm() > 1e-7 || error.tail<3>().norm() > 1e-7) continue;
    if (count < 8) solutions[count++] = solution;
  }
}

int InverseKinematics::allSolutions(const Eigen::Isometry3d& target, const JointVector& seed,
                                    std::array<IkSolution, 8>& solutions) {
  if (!closed_form_) {
    throw InvalidArgument("robot '" + robot_.name +
                          "' has no closed-form inverse kinematics (joints 2 and 3 "
                          "parallel and a spherical wrist are needed); use solve()");
  }
  checkJointVector(robot_, seed, "seed");
  if (!target.matrix().allFinite()) throw InvalidArgument("inverse kinematics target is not finite");
  // The wrist centre is fixed in the tool frame.
  const Eigen::Vector3d wrist_target = target * (tool_at_zero_.inverse() * wrist_centre_);

  // Joint 1: one or two angles put the wrist centre in the plane of axes 2 and 3.
  double q1_candidates[2];
  bool shoulder_singular = false;
  const int q1_count = shoulderAngles(target, wrist_target, seed, q1_candidates, shoulder_singular);

  // Joints 2 and 3: a planar two-link arm about the parallel axes 2 and 3.
  const Eigen::Vector3d upper_arm = projectOff(axis2_, point3_ - point2_);
  const Eigen::Vector3d forearm = projectOff(axis2_, wrist_centre_ - point3_);
  const double l1 = upper_arm.norm();
  const double l2 = forearm.norm();
  const double forearm_angle = rotationTaking(axis2_, upper_arm, forearm);

  int count = 0;
  bool any_reachable_position = false;
  for (int a = 0; a < q1_count; ++a) {
    const double q1 = q1_candidates[a];
    const Eigen::Matrix3d r1 = rotation(axis1_, q1);
    const Eigen::Vector3d reach = projectOff(axis2_, point1_ + r1.transpose() * (wrist_target - point1_) - point2_);
    const double distance = reach.norm();
    double cos_elbow = (distance * distance - l1 * l1 - l2 * l2) / (2.0 * l1 * l2);
    if (std::abs(cos_elbow) > 1.0 + 1e-10) continue;
    any_reachable_position = true;
    const bool stretched = std::abs(cos_elbow) > 1.0 - 1e-14;
    cos_elbow = std::max(-1.0, std::min(1.0, cos_elbow));
    const double elbow = std::acos(cos_elbow);
    const double elbow_candidates[2] = {elbow - forearm_angle, -elbow - forearm_angle};
    for (int b = 0; b < (stretched ? 1 : 2); ++b) {
      const double q3 = elbow_candidates[b];
      const Eigen::Vector3d arm = upper_arm + rotation(axis2_, q3) * forearm;
      const double q2 = rotationTaking(axis2_, arm, reach);
      addWristSolutions(target, seed, {q1, q2, q3}, shoulder_singular || stretched, solutions, count);
    }
  }
  if (!any_reachable_position) throw UnreachableError(describe(target) + " is out of reach of the arm");
  return count;
}

IkSolution InverseKinematics::solve(const Eigen::Isometry3d& target, const JointVector& seed) {
  checkJointVector(robot_, seed, "seed");
  if (!target.matrix().allFinite()) throw InvalidArgument("inverse kinematics target is not finite");
  if (!closed_form_) return solveNumerically(target, seed);
  std::array<IkSolution, 8> solutions;
  const int count = allSolutions(target, seed, solutions);
  if (count == 0) throw UnreachableError(describe(target) + " is reachable only beyond the joint limits");
  int best = 0;
  double best_distance = (solutions[0].q - seed).squaredNorm();
  for (int s = 1; s < count; ++s) {
    const double distance = (solutions[s].q - seed).squaredNorm();
    if (distance < best_distance) {
      best = s;
      best_distance = distance;
    }
  }
  return solutions[best];
}

IkSolution InverseKinematics::solveNumerically(const Eigen::Isometry3d& target, const JointVector& seed) {
  // Levenberg-Marquardt on the 6-D pose error: damping grows when a step makes things worse, so the
  // iteration stays bounded near singularities instead of jumping.
  const int n = robot_.dof();
  JointVector q = seed;
  Jacobian jacobian;
  double damping = options_.damping;
  forwardKinematics(robot_, ws_, q);
  Vector6 error = poseError(ws_.tool_pose, target);
  double cost = error.squaredNorm();
  bool singular = false;
  for (int iteration = 0; iteration < options_.max_iterations; ++iteration) {
    if (error.head<3>().norm() < options_.position_tolerance &&
        error.tail<3>().norm() < options_.orientation_tolerance) {
      IkSolution solution{q, singular};
      if (options_.respect_limits && !wrapIntoLimits(solution.q, seed)) {
        throw UnreachableError(describe(target) + " is reachable only beyond the joint limits");
      }
      return solution;
    }
    toolJacobian(robot_, ws_, jacobian);
    const Eigen::Matrix<double, 6, 6> jjt = jacobian * jacobian.transpose();
    Eigen::JacobiSVD<Eigen::Matrix<double, 6, 6>> svd(jjt);
    singular = svd.singularValues()(5) < 1e-10 * std::max(1.0, svd.singularValues()(0));
    const Eigen::Matrix<double, 6, 6> damped = jjt + damping * Eigen::Matrix<double, 6, 6>::Identity();
    const JointVector step = jacobian.transpose() * damped.ldlt().solve(error);
    JointVector trial = q + step;
    if (options_.respect_limits) {
      for (int i = 0; i < n; ++i)
        trial[i] = std::min(robot_.joints[i].upper, std::max(robot_.joints[i].lower, trial[i]));
    }
    forwardKinematics(robot_, ws_, trial);
    const Vector6 trial_error = poseError(ws_.tool_pose, target);
    const double trial_cost = trial_error.squaredNorm();
    if (trial_cost < cost) {
      q = trial;
      error = trial_error;
      cost = trial_cost;
      damping = std::max(options_.damping, damping * 0.3);
    } else {
      damping = std::min(1e6, damping * 10.0);
      forwardKinematics(robot_, ws_, q);
    }
  }
  std::ostringstream text;
  text << describe(target) << " not reached: damped least squares stopped after " << options_.max_iterations
       << " iterations " << error.head<3>().norm() * 1e3 << " mm and " << error.tail<3>().norm()
       << " rad away (out of reach, beyond the limits, or a seed too far)";
  throw UnreachableError(text.str());
}

}  // namespace jointcomp
