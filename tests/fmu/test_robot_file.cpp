// The robot as JSON (model/io/robot_file.hpp), the form the FMU ships its robot in: it reads back bit for
// bit, and a broken file is refused with a message naming the field.
#include <cmath>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/io/robot_file.hpp"
#include "model/robot/kinematics.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp {
namespace {

// A chain with a continuous joint (infinite limits), a fixed tool, a rotated, off-axis joint and a link
// without an inertial: every kind of field robot.json has to carry.
constexpr const char* kOddArm = R"(<?xml version="1.0"?>
<robot name="odd_arm">
  <link name="base"/>
  <link name="a"><inertial><origin xyz="0.1 0.02 0.3" rpy="0.1 0.2 0.3"/><mass value="3.3"/>
    <inertia ixx="0.11" ixy="0.01" ixz="0.002" iyy="0.12" iyz="0.003" izz="0.05"/></inertial></link>
  <link name="b"/>
  <link name="tool"/>
  <joint name="j1" type="continuous"><parent link="base"/><child link="a"/>
    <origin xyz="0 0 0.4" rpy="0 0 0.7"/><axis xyz="0 0 1"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/>
    <origin xyz="0.3 0.1 0" rpy="1.5707963267948966 0 0.1"/><axis xyz="0.3 0.4 0.5"/>
    <limit lower="-2.1" upper="1.7" velocity="3.1" effort="120"/></joint>
  <joint name="flange" type="fixed"><parent link="b"/><child link="tool"/><origin xyz="0 0 0.123" rpy="0 0 0"/></joint>
</robot>)";

void expectRoundTrip(const Robot& robot) {
  const std::string text = robotToJson(robot);
  const Robot back = robotFromJson(text, "robot.json");
  EXPECT_TRUE(sameRobot(robot, back)) << robot.name;
  EXPECT_EQ(back.source, "robot.json");
  EXPECT_EQ(robotToJson(back), text);  // and writes the same text again
  // The same kinematics, bit for bit.
  RobotWorkspace a(robot), b(back);
  JointVector q(robot.dof());
  for (int j = 0; j < robot.dof(); ++j) q[j] = 0.3 * (j + 1) - 0.7;
  forwardKinematics(robot, a, q);
  forwardKinematics(back, b, q);
  EXPECT_TRUE((a.tool_pose.matrix().array() == b.tool_pose.matrix().array()).all());
}

TEST(RobotFile, ShippedRobotsReadBackBitForBit) {
  expectRoundTrip(loadRobotFromUrdfFile(JOINTCOMP_DATA_DIR "/robots/rx170.urdf"));
  expectRoundTrip(loadRobotFromUrdfFile(JOINTCOMP_DATA_DIR "/robots/ur10.urdf"));
}

TEST(RobotFile, ContinuousJointsFixedToolsAndMissingInertialsReadBack) {
  const Robot robot = loadRobotFromUrdfString(kOddArm, "odd_arm.urdf");
  ASSERT_EQ(robot.dof(), 2);
  ASSERT_TRUE(std::isinf(robot.joints[0].lower));
  ASSERT_FALSE(robot.hasInertials());
  expectRoundTrip(robot);
  const Robot back = robotFromJson(robotToJson(robot), "x");
  EXPECT_EQ(back.joints[0].lower, -std::numeric_limits<double>::infinity());
  EXPECT_EQ(back.joints[0].upper, std::numeric_limits<double>::infinity());
  EXPECT_EQ(back.link_without_inertial, "b");
}

void expectRefused(const std::string& text, const std::string& fragment) {
  try {
    robotFromJson(text, "broken.json");
    ADD_FAILURE() << "accepted: " << text.substr(0, 200);
  } catch (const UrdfError& error) {
    EXPECT_NE(std::string(error.what()).find(fragment), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("broken.json"), std::string::npos) << error.what();
  }
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

TEST(RobotFile, BrokenFilesAreRefusedNamingTheField) {
  const std::string good = robotToJson(loadRobotFromUrdfString(kOddArm, "odd_arm.urdf"));
  expectRefused("{", "not valid JSON");
  expectRefused("[]", "expected a JSON object");
  expectRefused(replaced(good, "jointcomp-robot/1", "jointcomp-robot/9"), "format");
  expectRefused(replaced(good, "\"name\": \"odd_arm\",", "\"name\": \"odd_arm\", \"colour\": 1,"),
                "colour: unknown key");
  expectRefused(replaced(good, "\"tip_link\": \"tool\",", ""), "tip_link: missing");
  expectRefused(replaced(good, "\"mass_kg\": 3.3", "\"mass_kg\": -3.3"), "mass_kg");
  expectRefused(replaced(good, "\"mass_kg\": 3.3", "\"mass_kg\": 1e999"), "not valid JSON");
  expectRefused(replaced(good, "\"lower_rad\": -2.1", "\"lower_rad\": 2.1"), "lower_rad");
  expectRefused(replaced(good, "\"lower_rad\": -2.1", "\"lower_rad\": \"low\""), "lower_rad");
  expectRefused(replaced(good, "\"joints\": [", "\"joints\": [ 7,"), "joints[0]");
  expectRefused(replaced(good, "\"axis\": [\n        0.0,\n        0.0,\n        1.0",
                         "\"axis\": [\n        0.0,\n        0.0,\n        2.0"),
                "axis");
  expectRefused(replaced(good, "\"rotation\": [\n      1.0", "\"rotation\": [\n      1.5"), "rotation");
  expectRefused(R"({"format": "jointcomp-robot/1", "name": "x", "root_link": "a", "tip_link": "b",
      "link_without_inertial": "", "gravity_m_per_s2": [0, 0, -9.81],
      "tool": {"rotation": [1, 0, 0, 0, 1, 0, 0, 0, 1], "translation_m": [0, 0, 0]}, "joints": []})",
                "no joints");
}

TEST(RobotFile, AMissingFileIsNamed) {
  try {
    loadRobotFile("/nonexistent/robot.json");
    FAIL() << "no error";
  } catch (const UrdfError& error) {
    EXPECT_NE(std::string(error.what()).find("/nonexistent/robot.json"), std::string::npos);
  }
}

}  // namespace
}  // namespace jointcomp
