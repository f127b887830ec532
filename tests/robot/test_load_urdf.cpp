// Loading robots from URDF: the shipped robots load with the values written in their files, broken files
// give a UrdfError naming the file and the offending element, sub-chains and tips can be chosen, and
// fixed joints are folded (checked against a file folded by hand and against hand-computed torques).
#include <cmath>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/kinematics.hpp"
#include "model/robot/load_urdf.hpp"
#include "robot_test_support.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;
using testing_support::kPi;
using testing_support::urdfTestFile;

std::string readFile(const std::string& path) {
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

// Loading `file` must throw UrdfError whose message contains the file's path and each of `names`.
void expectUrdfError(const std::string& file, const std::vector<std::string>& names,
                     const UrdfChainOptions& options = {}) {
  const std::string path = urdfTestFile(file);
  try {
    const Robot robot = loadRobotFromUrdfFile(path, options);
    ADD_FAILURE() << file << " loaded (" << robot.dof() << " joints) instead of throwing UrdfError";
  } catch (const UrdfError& error) {
    EXPECT_THAT(error.what(), HasSubstr(path)) << file;
    for (const std::string& name : names) EXPECT_THAT(error.what(), HasSubstr(name)) << file;
  } catch (const std::exception& error) {
    ADD_FAILURE() << file << " threw something other than UrdfError: " << error.what();
  }
}

double totalMass(const Robot& robot) {
  double mass = 0.0;
  for (const Joint& joint : robot.joints) mass += joint.body.mass;
  return mass;
}

double isometryDistance(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff();
}

// --- the shipped robots -------------------------------------------------------------------------------

TEST(LoadUrdf, Rx170HasTheChainWrittenInItsFile) {
  const Robot& robot = testing_support::rx170();
  EXPECT_EQ(robot.name, "rx170");
  EXPECT_EQ(robot.source, testing_support::rx170Path());
  EXPECT_EQ(robot.root_link, "base_link");
  EXPECT_EQ(robot.tip_link, "flange");
  ASSERT_EQ(robot.dof(), 6);
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(robot.joints[i].name, "joint_" + std::to_string(i + 1));
    EXPECT_EQ(robot.joints[i].child_link, "link_" + std::to_string(i + 1));
    EXPECT_LT((robot.joints[i].axis - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
    EXPECT_EQ(robot.jointIndex("joint_" + std::to_string(i + 1)), i);
  }
  EXPECT_THROW(robot.jointIndex("flange_joint"), InvalidArgument);
  EXPECT_DOUBLE_EQ(robot.joints[4].lower, -1.8325957145940461);
  EXPECT_DOUBLE_EQ(robot.joints[4].upper, 2.0943951023931953);
  EXPECT_DOUBLE_EQ(robot.lowerLimits()[1], -2.399827721492203);
  EXPECT_DOUBLE_EQ(robot.upperLimits()[3], 4.71238898038469);
  EXPECT_DOUBLE_EQ(robot.joints[5].velocity_limit, 15.184364492350667);
  EXPECT_DOUBLE_EQ(robot.joints[2].effort_limit, 1500.0);
  // The flange_joint is folded into the tool frame: 0.11 m along z of link 6.
  EXPECT_LT(isometryDistance(robot.tool, Eigen::Isometry3d(Eigen::Translation3d(0, 0, 0.11))), 1e-15);
  EXPECT_TRUE(robot.hasInertials());
  EXPECT_NEAR(totalMass(robot), 45.36 + 51.27 + 19.75 + 27.64 + 5.0 + 1.0, 1e-12);
  EXPECT_NEAR(robot.joints[3].body.mass, 27.64, 1e-12);
  EXPECT_LT((robot.joints[3].body.com - Eigen::Vector3d(0, 0, 0.475)).norm(), 1e-15);
  EXPECT_NEAR(robot.joints[3].body.inertia(2, 2), 0.15, 1e-15);
  EXPECT_LT((robot.gravity - Eigen::Vector3d(0, 0, -9.81)).norm(), 1e-15);
}

TEST(LoadUrdf, Ur10HasTheChainWrittenInItsFile) {
  const Robot& robot = testing_support::ur10();
  EXPECT_EQ(robot.name, "ur10");
  ASSERT_EQ(robot.dof(), 6);
  EXPECT_NEAR(totalMass(robot), 7.1 + 12.7 + 4.27 + 2.0 + 2.0 + 0.365, 1e-12);
  for (const Joint& joint : robot.joints) {
    EXPECT_DOUBLE_EQ(joint.lower, -2.0 * kPi);
    EXPECT_DOUBLE_EQ(joint.upper, 2.0 * kPi);
  }
  EXPECT_DOUBLE_EQ(robot.joints[3].effort_limit, 56.0);
}

TEST(LoadUrdf, FromStringGivesTheSameRobotAndNamesTheSource) {
  const Robot from_string = loadRobotFromUrdfString(readFile(testing_support::rx170Path()), "rx170 (inline)");
  const Robot& from_file = testing_support::rx170();
  EXPECT_EQ(from_string.source, "rx170 (inline)");
  ASSERT_EQ(from_string.dof(), from_file.dof());
  for (int i = 0; i < from_file.dof(); ++i) {
    EXPECT_TRUE(from_string.joints[i].placement.matrix() == from_file.joints[i].placement.matrix());
    EXPECT_EQ(from_string.joints[i].body.mass, from_file.joints[i].body.mass);
    EXPECT_TRUE(from_string.joints[i].body.inertia == from_file.joints[i].body.inertia);
  }
  try {
    loadRobotFromUrdfString("<robot name=\"x\"><link name=\"a\"", "inline text");
    FAIL() << "no exception";
  } catch (const UrdfError& error) {
    EXPECT_THAT(error.what(), HasSubstr("inline text"));
  }
  EXPECT_THROW(loadRobotFromUrdfString("", "empty text"), UrdfError);
}

// --- broken files --------------------------------------------------------------------------------------

TEST(LoadUrdf, TheTemplateOfTheBrokenFilesLoads) {
  // Every broken file differs from valid_arm.urdf in one element, so that element is what fails.
  const Robot robot = loadRobotFromUrdfFile(urdfTestFile("valid_arm.urdf"));
  EXPECT_EQ(robot.dof(), 3);
  EXPECT_EQ(robot.tip_link, "tool");
  EXPECT_TRUE(robot.hasInertials());
}

TEST(LoadUrdf, MissingFileNamesThePath) { expectUrdfError("does_not_exist.urdf", {}); }

TEST(LoadUrdf, MalformedXmlNamesTheFile) { expectUrdfError("malformed.urdf", {}); }

TEST(LoadUrdf, PrismaticJointOnTheChainIsRejected) {
  expectUrdfError("prismatic_joint.urdf", {"joint_2", "prismatic"});
}

TEST(LoadUrdf, FloatingJointOnTheChainIsRejected) { expectUrdfError("floating_joint.urdf", {"joint_2", "floating"}); }

TEST(LoadUrdf, LowerLimitAboveUpperIsRejected) { expectUrdfError("lower_above_upper.urdf", {"joint_2", "lower"}); }

TEST(LoadUrdf, NegativeOrZeroMassIsRejected) {
  expectUrdfError("negative_mass.urdf", {"link_2", "mass"});
  expectUrdfError("zero_mass.urdf", {"link_2", "mass"});
}

TEST(LoadUrdf, NanInAnOriginIsRejected) { expectUrdfError("nan_origin.urdf", {"joint_2"}); }

TEST(LoadUrdf, NonPhysicalInertiaIsRejected) {
  expectUrdfError("non_physical_inertia.urdf", {"link_2", "inertia"});
  expectUrdfError("negative_inertia.urdf", {"link_2", "inertia"});
}

TEST(LoadUrdf, ZeroAxisIsRejected) { expectUrdfError("zero_axis.urdf", {"joint_2", "axis"}); }

TEST(LoadUrdf, MissingInertialLoadsButDynamicsThrow) {
  const Robot robot = loadRobotFromUrdfFile(urdfTestFile("missing_inertial.urdf"));
  EXPECT_EQ(robot.dof(), 3);
  EXPECT_FALSE(robot.hasInertials());
  EXPECT_EQ(robot.link_without_inertial, "link_2");
  RobotWorkspace ws(robot);
  JointVector tau;
  try {
    gravityTorques(robot, ws, JointVector::Zero(3), tau);
    FAIL() << "no exception";
  } catch (const Error& error) {
    EXPECT_THAT(error.what(), HasSubstr("link_2"));
  }
  // Kinematics works without masses.
  EXPECT_NO_THROW(forwardKinematics(robot, ws, JointVector::Zero(3)));
}

// --- choosing the chain --------------------------------------------------------------------------------

TEST(LoadUrdf, UnknownRootOrTipLinkIsRejectedByName) {
  UrdfChainOptions unknown_root;
  unknown_root.root_link = "no_such_root";
  UrdfChainOptions unknown_tip;
  unknown_tip.tip_link = "no_such_tip";
  expectUrdfError("valid_arm.urdf", {"no_such_root"}, unknown_root);
  expectUrdfError("valid_arm.urdf", {"no_such_tip"}, unknown_tip);
  // A tip that is not below the root.
  UrdfChainOptions upside_down;
  upside_down.root_link = "link_3";
  upside_down.tip_link = "link_1";
  expectUrdfError("valid_arm.urdf", {"link_1", "link_3"}, upside_down);
}

TEST(LoadUrdf, SubChainBetweenChosenLinksMatchesTheFullChain) {
  UrdfChainOptions options;
  options.root_link = "link_2";
  options.tip_link = "link_5";
  const Robot sub = loadRobotFromUrdfFile(testing_support::rx170Path(), options);
  const Robot& full = testing_support::rx170();
  ASSERT_EQ(sub.dof(), 3);
  EXPECT_EQ(sub.joints[0].name, "joint_3");
  EXPECT_EQ(sub.joints[2].name, "joint_5");
  EXPECT_EQ(sub.root_link, "link_2");
  EXPECT_EQ(sub.tip_link, "link_5");
  RobotWorkspace ws_sub(sub);
  RobotWorkspace ws_full(full);
  std::mt19937 rng(301u);
  for (int sample = 0; sample < 50; ++sample) {
    const JointVector q = testing_support::randomConfiguration(full, rng);
    forwardKinematics(full, ws_full, q);
    forwardKinematics(sub, ws_sub, q.segment(2, 3));
    // link_5 seen from link_2 is the tool of the sub-chain.
    const Eigen::Isometry3d expected = ws_full.joint_pose[1].inverse() * ws_full.joint_pose[4];
    EXPECT_LT(isometryDistance(ws_sub.tool_pose, expected), 1e-12);
  }
}

// URDFs in the ROS-Industrial layout (a "base" frame beside base_link, a camera fixed to link_3, tool0 on
// the flange) load without naming a tip: the longest moving chain ends in tool0, the side frames change
// nothing of the arm, and tool0's offset is the only difference from the plain file. Naming the tip picks
// the flange (the plain file's robot, bit for bit) or the camera (the first three joints).
TEST(LoadUrdf, RosIndustrialLayoutLoadsTheArmToTool0) {
  for (const char* name : {"rx170", "ur10"}) {
    const std::string file = std::string(JOINTCOMP_TEST_DATA_DIR) + "/urdf/" + name + "_ros_industrial.urdf";
    const Robot plain = loadRobotFromUrdfFile(std::string(JOINTCOMP_DATA_DIR) + "/robots/" + name + ".urdf");
    const Robot arm = loadRobotFromUrdfFile(file);
    EXPECT_EQ(arm.tip_link, "tool0") << name;
    ASSERT_EQ(arm.dof(), plain.dof()) << name;
    for (int j = 0; j < arm.dof(); ++j) {
      EXPECT_EQ(arm.joints[j].name, plain.joints[j].name);
      EXPECT_TRUE(arm.joints[j].placement.matrix() == plain.joints[j].placement.matrix()) << name << " joint " << j;
      EXPECT_EQ(arm.joints[j].body.mass, plain.joints[j].body.mass);
      EXPECT_TRUE(arm.joints[j].body.inertia == plain.joints[j].body.inertia);
    }
    Eigen::Isometry3d tool0 = Eigen::Isometry3d::Identity();
    tool0.translation() = Eigen::Vector3d(0, 0, 0.05);
    tool0.linear() = Eigen::AngleAxisd(1.5707963267948966, Eigen::Vector3d::UnitY()).toRotationMatrix();
    EXPECT_LT(isometryDistance(arm.tool, plain.tool * tool0), 1e-12) << name;

    UrdfChainOptions flange;
    flange.tip_link = "flange";
    const Robot at_flange = loadRobotFromUrdfFile(file, flange);
    EXPECT_TRUE(at_flange.tool.matrix() == plain.tool.matrix()) << name;
    UrdfChainOptions camera;
    camera.tip_link = "camera_link";
    const Robot to_camera = loadRobotFromUrdfFile(file, camera);
    ASSERT_EQ(to_camera.dof(), 3) << name;
    EXPECT_EQ(to_camera.joints[2].name, "joint_3");
  }
}

TEST(LoadUrdf, BranchingTreeNeedsATip) {
  // Two arms on one base.
  expectUrdfError("dual_arm.urdf", {"base_link", "tip"});
  UrdfChainOptions left;
  left.tip_link = "left_tool";
  const Robot robot = loadRobotFromUrdfFile(urdfTestFile("dual_arm.urdf"), left);
  ASSERT_EQ(robot.dof(), 2);
  EXPECT_EQ(robot.joints[0].name, "left_joint_1");
  EXPECT_EQ(robot.joints[1].name, "left_joint_2");
  RobotWorkspace ws(robot);
  forwardKinematics(robot, ws, JointVector::Zero(2));
  // left_joint_1 at (0, 0.3, 0.2), left_joint_2 0.3 above it, the tool 0.4 along x.
  EXPECT_LT((ws.tool_pose.translation() - Eigen::Vector3d(0.4, 0.3, 0.5)).norm(), 1e-15);
  UrdfChainOptions right;
  right.tip_link = "right_tool";
  const Robot right_arm = loadRobotFromUrdfFile(urdfTestFile("dual_arm.urdf"), right);
  EXPECT_EQ(right_arm.joints[0].name, "right_joint_1");
}

TEST(LoadUrdf, FixedBranchJoinsTheBodyAndEitherToolCanBeTheTip) {
  expectUrdfError("two_tools.urdf", {"link_3"});
  UrdfChainOptions tool;
  tool.tip_link = "tool";
  const Robot robot = loadRobotFromUrdfFile(urdfTestFile("two_tools.urdf"), tool);
  ASSERT_EQ(robot.dof(), 3);
  // The camera frame sits at (0.1, 0, 0.1) in link_3, turned by pi/2 about y, so its centre (0.05 along its
  // own z) is at (0.15, 0, 0.1) in link_3; 0.5 kg of it join body 3 (1 kg at (0.15, 0, 0)).
  EXPECT_NEAR(robot.joints[2].body.mass, 1.5, 1e-12);
  EXPECT_LT((robot.joints[2].body.com - Eigen::Vector3d(0.15, 0, 0.5 * 0.1 / 1.5)).norm(), 1e-12);
  EXPECT_LT(isometryDistance(robot.tool, Eigen::Isometry3d(Eigen::Translation3d(0.3, 0, 0))), 1e-15);
  UrdfChainOptions camera;
  camera.tip_link = "camera";
  const Robot seen_from_camera = loadRobotFromUrdfFile(urdfTestFile("two_tools.urdf"), camera);
  const Eigen::Isometry3d camera_in_link_3 =
      Eigen::Translation3d(0.1, 0, 0.1) * Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitY());
  EXPECT_LT(isometryDistance(seen_from_camera.tool, camera_in_link_3), 1e-15);
  EXPECT_NEAR(seen_from_camera.joints[2].body.mass, 1.5, 1e-12);
  // The tool pose carries the tool frame's rotation.
  RobotWorkspace ws(seen_from_camera);
  std::mt19937 rng(304u);
  for (int sample = 0; sample < 20; ++sample) {
    const JointVector q = testing_support::randomConfiguration(seen_from_camera, rng);
    forwardKinematics(seen_from_camera, ws, q);
    EXPECT_LT(isometryDistance(ws.tool_pose, ws.joint_pose[2] * camera_in_link_3), 1e-14);
  }
}

TEST(LoadUrdf, MovingBranchOffTheChainIsRejectedNamingIt) {
  // Without a tip the tree is ambiguous at link_2; with the tip the finger is a moving body the model
  // cannot carry, and the message names its joint.
  expectUrdfError("moving_branch.urdf", {"link_2"});
  UrdfChainOptions tool;
  tool.tip_link = "tool";
  expectUrdfError("moving_branch.urdf", {"finger_joint"}, tool);
}

TEST(LoadUrdf, ContinuousJointsAreUnlimited) {
  const std::string urdf = R"(<?xml version="1.0"?>
<robot name="wheel">
  <link name="base"/>
  <joint name="spin" type="continuous"><parent link="base"/><child link="wheel"/><axis xyz="0 0 2"/></joint>
  <link name="wheel"><inertial><mass value="1"/>
    <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
</robot>)";
  const Robot robot = loadRobotFromUrdfString(urdf, "wheel");
  ASSERT_EQ(robot.dof(), 1);
  EXPECT_TRUE(std::isinf(robot.joints[0].lower) && robot.joints[0].lower < 0);
  EXPECT_TRUE(std::isinf(robot.joints[0].upper) && robot.joints[0].upper > 0);
  // The axis is normalised.
  EXPECT_LT((robot.joints[0].axis - Eigen::Vector3d::UnitZ()).norm(), 1e-15);
}

