// From a feed-rate-planned tool path to a joint trajectory, through inverse kinematics at a fixed tool
// orientation, each point seeded by the previous one so that the arm stays on one branch.
#pragma once

#include <vector>

#include "model/compensation/feed_rate.hpp"
#include "model/robot/inverse_kinematics.hpp"

namespace jointcomp {

struct JointTrajectory {
  std::vector<double> time;                    // s
  std::vector<Eigen::Vector3d> tool_position;  // m, the planned tool point
  std::vector<JointVector> q;                  // rad
  std::vector<JointVector> qd;                 // rad/s, central differences
  std::size_t size() const { return time.size(); }
};

// Throws UnreachableError naming the sample (index, time, position) that inverse kinematics cannot
// reach, and SolverError where consecutive samples jump by more than `max_joint_step` rad (a branch
// change or a singularity on the way).
JointTrajectory planJointTrajectory(const Robot& robot, const std::vector<FeedRateSample>& samples,
                                    const Eigen::Matrix3d& tool_orientation, const JointVector& seed,
                                    double max_joint_step = 0.05);

// The tool pointing straight down (tool z along -Z of the base), the pose of the paper's test.
Eigen::Matrix3d toolPointingDown();

}  // namespace jointcomp
