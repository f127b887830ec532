// The calibration's geometry within what a real robot can be off by (GeometryLimits): each bound at its
// edge, with the size re-derived from the corrected robot itself (the axis's shift and turn between the
// nominal and the corrected joint placement); whole campaigns whose truth lies beyond a bound, refused
// by name, and just inside it, recovered; discovery undoing a freed offset that would cross its bound.
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/identify/discovery.hpp"
#include "tests/identify/calibration_test_support.hpp"

namespace jointcomp {
namespace {

using namespace calibration_test;
using ::testing::HasSubstr;

// The joint's placement turned by, and shifted by, between the nominal robot and the corrected one.
struct PlacementChange {
  double shift = 0.0;  // m
  double turn = 0.0;   // rad
};
PlacementChange changeOf(const GeometricParameters& p, int joint) {
  const Robot corrected = correctedRobot(*ur10(), p);
  const Eigen::Isometry3d& before = ur10()->joints[static_cast<std::size_t>(joint)].placement;
  const Eigen::Isometry3d& after = corrected.joints[static_cast<std::size_t>(joint)].placement;
  PlacementChange change;
  change.shift = (after.translation() - before.translation()).norm();
  change.turn = Eigen::AngleAxisd(before.linear().transpose() * after.linear()).angle();
  return change;
}

TEST(GeometryLimits, EachBoundHoldsAtItsEdgeAndNamesItsJoint) {
  const GeometryLimits limits;
  const Robot& robot = *ur10();
  for (double sign : {1.0, -1.0}) {
    GeometricParameters p = GeometricParameters::zero(6);
    p.offset[2] = sign * 0.99 * limits.offset;
    EXPECT_EQ(geometryBeyondLimits(robot, p, limits), "");
    p.offset[2] = sign * 1.01 * limits.offset;
    EXPECT_THAT(geometryBeyondLimits(robot, p, limits), HasSubstr("joint_3.offset_rad"));
  }
  // The shift and the turn are bounded as vectors: along a diagonal each component stays inside the
  // bound while the axis moves (turns) beyond it.
  const Eigen::Vector3d diagonal(0.6, 0.0, -0.8);
  for (double factor : {0.99, 1.01}) {
    GeometricParameters shifted = GeometricParameters::zero(6);
    shifted.placement[3].head<3>() = factor * limits.placement_shift * diagonal;
    EXPECT_NEAR(changeOf(shifted, 3).shift, factor * limits.placement_shift, 1e-15);
    GeometricParameters turned = GeometricParameters::zero(6);
    turned.placement[1].tail<3>() = factor * limits.placement_turn * diagonal;
    EXPECT_NEAR(changeOf(turned, 1).turn, factor * limits.placement_turn, 1e-12);
    if (factor < 1.0) {
      EXPECT_EQ(geometryBeyondLimits(robot, shifted, limits), "");
      EXPECT_EQ(geometryBeyondLimits(robot, turned, limits), "");
    } else {
      EXPECT_THAT(geometryBeyondLimits(robot, shifted, limits), HasSubstr("joint_4.placement_d*_m"));
      EXPECT_THAT(geometryBeyondLimits(robot, turned, limits), HasSubstr("joint_2.placement_r*_rad"));
    }
  }
  GeometricParameters unknown = GeometricParameters::zero(6);
  unknown.placement[5][4] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(geometryBeyondLimits(robot, unknown, limits), HasSubstr("joint_6.placement_r*_rad"));
  // The frame and the target are where the instrument and the tool are, not the robot's geometry.
  GeometricParameters far = GeometricParameters::zero(6);
  far.frame_translation << 3.0, -2.0, 1.0;
  far.target << 0.0, 0.0, 0.4;
  EXPECT_EQ(geometryBeyondLimits(robot, far, limits), "");
}

// A noise-free campaign of `truth` (frame, target and robot) on 80 poses.
MeasurementCampaign campaignOf(const GeometricParameters& truth) {
  return simulateGeometricCampaign(ur10Model(), truth, randomPoses(80, 5), 1e-6, 3, kNominalTarget);
}

GeometricParameters truthWith(double joint_3_offset, double joint_4_shift_x) {
  DeterministicRandom random(11);
  GeometricParameters truth = GeometricParameters::zero(6);
  truth.setInstrumentFromBase(trackerFrame(random));
  truth.target = kNominalTarget;
  truth.offset[2] = joint_3_offset;
  truth.placement[3][0] = joint_4_shift_x;
  return truth;
}

double fitted(const GeometricCalibrationResult& result, const std::string& name) {
  for (const ParameterEstimate& p : result.parameters) {
    if (p.name == name && p.identified) return p.value;
  }
  ADD_FAILURE() << name << " not identified";
  return std::numeric_limits<double>::quiet_NaN();
}

void expectRefused(const MeasurementCampaign& campaign, const GeometricCalibrationOptions& options,
                   const std::string& named) {
  try {
    calibrateGeometry(ur10Model(), campaign, options);
    ADD_FAILURE() << "a calibration beyond the limits was accepted; expected it refused naming " << named;
  } catch (const ImplausibleGeometry& e) {
    EXPECT_THAT(e.what(), HasSubstr(named));
    EXPECT_THAT(e.what(), HasSubstr("--geometry-limits"));
  }
}

TEST(GeometryLimits, ACampaignBeyondAnOffsetsLimitIsRefusedAndOneInsideIsRecovered) {
  GeometricCalibrationOptions options;
  options.fit_compliance = false;
  const GeometryLimits limits;
  expectRefused(campaignOf(truthWith(1.5 * limits.offset, 0.0)), options, "joint_3.offset_rad");
  const GeometricCalibrationResult inside =
      calibrateGeometry(ur10Model(), campaignOf(truthWith(0.5 * limits.offset, 0.0)), options);
  EXPECT_NEAR(fitted(inside, "joint_3.offset_rad"), 0.5 * limits.offset, 1e-5);
  // The same campaign beyond the default, under a wider limit: the limit is the only reason it was refused.
  options.limits.offset = 2.0 * limits.offset;
  const GeometricCalibrationResult wider =
      calibrateGeometry(ur10Model(), campaignOf(truthWith(1.5 * limits.offset, 0.0)), options);
  EXPECT_NEAR(fitted(wider, "joint_3.offset_rad"), 1.5 * limits.offset, 1e-5);
}

TEST(GeometryLimits, ACampaignBeyondAPlacementsLimitIsRefusedAndOneInsideIsRecovered) {
  GeometricCalibrationOptions options;
  options.fit_compliance = false;
  const GeometryLimits limits;
  expectRefused(campaignOf(truthWith(0.0, 1.5 * limits.placement_shift)), options, "joint_4.placement_d*_m");
  const GeometricCalibrationResult inside =
      calibrateGeometry(ur10Model(), campaignOf(truthWith(0.0, 0.5 * limits.placement_shift)), options);
  EXPECT_NEAR(fitted(inside, "joint_4.placement_dx_m"), 0.5 * limits.placement_shift, 1e-5);
}

TEST(GeometryLimits, DiscoveryUndoesAFreedOffsetThatWouldCrossItsLimit) {
  // The base fits the frame and the target only; the truth's joint 3 zero is 1.5 times the limit away,
  // which freeing joint 3's offset would take whole. Joint 2's, inside the limit, is taken.
  const GeometryLimits limits;
  GeometricParameters truth = truthWith(1.5 * limits.offset, 0.0);
  truth.offset[1] = 0.3 * limits.offset;
  DiscoveryOptions options;
  options.types = {"offset"};
  options.max_steps = 3;
  options.calibration.fit_compliance = false;
  const DiscoveryResult r = discoverEffects(ur10Model(), {campaignOf(truth)}, {}, options);
  std::string said = r.rejected_at_stop;
  for (const DiscoveryStep& s : r.steps) {
    said += " " + s.rejected;
    for (const NamedEstimate& p : s.parameters) {
      EXPECT_LE(std::abs(p.value), limits.offset) << s.type << " " << p.name;
      EXPECT_NE(p.name, "joint_3.offset_rad");
    }
  }
  EXPECT_THAT(said, HasSubstr("joint_3.offset_rad"));
  EXPECT_EQ(geometryBeyondLimits(*ur10(), r.calibration.estimate, limits), "");
}

}  // namespace
}  // namespace jointcomp
