// What a URDF may be, and what it may not make the loader do (issue 41): thousands of fixed links in a row
// load without recursion, XML nested 200,000 deep and files past the size cap are refused before they are
// parsed, devices and folders before they are read.
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

const char* const kInertial =
    "<inertial><mass value=\"1\"/><inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" izz=\"0.1\"/>"
    "</inertial>";

// One revolute joint, then `fixed` links in a row, each of 1 kg, fixed to the one before.
std::string longFixedChain(int fixed) {
  std::string urdf = "<robot name=\"long\"><link name=\"base\"/><link name=\"l0\">" + std::string(kInertial) +
                     "</link><joint name=\"j1\" type=\"revolute\"><parent link=\"base\"/><child link=\"l0\"/>"
                     "<axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>";
  for (int i = 1; i <= fixed; ++i) {
    const std::string link = "l" + std::to_string(i), parent = "l" + std::to_string(i - 1);
    urdf += "<link name=\"" + link + "\">" + kInertial + "</link><joint name=\"f" + std::to_string(i) +
            "\" type=\"fixed\"><parent link=\"" + parent + "\"/><child link=\"" + link +
            "\"/><origin xyz=\"0.001 0 0\"/></joint>";
  }
  return urdf + "</robot>";
}

template <typename Call>
void expectUrdfError(Call call, const std::vector<std::string>& phrases) {
  try {
    call();
    ADD_FAILURE() << "loaded instead of throwing UrdfError";
  } catch (const UrdfError& error) {
    for (const std::string& phrase : phrases) EXPECT_THAT(error.what(), HasSubstr(phrase));
  }
}

TEST(UrdfLimits, TwentyThousandFixedLinksInARowFoldIntoOneBodyWithoutRecursion) {
  // The recursive fold overflowed the stack at about 10,470 links.
  const int fixed = 20000;
  const Robot robot = loadRobotFromUrdfString(longFixedChain(fixed), "long.urdf", {"base", "l0"});
  ASSERT_EQ(robot.dof(), 1);
  EXPECT_DOUBLE_EQ(robot.joints[0].body.mass, fixed + 1.0);
  // The links' centres are 0, 1, ..., 20000 mm along x: their mean is 10 m.
  EXPECT_NEAR(robot.joints[0].body.com.x(), fixed * 0.001 / 2, 1e-9);
}

TEST(UrdfLimits, DeeplyNestedXmlIsRefusedBeforeItIsParsed) {
  // TinyXML crashed after 12 s on 200,000 nested elements.
  const int depth = 200000;
  std::string urdf = "<robot name=\"deep\">";
  for (int i = 0; i < depth; ++i) urdf += "<a>";
  for (int i = 0; i < depth; ++i) urdf += "</a>";
  urdf += "</robot>";
  expectUrdfError([&] { loadRobotFromUrdfString(urdf, "deep.urdf"); },
                  {"deep.urdf", "nests elements more than 100 deep"});
}

TEST(UrdfLimits, TheDepthCountSkipsCommentsSelfClosedElementsAndQuotedBrackets) {
  // 100 levels of nesting, with what must not count: comments, CDATA, '>' inside attribute values,
  // self-closed elements, a declaration.
  std::string inner = "<x a=\"<b>\"/><![CDATA[<c><c>]]>";
  for (int i = 0; i < 98; ++i) inner = "<g note=\"a > b\">" + inner + "</g>";
  const std::string chain = longFixedChain(0);
  const std::size_t robot_open = chain.find('>') + 1;  // after <robot name="long">: 100 levels in all
  const std::string urdf = "<?xml version=\"1.0\"?><!-- <a><a><a> -->" + chain.substr(0, robot_open) + "<gazebo>" +
                           inner + "</gazebo>" + chain.substr(robot_open);
  const Robot robot = loadRobotFromUrdfString(urdf, "nested.urdf");
  EXPECT_EQ(robot.dof(), 1);
}

TEST(UrdfLimits, AFileOverTheSizeCapIsRefusedWithTheNumber) {
  const std::string urdf = longFixedChain(0) + std::string(kMaxUrdfBytes, ' ');
  expectUrdfError([&] { loadRobotFromUrdfString(urdf, "big.urdf"); },
                  {"big.urdf", std::to_string(urdf.size()) + " bytes", std::to_string(kMaxUrdfBytes)});
}

TEST(UrdfLimits, DevicesAndFoldersAreRefusedBeforeTheyAreRead) {
  // --urdf /dev/zero read until the memory ran out.
  expectUrdfError([] { loadRobotFromUrdfFile("/dev/zero"); }, {"/dev/zero is a device, not a file (the URDF)"});
  expectUrdfError([] { loadRobotFromUrdfFile("/tmp"); }, {"/tmp is a folder, not a file (the URDF)"});
  expectUrdfError([] { loadRobotFromUrdfFile("/nonexistent/robot.urdf"); },
                  {"/nonexistent/robot.urdf: cannot open the URDF", "No such file"});
}

// Two revolute joints base -> l1 -> l2, with `extra` appended inside <robot>, and the given joint-2 body.
std::string twoJoints(const std::string& extra, const std::string& second_joint_body = "", double mass = 1.0) {
  const std::string inertial = "<inertial><mass value=\"" + std::to_string(mass) +
                               "\"/><inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" izz=\"0.1\"/>"
                               "</inertial>";
  return "<robot name=\"two\"><link name=\"base\"/><link name=\"l1\">" + inertial + "</link><link name=\"l2\">" +
         inertial +
         "</link><joint name=\"j1\" type=\"revolute\"><parent link=\"base\"/><child link=\"l1\"/><axis xyz=\"0 0 1\"/>"
         "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint><joint name=\"j2\" type=\"revolute\">"
         "<parent link=\"l1\"/><child link=\"l2\"/><axis xyz=\"0 1 0\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" "
         "velocity=\"1\"/>" +
         second_joint_body + "</joint>" + extra + "</robot>";
}

TEST(UrdfLimits, TheTwoJointTemplateLoads) { EXPECT_EQ(loadRobotFromUrdfString(twoJoints(""), "two.urdf").dof(), 2); }

TEST(UrdfLimits, ALinkWithTwoParentsIsRefused) {
  // urdfdom kept the last parent read and said nothing.
  const std::string second_parent =
      "<joint name=\"j3\" type=\"fixed\"><parent link=\"base\"/><child link=\"l2\"/></joint>";
  expectUrdfError([&] { loadRobotFromUrdfString(twoJoints(second_parent), "two.urdf"); },
                  {"two.urdf", "link 'l2' is the child of joints 'j2' and 'j3'"});
}

TEST(UrdfLimits, AMimicJointOnTheChainIsRefused) {
  expectUrdfError([&] { loadRobotFromUrdfString(twoJoints("", "<mimic joint=\"j1\"/>"), "two.urdf"); },
                  {"two.urdf", "joint 'j2' mimics joint 'j1'"});
}

TEST(UrdfLimits, MassesAndOriginsNoRobotHasAreRefused) {
  // A mass of 1e300 kg made paper report errors of metres with exit 0.
  expectUrdfError([&] { loadRobotFromUrdfString(twoJoints("", "", 1e300), "heavy.urdf"); },
                  {"heavy.urdf", "link 'l1' <inertial>", "no robot's link"});
  expectUrdfError([&] { loadRobotFromUrdfString(twoJoints("", "<origin xyz=\"0 0 1e6\"/>"), "far.urdf"); },
                  {"far.urdf", "joint 'j2': <origin> is more than 1000 m away"});
}

}  // namespace
}  // namespace jointcomp
