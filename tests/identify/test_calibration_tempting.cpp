// The calibration's compliance constraint (ComplianceEffect::implausibility: positive, a stiffness of at
// least kMinPlausibleStiffness, a deflection within 0.01 rad at the largest torque) driven by whole
// campaigns: a truth that deflects backwards, one that deflects by 0.02 rad, and the same at half the bound,
// in calibrate and in discovery's "compliance" candidate. The deflection is re-derived here from the
// campaign's own load torques, and the bound is stated here, not read from the code.
#include <cmath>
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

constexpr double kPlausibleDeflection = 0.01;  // rad: the bound the constraint states, said again here
constexpr int kJoint = 1;                      // joint_2: the shoulder, which carries the most torque

std::vector<JointVector> poses() { return randomPoses(120, 21); }

// The largest |load torque| of joint 2 over the poses, from the nominal robot's gravity (what the
// calibration's compliance multiplies).
double largestTorque() {
  GeometricParameters zero = GeometricParameters::zero(6);
  zero.target = kNominalTarget;
  const CalibrationData data = prepareCalibrationData(
      ur10Model(), simulateGeometricCampaign(ur10Model(), zero, poses(), 0.0, 1, kNominalTarget));
  double largest = 0.0;
  for (const JointVector& torque : data.load_torque) largest = std::max(largest, std::abs(torque[kJoint]));
  return largest;
}

MeasurementCampaign campaignWithCompliance(double compliance) {
  DeterministicRandom random(13);
  GeometricParameters truth = GeometricParameters::zero(6);
  truth.setInstrumentFromBase(trackerFrame(random));
  truth.target = kNominalTarget;
  truth.compliance[kJoint] = compliance;
  return simulateGeometricCampaign(ur10Model(), truth, poses(), 1e-6, 4, kNominalTarget);
}

const ParameterEstimate& estimateOf(const GeometricCalibrationResult& result, const std::string& name) {
  for (const ParameterEstimate& p : result.parameters) {
    if (p.name == name) return p;
  }
  throw std::runtime_error("no parameter " + name);
}

TEST(CalibrationTempting, TheLargestTorqueIsAShouldersUnderGravity) {
  // 28 kg of arm about 0.6 m from the shoulder: a hundred N m or more, never thousands.
  EXPECT_GT(largestTorque(), 80.0);
  EXPECT_LT(largestTorque(), 600.0);
}

TEST(CalibrationTempting, AComplianceAcrossItsConstraintIsHeldAtNominalAndOneInsideIsFitted) {
  const double torque = largestTorque();
  const std::string name = "joint_2.compliance_rad_per_nm";
  struct Case {
    double deflection;  // rad at the largest torque
    const char* says;   // what the calibration says of it; empty: fitted
  };
  for (const Case& c :
       {Case{-0.5 * kPlausibleDeflection, "not positive"}, Case{2.0 * kPlausibleDeflection, "beyond the plausible"},
        Case{0.5 * kPlausibleDeflection, ""}}) {
    const double truth = c.deflection / torque;
    const GeometricCalibrationResult r = calibrateGeometry(ur10Model(), campaignWithCompliance(truth));
    const ParameterEstimate& p = estimateOf(r, name);
    std::printf("[ tempting ] truth %.3g rad/(N m) (%.3g rad at %.1f N m): %s %.3g %s\n", truth, c.deflection, torque,
                p.identified ? "fitted" : "held", p.value, p.fixed_because.c_str());
    if (*c.says == '\0') {
      EXPECT_TRUE(p.identified) << p.fixed_because;
      EXPECT_NEAR(p.value, truth, 1e-3 * std::abs(truth));
    } else {
      EXPECT_FALSE(p.identified);
      EXPECT_THAT(p.fixed_because, HasSubstr("not physical"));
      EXPECT_THAT(p.fixed_because, HasSubstr(c.says));
      EXPECT_EQ(p.value, p.nominal);
    }
    EXPECT_LE(std::abs(r.estimate.compliance[kJoint]) * torque, kPlausibleDeflection);
  }
}

TEST(CalibrationTempting, DiscoveryNeverTakesACompliancePastItsConstraint) {
  // Discovery's base fits the frame and target only; the "compliance" candidate frees a joint's compliance,
  // and the truth's shoulder deflects by twice the bound.
  const double torque = largestTorque();
  DiscoveryOptions options;
  options.types = {"compliance"};
  options.max_steps = 3;
  const DiscoveryResult r =
      discoverEffects(ur10Model(), {campaignWithCompliance(2.0 * kPlausibleDeflection / torque)}, {}, options);
  for (const DiscoveryStep& s : r.steps) {
    for (const NamedEstimate& p : s.parameters) {
      std::printf("[ tempting ] step %s %s = %.3g\n", s.type.c_str(), p.name.c_str(), p.value);
      if (p.name == "joint_2.compliance_rad_per_nm") {
        EXPECT_GT(p.value, 0.0);
        EXPECT_LE(p.value * torque, kPlausibleDeflection);
      }
    }
  }
  EXPECT_GT(r.final_state.fitted.rms, 1e-4) << "the shoulder's deflection was explained, past its bound";
  EXPECT_LE(r.calibration.estimate.compliance[kJoint] * torque, kPlausibleDeflection);

  // The same at half the bound is taken, and the shoulder's compliance found.
  const double inside = 0.5 * kPlausibleDeflection / torque;
  const DiscoveryResult taken = discoverEffects(ur10Model(), {campaignWithCompliance(inside)}, {}, options);
  bool found = false;
  for (const DiscoveryStep& s : taken.steps) {
    for (const NamedEstimate& p : s.parameters) {
      if (p.name != "joint_2.compliance_rad_per_nm") continue;
      found = true;
      EXPECT_NEAR(p.value, inside, 1e-3 * inside);
    }
  }
  EXPECT_TRUE(found) << taken.stop_reason << "; " << taken.rejected_at_stop;
}

}  // namespace
}  // namespace jointcomp
