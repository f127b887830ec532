// A plant never runs away silently. A reference step the drive cannot follow at once saturates the motor
// torque: the controller's integral must not wind up meanwhile (anti-windup), so the joint settles at the
// reference instead of swinging away; and a run that still leaves its joint limits or its tracking
// envelope (the drive's following-error window) is an error naming the joint and the reason, after which
// the plant refuses to go on until it is reset or restored.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/plant/plant_test_support.hpp"

#include "model/common/errors.hpp"
#include "model/io/parameter_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"

namespace jointcomp {
namespace {

using namespace plant_testing;

JointErrorModel rx170Model() { return loadParameterFile(kParameters, rx170()); }
std::vector<DriveParameters> rx170Drives() { return loadDriveParameters(kParameters, *rx170()); }

JointVector home() { return joints({0.0, 60.0, 60.0, 0.0, 60.0, 0.0}); }

// Advances in the 4 ms updates of a drive, holding the reference; returns the largest |q_j - target_j|
// over the last `settle_window` seconds.
double stepResponse(FlexibleJointPlant& plant, const JointVector& target, double duration, double settle_window,
                    int joint) {
  plant.setReference(target, JointVector::Zero(plant.dof()));
  double worst_late = 0.0;
  const double start = plant.time();
  for (double t = start + 0.004; t <= start + duration + 1e-12; t += 0.004) {
    plant.advance(t);
    if (t > start + duration - settle_window) {
      worst_late = std::max(worst_late, std::abs(plant.linkPositions()[joint] - target[joint]));
    }
  }
  return worst_late;
}

// The step of the issue: 0.1 rad on joint 1 saturates its drive. Without anti-windup the integral wound
// up during the saturation and the swing grew each cycle (joint 1 ended at 63 rad, every call OK); with
// it, the swing decays (the joint's lightly damped link mode rings for a few seconds, friction taking a
// little of it each cycle) and the joint comes to rest on its reference, the torque back inside its
// limit and the integral holding a bounded torque, not a long saturation's sum.
TEST(PlantRunaway, SaturatingStepDecaysWithoutWindup) {
  FlexibleJointPlant plant(rx170Model(), rx170Drives());
  plant.reset(home());
  JointVector target = home();
  target[0] += 0.1;
  // The step saturates the drive (otherwise this test would not test the anti-windup).
  plant.setReference(target, JointVector::Zero(6));
  plant.advance(0.004);
  const double limit = rx170()->joints[0].effort_limit;
  ASSERT_GT(limit, 0.0);
  EXPECT_NEAR(std::abs(plant.motorTorques()[0]), limit, 1e-9 * limit);

  const double first_second = stepResponse(plant, target, 1.0, 0.5, 0);
  const double eighth_second = stepResponse(plant, target, 7.0, 1.0, 0);
  EXPECT_GT(first_second, 0.01);  // the step did make it swing
  EXPECT_LT(eighth_second, 1e-3) << "joint 1 does not come to rest on its reference";
  EXPECT_LT(std::abs(plant.motorTorques()[0]), limit);
  const double integral_torque = rx170Drives()[0].ki_nm_per_rad_s * plant.state()[4 * 6 + 0];
  EXPECT_LT(std::abs(integral_torque), 0.5 * limit);
}

// Anti-windup touches nothing while the drive is not saturated: a small step's response is the same
// whether or not the torque limits are far away (no back-calculation term when nothing saturates).
TEST(PlantRunaway, AntiWindupIsSilentBelowSaturation) {
  JointVector target = home();
  target[1] += 0.002;
  FlexibleJointPlant plant(rx170Model(), rx170Drives());
  plant.reset(home());
  stepResponse(plant, target, 0.2, 0.0, 1);
  plant.advance(plant.time() + 0.004);
  const JointVector with_limits = plant.linkPositions();
  for (int j = 0; j < 6; ++j) EXPECT_LT(std::abs(plant.motorTorques()[j]), 0.5 * rx170()->joints[j].effort_limit);

  // The same robot with effort limits a thousand times larger: no saturation anywhere, same response.
  auto unlimited = std::make_shared<Robot>(*rx170());
  for (Joint& joint : unlimited->joints) joint.effort_limit *= 1000.0;
  FlexibleJointPlant reference_plant(loadParameterFile(kParameters, unlimited), rx170Drives());
  reference_plant.reset(home());
  stepResponse(reference_plant, target, 0.2, 0.0, 1);
  reference_plant.advance(reference_plant.time() + 0.004);
  for (int j = 0; j < 6; ++j) EXPECT_EQ(with_limits[j], reference_plant.linkPositions()[j]) << "joint " << j + 1;
}

// A reference the drive cannot follow (a 0.5 rad step, as the FMU was given) leaves the tracking
// envelope at once: the advance is an error naming the joint, the following error and the envelope;
// the plant then refuses to advance until reset, and after a reset it runs again.
TEST(PlantRunaway, LeavingTheTrackingEnvelopeIsAnError) {
  FlexibleJointPlant plant(rx170Model(), rx170Drives());
  plant.reset(home());
  JointVector target = home();
  target[0] -= 0.5;
  plant.setReference(target, JointVector::Zero(6));
  expectThrowMentioning<PlantLimitError>([&] { plant.advance(0.004); },
                                         {"joint_1", "following error", "tracking envelope"}, "0.5 rad step");
  EXPECT_EQ(plant.time(), 0.004);  // the integration itself succeeded: the state is where the run went
  expectThrowMentioning<PlantLimitError>([&] { plant.advance(0.008); }, {"joint_1", "reset"},
                                         "advance after the watchdog");

  plant.reset(home());
  plant.setReference(home(), JointVector::Zero(6));
  EXPECT_NO_THROW(plant.advance(0.1));

  // A wider envelope lets the same step through (a user's deliberate step-response study).
  PlantOptions wide;
  wide.tracking_envelope_rad = 1.0;
  FlexibleJointPlant patient(rx170Model(), rx170Drives(), wide);
  patient.reset(home());
  EXPECT_LT(stepResponse(patient, target, 8.0, 1.0, 0), 1e-3);
}

// A reference inside the tracking envelope that drives the link past its joint limit (a reference ramp
// beyond the limit, as a careless co-simulation master might send) trips on the joint limit, naming
// the joint, its position and its limits.
TEST(PlantRunaway, LeavingTheJointLimitsIsAnError) {
  const Joint& joint_5 = rx170()->joints[4];
  FlexibleJointPlant plant(rx170Model(), rx170Drives());
  JointVector start = home();
  start[4] = joint_5.upper - 0.01;
  plant.reset(start);
  bool tripped = false;
  JointVector position = start;
  JointVector velocity = JointVector::Zero(6);
  velocity[4] = 0.5;  // rad/s, past the upper limit within 0.1 s
  for (int k = 1; k <= 100 && !tripped; ++k) {
    position[4] = start[4] + velocity[4] * 0.004 * (k - 1);
    plant.setReference(position, velocity);
    try {
      plant.advance(0.004 * k);
    } catch (const PlantLimitError& e) {
      tripped = true;
      const std::string message = e.what();
      EXPECT_NE(message.find("joint_5"), std::string::npos) << message;
      EXPECT_NE(message.find("limit"), std::string::npos) << message;
      EXPECT_GT(plant.linkPositions()[4], joint_5.upper + plant.options().joint_limit_margin_rad);
    }
  }
  EXPECT_TRUE(tripped) << "the link went past its limit without an error";
}

// The watchdog's settings are checked like the other options.
TEST(PlantRunaway, WatchdogSettingsAreChecked) {
  for (const double bad : {0.0, -1.0, std::nan(""), HUGE_VAL}) {
    PlantOptions options;
    options.tracking_envelope_rad = bad;
    EXPECT_THROW(FlexibleJointPlant(rx170Model(), rx170Drives(), options), InvalidArgument) << bad;
    options = PlantOptions();
    options.joint_limit_margin_rad = bad == 0.0 ? -1e-3 : bad;
    EXPECT_THROW(FlexibleJointPlant(rx170Model(), rx170Drives(), options), InvalidArgument) << bad;
  }
}

}  // namespace
}  // namespace jointcomp
