// robotToUrdf (model/io/urdf_writer.hpp): what it writes, the URDF loader reads back as the same Robot
// to within 1e-12, for the shipped robots, for a calibrated robot with corrected placements, for chains
// with folded fixed joints and merged inertials, continuous joints and a link without inertial.
#include <cmath>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "calibration_test_support.hpp"
#include "model/common/errors.hpp"
#include "model/io/urdf_writer.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

void expectSameRobot(const Robot& a, const Robot& b, double tolerance = 1e-12) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.root_link, b.root_link);
  EXPECT_EQ(a.tip_link, b.tip_link);
  EXPECT_EQ(a.link_without_inertial, b.link_without_inertial);
  EXPECT_LE((a.gravity - b.gravity).cwiseAbs().maxCoeff(), tolerance);
  EXPECT_LE((a.tool.matrix() - b.tool.matrix()).cwiseAbs().maxCoeff(), tolerance);
  ASSERT_EQ(a.dof(), b.dof());
  for (int j = 0; j < a.dof(); ++j) {
    const Joint& x = a.joints[j];
    const Joint& y = b.joints[j];
    SCOPED_TRACE(x.name);
    EXPECT_EQ(x.name, y.name);
    EXPECT_EQ(x.child_link, y.child_link);
    EXPECT_LE((x.placement.matrix() - y.placement.matrix()).cwiseAbs().maxCoeff(), tolerance);
    EXPECT_LE((x.axis - y.axis).cwiseAbs().maxCoeff(), tolerance);
    if (std::isinf(x.lower)) {
      EXPECT_EQ(x.lower, y.lower);
      EXPECT_EQ(x.upper, y.upper);
    } else {
      EXPECT_NEAR(x.lower, y.lower, tolerance);
      EXPECT_NEAR(x.upper, y.upper, tolerance);
    }
    EXPECT_NEAR(x.velocity_limit, y.velocity_limit, tolerance);
    EXPECT_NEAR(x.effort_limit, y.effort_limit, tolerance);
    EXPECT_NEAR(x.body.mass, y.body.mass, tolerance);
    EXPECT_LE((x.body.com - y.body.com).cwiseAbs().maxCoeff(), tolerance);
    EXPECT_LE((x.body.inertia - y.body.inertia).cwiseAbs().maxCoeff(), tolerance);
  }
}

Robot roundTrip(const Robot& robot) { return loadRobotFromUrdfString(robotToUrdf(robot, "round trip"), "written"); }

TEST(UrdfWriter, ShippedRobotsComeBackTheSame) {
  for (const char* name : {"ur10", "rx170"}) {
    SCOPED_TRACE(name);
    const Robot robot = loadRobotFromUrdfFile(std::string(JOINTCOMP_DATA_DIR) + "/robots/" + name + ".urdf");
    expectSameRobot(robot, roundTrip(robot));
  }
}

TEST(UrdfWriter, TestChainsWithFoldedFixedJointsAndMergedInertialsComeBackTheSame) {
  for (const char* name : {"valid_arm", "fixed_folded", "fixed_merged", "missing_inertial"}) {
    SCOPED_TRACE(name);
    const Robot robot = loadRobotFromUrdfFile(std::string(JOINTCOMP_TEST_DATA_DIR) + "/urdf/" + name + ".urdf");
    expectSameRobot(robot, roundTrip(robot));
  }
}

TEST(UrdfWriter, CalibratedRobotWithCorrectedPlacementsComesBackTheSame) {
  GeometricParameters parameters = GeometricParameters::zero(6);
  DeterministicRandom random(3);
  for (auto& c : parameters.placement) {
    for (int k = 0; k < 6; ++k) c[k] = random.uniform(-2e-3, 2e-3);
  }
  parameters.placement[4][3] = 1.5707963267948966;  // a placement at gimbal lock of the URDF angles
  const Robot robot = correctedRobot(*calibration_test::ur10(), parameters);
  expectSameRobot(robot, roundTrip(robot));
}

TEST(UrdfWriter, ContinuousJointsAndMasslessLinksComeBackTheSame) {
  Robot robot = *calibration_test::ur10();
  robot.joints[5].lower = -std::numeric_limits<double>::infinity();
  robot.joints[5].upper = std::numeric_limits<double>::infinity();
  robot.joints[5].body = BodyInertia();
  robot.link_without_inertial = robot.joints[5].child_link;
  robot.name = "arm \"with\" <odd> & name";
  const std::string text = robotToUrdf(robot);
  EXPECT_THAT(text, HasSubstr("type=\"continuous\""));
  expectSameRobot(robot, loadRobotFromUrdfString(text, "written"));
}

TEST(UrdfWriter, RpyAnglesGiveBackTheRotationEverywhere) {
  DeterministicRandom random(11);
  for (int k = 0; k < 2000; ++k) {
    Eigen::Matrix3d rotation;
    if (k % 4 == 0) {
      // At and near gimbal lock: pitch +-pi/2 plus a tiny amount.
      const double pitch = (k % 8 == 0 ? 1.0 : -1.0) * 1.5707963267948966 + (k % 3) * 1e-9;
      rotation = (Eigen::AngleAxisd(random.uniform(-3, 3), Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(random.uniform(-3, 3), Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
    } else {
      rotation = Eigen::Quaterniond(random.normal(), random.normal(), random.normal(), random.normal())
                     .normalized()
                     .toRotationMatrix();
    }
    const Eigen::Vector3d rpy = rotationToRpy(rotation);
    const Eigen::Matrix3d back =
        (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
    ASSERT_LE((back - rotation).cwiseAbs().maxCoeff(), 1e-14) << "case " << k;
    ASSERT_EQ(rpyToRotation(rpy), back) << "case " << k;  // the library's inverse is this composition
  }
}

TEST(UrdfWriter, RejectsWhatUrdfCannotHold) {
  Robot robot = *calibration_test::ur10();
  robot.joints[2].placement.translation().x() = std::numeric_limits<double>::quiet_NaN();
  try {
    robotToUrdf(robot);
    FAIL() << "accepted a NaN placement";
  } catch (const InvalidArgument& error) {
    EXPECT_THAT(error.what(), HasSubstr("joint_3"));
  }
  Robot empty = *calibration_test::ur10();
  empty.joints.clear();
  EXPECT_THROW(robotToUrdf(empty), InvalidArgument);
}

}  // namespace
}  // namespace jointcomp
