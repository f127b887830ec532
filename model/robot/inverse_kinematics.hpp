// Inverse kinematics of the tool frame.
//
// Closed form for arms whose joints 2 and 3 are parallel and whose last three axes meet in a point
// (the Staubli RX, most industrial 6R arms): up to 8 solutions from the geometry found in the URDF at
// load time (joint 1 from the constant offset along axis 2, joints 2 and 3 as a planar two-link arm,
// the wrist by Paden-Kahan subproblems). Any other chain gets damped least squares from a seed.
#pragma once

#include <array>

#include "model/robot/workspace.hpp"

namespace jointcomp {

struct IkOptions {
  double position_tolerance = 1e-10;     // m
  double orientation_tolerance = 1e-10;  // rad
  int max_iterations = 200;              // damped least squares only
  // Damped least squares: the smallest lambda^2 added to J J^T. Levenberg-Marquardt raises it when a step
  // fails; it must stay far below sigma_min^2 near singularities or convergence slows to a crawl.
  double damping = 1e-12;
  bool respect_limits = true;  // drop solutions outside the joint limits
};

struct IkSolution {
  JointVector q;
  // True when the solution sits at a singularity (wrist axes 4 and 6 aligned, wrist centre on axis 1,
  // arm stretched): the redundant joint was kept at its seed value.
  bool singular = false;
};

class InverseKinematics {
public:
  explicit InverseKinematics(const Robot& robot, IkOptions options = {});

  bool hasClosedForm() const { return closed_form_; }
  const IkOptions& options() const { return options_; }

  // All closed-form solutions within the limits (if respect_limits), each wrapped by 2 pi to lie as
  // close to `seed` as the limits allow. Returns how many; throws InvalidArgument without closed form.
  int allSolutions(const Eigen::Isometry3d& target, const JointVector& seed, std::array<IkSolution, 8>& solutions);

  // The solution closest to `seed` (closed form when there is one, else damped least squares from the
  // seed). Throws UnreachableError naming the target and the residual when there is none.
  IkSolution solve(const Eigen::Isometry3d& target, const JointVector& seed);

private:
  IkSolution solveNumerically(const Eigen::Isometry3d& target, const JointVector& seed);
  bool wrapIntoLimits(JointVector& q, const JointVector& seed) const;
  // allSolutions' steps. Joint 1's one or two angles (in q1_candidates; returns how many) that put the wrist
  // centre at wrist_target in reach of the plane of axes 2 and 3; singular: the wrist centre on axis 1 (the
  // seed's angle, joint 1 is free).
  int shoulderAngles(const Eigen::Isometry3d& target, const Eigen::Vector3d& wrist_target, const JointVector& seed,
                     double q1_candidates[2], bool& singular) const;
  // The wrist angles (joints 4 to 6) that give target's orientation after joints 1 to 3 at `arm`: each solution
  // within the limits that reaches target goes into solutions[count++] (up to 8).
  void addWristSolutions(const Eigen::Isometry3d& target, const JointVector& seed, const std::array<double, 3>& arm,
                         bool arm_singular, std::array<IkSolution, 8>& solutions, int& count);

  const Robot& robot_;
  IkOptions options_;
  RobotWorkspace ws_;
  bool closed_form_ = false;
  // Closed-form geometry at q = 0, base frame.
  Eigen::Vector3d axis1_, point1_, axis2_, point2_, point3_, wrist_centre_;
  std::array<Eigen::Vector3d, 3> wrist_axis_;  // axes 4, 5, 6 at q = 0
  Eigen::Isometry3d tool_at_zero_;             // tool pose at q = 0
};

}  // namespace jointcomp