TEST(LoadUrdf, ChainWithoutRevoluteJointIsRejected) {
  const std::string urdf = R"(<?xml version="1.0"?>
<robot name="statue">
  <link name="base"/>
  <joint name="bolt" type="fixed"><parent link="base"/><child link="top"/></joint>
  <link name="top"/>
</robot>)";
  EXPECT_THROW(loadRobotFromUrdfString(urdf, "statue"), UrdfError);
}

// --- fixed joints are folded ---------------------------------------------------------------------------

TEST(LoadUrdf, FixedJointBetweenRevoluteJointsFoldsLikeTheHandMergedFile) {
  const Robot folded = loadRobotFromUrdfFile(urdfTestFile("fixed_folded.urdf"));
  const Robot merged = loadRobotFromUrdfFile(urdfTestFile("fixed_merged.urdf"));
  ASSERT_EQ(folded.dof(), 2);
  ASSERT_EQ(merged.dof(), 2);
  for (int i = 0; i < 2; ++i) {
    EXPECT_LT(isometryDistance(folded.joints[i].placement, merged.joints[i].placement), 1e-15) << i;
    EXPECT_NEAR(folded.joints[i].body.mass, merged.joints[i].body.mass, 1e-14) << i;
    EXPECT_LT((folded.joints[i].body.com - merged.joints[i].body.com).norm(), 1e-14) << i;
    EXPECT_LT((folded.joints[i].body.inertia - merged.joints[i].body.inertia).cwiseAbs().maxCoeff(), 1e-14) << i;
  }
  EXPECT_LT(isometryDistance(folded.tool, merged.tool), 1e-15);
  RobotWorkspace ws_folded(folded);
  RobotWorkspace ws_merged(merged);
  std::mt19937 rng(302u);
  for (int sample = 0; sample < 100; ++sample) {
    const JointVector q = testing_support::randomConfiguration(folded, rng);
    forwardKinematics(folded, ws_folded, q);
    forwardKinematics(merged, ws_merged, q);
    EXPECT_LT(isometryDistance(ws_folded.tool_pose, ws_merged.tool_pose), 1e-14);
    JointMatrix m_folded, m_merged;
    massMatrix(folded, ws_folded, q, m_folded);
    massMatrix(merged, ws_merged, q, m_merged);
    EXPECT_LT((m_folded - m_merged).cwiseAbs().maxCoeff(), 1e-13);
  }
}

