#include <cstdio>

#include "cli/commands.hpp"
#include "cli/options.hpp"
#include "cli/robot_setup.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/kinematics.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp::cli {

int runKinematics(int argc, char** argv) {
  const Options options(argc, argv, {"urdf", "base-link", "tip-link"});
  const std::string urdf = options.get("urdf", robotFile("rx170"));
  const Robot robot = loadRobotFromUrdfFile(urdf, chainOptions(options));
  RobotWorkspace ws(robot);
  std::printf("robot '%s' from %s: %d joints, tool link '%s'\n", robot.name.c_str(), urdf.c_str(), robot.dof(),
              robot.tip_link.c_str());
  const double deg = 3.14159265358979323846 / 180.0;
  // Four poses of the first six joints (further joints at 0); every joint's angle is printed.
  const double poses[][6] = {
      {0, 0, 0, 0, 0, 0}, {0, 90, 0, 0, 0, 0}, {30, 45, 60, 0, 45, 0}, {-20, 60, 30, 90, -45, 10}};
  std::printf("%-*s %-30s %s\n", 6 * robot.dof(), "q [deg]", "tool position [mm]", "gravity torque [N m]");
  for (const auto& pose : poses) {
    JointVector q(robot.dof());
    for (int i = 0; i < robot.dof(); ++i) q[i] = i < 6 ? pose[i] * deg : 0.0;
    JointVector tau;
    gravityTorques(robot, ws, q, tau);
    const Eigen::Vector3d p = ws.tool_pose.translation() * 1e3;
    for (int i = 0; i < robot.dof(); ++i) std::printf("%5.0f ", q[i] / deg);
    std::printf("  %9.2f %9.2f %9.2f  ", p.x(), p.y(), p.z());
    for (int i = 0; i < robot.dof(); ++i) std::printf(" %8.2f", tau[i]);
    std::printf("\n");
  }
  return 0;
}

}  // namespace jointcomp::cli
