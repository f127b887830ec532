#include "model/compensation/joint_trajectory.hpp"

#include <sstream>

#include "model/common/errors.hpp"

namespace jointcomp {

Eigen::Matrix3d toolPointingDown() {
  return Eigen::AngleAxisd(3.14159265358979323846, Eigen::Vector3d::UnitX()).toRotationMatrix();
}

JointTrajectory planJointTrajectory(const Robot& robot, const std::vector<FeedRateSample>& samples,
                                    const Eigen::Matrix3d& tool_orientation, const JointVector& seed,
                                    double max_joint_step) {
  if (samples.empty()) throw InvalidArgument("planJointTrajectory: no samples");
  InverseKinematics ik(robot);
  JointTrajectory trajectory;
  trajectory.time.reserve(samples.size());
  trajectory.tool_position.reserve(samples.size());
  trajectory.q.reserve(samples.size());
  JointVector previous = seed;
  Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
  target.linear() = tool_orientation;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    target.translation() = samples[k].position;
    IkSolution solution;
    try {
      solution = ik.solve(target, previous);
    } catch (const UnreachableError& error) {
      std::ostringstream text;
      text << "path sample " << k << " (t = " << samples[k].t << " s): " << error.what();
      throw UnreachableError(text.str());
    }
    if (k > 0 && (solution.q - previous).cwiseAbs().maxCoeff() > max_joint_step) {
      std::ostringstream text;
      text << "path sample " << k << " (t = " << samples[k].t << " s): the joints jump by "
           << (solution.q - previous).cwiseAbs().maxCoeff()
           << " rad from the previous sample (a singularity or a change of branch on the path)";
      throw SolverError(text.str());
    }
    trajectory.time.push_back(samples[k].t);
    trajectory.tool_position.push_back(samples[k].position);
    trajectory.q.push_back(solution.q);
    previous = solution.q;
  }
  const std::size_t n = trajectory.q.size();
  trajectory.qd.assign(n, JointVector::Zero(robot.dof()));
  for (std::size_t k = 1; k + 1 < n; ++k) {
    trajectory.qd[k] = (trajectory.q[k + 1] - trajectory.q[k - 1]) / (trajectory.time[k + 1] - trajectory.time[k - 1]);
  }
  return trajectory;
}

}  // namespace jointcomp