TEST(LoadUrdf, FoldedMassesGiveTheHandComputedGravityTorques) {
  const Robot robot = loadRobotFromUrdfFile(urdfTestFile("fixed_folded.urdf"));
  // Bodies: 3 + 2 kg (link_1 and link_mid), 1.5 + 0.5 kg (link_2 and tool).
  EXPECT_NEAR(totalMass(robot), 7.0, 1e-14);
  EXPECT_NEAR(robot.joints[0].body.mass, 5.0, 1e-14);
  EXPECT_NEAR(robot.joints[1].body.mass, 2.0, 1e-14);
  EXPECT_LT((robot.joints[0].body.com - Eigen::Vector3d(0.24, 0.04, 0.08)).norm(), 1e-14);
  EXPECT_LT((robot.joints[1].body.com - Eigen::Vector3d(0.15, 0.3125, 0.0375)).norm(), 1e-14);

  RobotWorkspace ws(robot);
  JointVector tau;
  // q = 0. Centres in the base frame: link_1 (0.2, 0, 0.4), link_mid (0.3, 0.1, 0.6), link_2
  // (0.35, 0.3, 0.85), tool (0.3, 0.1, 1.1); joint 1 turns about y through (0, 0, 0.4), joint 2 about x
  // through (0.3, 0.1, 0.6). With V = 9.81 sum m z: dz/dq1 = -x, dz/dq2 = y - 0.1.
  gravityTorques(robot, ws, JointVector::Zero(2), tau);
  EXPECT_NEAR(tau[0], -9.81 * (3.0 * 0.2 + 2.0 * 0.3 + 1.5 * 0.35 + 0.5 * 0.3), 1e-12);
  EXPECT_NEAR(tau[1], 9.81 * (1.5 * 0.2 + 0.5 * 0.0), 1e-12);
  EXPECT_LT((ws.tool_pose.translation() - Eigen::Vector3d(0.3, 0.1, 1.1)).norm(), 1e-14);

  // Any q: place the four point masses by hand (Ry(q1) about the shoulder, Rx(q2) about the elbow).
  std::mt19937 rng(303u);
  for (int sample = 0; sample < 20; ++sample) {
    const JointVector q = testing_support::randomConfiguration(robot, rng);
    const Eigen::Vector3d shoulder(0, 0, 0.4);
    const Eigen::Matrix3d r1 = Eigen::AngleAxisd(q[0], Eigen::Vector3d::UnitY()).toRotationMatrix();
    const Eigen::Vector3d elbow = shoulder + r1 * Eigen::Vector3d(0.3, 0.1, 0.2);
    const Eigen::Vector3d elbow_axis = r1 * Eigen::Vector3d::UnitX();
    const Eigen::Matrix3d r2 = Eigen::AngleAxisd(q[1], elbow_axis).toRotationMatrix() * r1;
    const Eigen::Vector3d c1 = shoulder + r1 * Eigen::Vector3d(0.2, 0, 0);
    const Eigen::Vector3d c_mid = shoulder + r1 * Eigen::Vector3d(0.3, 0.1, 0.2);
    const Eigen::Vector3d c2 = elbow + r2 * Eigen::Vector3d(0.05, 0.2, 0.25);
    const Eigen::Vector3d c_tool = elbow + r2 * Eigen::Vector3d(0, 0, 0.5);
    const Eigen::Vector3d weight(0, 0, -9.81);
    // Holding torque = minus the moment of the weights about each axis.
    const double tau1 =
        -Eigen::Vector3d::UnitY().dot((c1 - shoulder).cross(3.0 * weight) + (c_mid - shoulder).cross(2.0 * weight) +
                                      (c2 - shoulder).cross(1.5 * weight) + (c_tool - shoulder).cross(0.5 * weight));
    const double tau2 = -elbow_axis.dot((c2 - elbow).cross(1.5 * weight) + (c_tool - elbow).cross(0.5 * weight));
    gravityTorques(robot, ws, q, tau);
    EXPECT_NEAR(tau[0], tau1, 1e-12);
    EXPECT_NEAR(tau[1], tau2, 1e-12);
    EXPECT_LT((ws.tool_pose.translation() - c_tool).norm(), 1e-14);
  }
}

}  // namespace
}  // namespace jointcomp
