// The dynamic compensation (model/dynamic_compensation/dynamic_compensation.hpp): with the model equal to the robot and
// no noise, a fast planned move is followed to within 1e-6 rad, where the static compensation leaves the drives' lag
// and the links' inertia; bad trajectories and drives are refused with the reason.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/compensation/compensator.hpp"
#include "model/dynamic_compensation/dynamic_compensation.hpp"
#include "model/io/parameter_file.hpp"
#include "tests/plant/plant_test_support.hpp"

namespace jointcomp {
namespace {

using plant_testing::joints;
using plant_testing::kParameters;
using plant_testing::rx170;

// A rest-to-rest septic move of joints 1 to 3 (and 5) in `duration` s, held still for 0.2 s before and
// after, sampled every 4 ms like the spiral.
JointTrajectory septicMove(double duration) {
  const JointVector start = joints({0, 30, 60, 0, 45, 0});
  const JointVector travel = joints({30, 20, -25, 0, 15, 0});
  JointTrajectory planned;
  const double period = 0.004, hold = 0.2;
  for (double t = 0.0; t <= duration + 2 * hold + 1e-9; t += period) {
    const double s = std::min(1.0, std::max(0.0, (t - hold) / duration));
    // The septic rest-to-rest profile: position, velocity, acceleration and jerk continuous.
    const double shape = s * s * s * s * (35 - 84 * s + 70 * s * s - 20 * s * s * s);
    const double rate = 140 * s * s * s * (1 - s) * (1 - s) * (1 - s) / duration;
    planned.time.push_back(t);
    planned.q.push_back(start + shape * travel);
    planned.qd.push_back(rate * travel);
  }
  return planned;
}

// The planned accelerations of septicMove(duration), from the profile's second derivative.
std::vector<JointVector> septicAcceleration(const JointTrajectory& planned, double duration) {
  const JointVector travel = joints({30, 20, -25, 0, 15, 0});
  const double hold = 0.2;
  std::vector<JointVector> acceleration;
  for (double t : planned.time) {
    const double s = std::min(1.0, std::max(0.0, (t - hold) / duration));
    acceleration.push_back(420 * s * s * (1 - s) * (1 - s) * (1 - 2 * s) / (duration * duration) * travel);
  }
  return acceleration;
}

// The closed form run sample by sample, as the FMU's dynamic mode does.
void compensateOnline(const ParameterSet& set, const JointTrajectory& planned,
                      const std::vector<JointVector>& acceleration, std::vector<JointVector>& reference,
                      std::vector<JointVector>& velocity) {
  OnlineDynamicCompensator online(set.model, set.drives);
  OnlineDynamicState state = online.initialState();
  reference.resize(planned.time.size());
  velocity.resize(planned.time.size());
  for (std::size_t k = 0; k < planned.time.size(); ++k) {
    const FixedPointReport report =
        online.compensate(state, planned.time[k], planned.q[k], planned.qd[k], acceleration[k], Vector6::Zero(),
                          reference[k], velocity[k], state);
    ASSERT_TRUE(report.converged) << "sample " << k;
  }
}

double largestLinkError(const std::vector<JointVector>& actual, const std::vector<JointVector>& planned) {
  double largest = 0.0;
  for (std::size_t k = 0; k < actual.size(); ++k)
    largest = std::max(largest, (actual[k] - planned[k]).cwiseAbs().maxCoeff());
  return largest;
}

TEST(DynamicCompensation, WithTheModelEqualToTheRobotTheLinksFollowAFastMoveWithin1e6Rad) {
  const ParameterSet set = loadParameterSet(kParameters, rx170());
  const JointTrajectory planned = septicMove(1.0);
  std::vector<JointVector> reference, velocity;
  // Tighter than the default (2e-6 rad, what a tracker could see): the refinement's own floor.
  DynamicCompensationOptions options;
  options.tolerance_rad = 2e-7;
  options.plant = DynamicCompensationOptions::tightPlantOptions(1e-8);
  const DynamicCompensationReport report =
      compensateDynamically(set.model, set.drives, planned, reference, velocity, options);

  FlexibleJointPlant robot(set.model, set.drives, options.plant);
  const double dynamic_error = largestLinkError(runReference(robot, planned.time, reference, velocity), planned.q);

  // The paper's static correction of every effect, on the same robot.
  std::vector<JointVector> static_reference;
  compensateTrajectory(set.model, set.model.allEffects(), planned.q, planned.qd, static_reference);
  const double static_error =
      largestLinkError(runReference(robot, planned.time, static_reference, planned.qd), planned.q);
  std::printf("static correction %.3g rad, dynamic: stage 1 %.3g rad, after %d runs %.3g rad (on the robot %.3g)\n",
              static_error, report.initial_error_rad, report.iterations, report.max_error_rad, dynamic_error);
  EXPECT_LT(dynamic_error, 1e-6);
  EXPECT_LT(report.initial_error_rad, static_error) << "stage 1 removes the links' inertia";
  EXPECT_LT(dynamic_error, 0.01 * static_error);
  EXPECT_LE(report.iterations, 30);
  EXPECT_GT(report.max_correction_rad, 1e-4);
}

// The online closed form (causal drive filter, planned accelerations) is the offline closed form (one run,
// no refinement; velocities and accelerations by central differences) re-derived: the references agree to
// a small part of the correction, and on the robot both leave the same error, a fraction of the static one.
TEST(DynamicCompensation, TheOnlineClosedFormMatchesTheOfflineOneAndRemovesMostOfTheDynamicError) {
  const ParameterSet set = loadParameterSet(kParameters, rx170());
  const double duration = 1.0;
  const JointTrajectory planned = septicMove(duration);
  std::vector<JointVector> offline, offline_velocity;
  DynamicCompensationOptions closed_form_only;
  closed_form_only.max_iterations = 1;
  closed_form_only.tolerance_rad = 1.0;  // whatever the first run leaves: the closed form is returned
  closed_form_only.plant = DynamicCompensationOptions::tightPlantOptions(1e-8);
  const DynamicCompensationReport offline_report =
      compensateDynamically(set.model, set.drives, planned, offline, offline_velocity, closed_form_only);
  std::vector<JointVector> online, online_velocity;
  compensateOnline(set, planned, septicAcceleration(planned, duration), online, online_velocity);

  double difference = 0.0;
  for (std::size_t k = 0; k < planned.time.size(); ++k)
    difference = std::max(difference, (online[k] - offline[k]).cwiseAbs().maxCoeff());
  FlexibleJointPlant robot(set.model, set.drives, closed_form_only.plant);
  const double online_error = largestLinkError(runReference(robot, planned.time, online, online_velocity), planned.q);
  std::vector<JointVector> static_reference;
  compensateTrajectory(set.model, set.model.allEffects(), planned.q, planned.qd, static_reference);
  const double static_error =
      largestLinkError(runReference(robot, planned.time, static_reference, planned.qd), planned.q);
  std::printf(
      "online vs offline closed form: references differ by %.3g rad (correction %.3g rad); link error "
      "static %.3g, offline closed form %.3g, online %.3g rad\n",
      difference, offline_report.max_correction_rad, static_error, offline_report.initial_error_rad, online_error);
  EXPECT_LT(difference, 0.02 * offline_report.max_correction_rad);  // central versus backward differences
  EXPECT_LT(online_error, 0.2 * static_error);
  EXPECT_LT(online_error, 2.0 * offline_report.initial_error_rad);
}

// The online state is a value: a sample repeated from the same state gives the same reference bit for bit;
// samples must move forward in time; drives must match the joints.
TEST(DynamicCompensation, TheOnlineStateIsAValueAndSamplesMoveForward) {
  const ParameterSet set = loadParameterSet(kParameters, rx170());
  const double duration = 0.5;
  const JointTrajectory planned = septicMove(duration);
  const std::vector<JointVector> acceleration = septicAcceleration(planned, duration);
  OnlineDynamicCompensator online(set.model, set.drives);
  OnlineDynamicState state = online.initialState(), once, twice;
  JointVector reference, velocity, again, again_velocity;
  for (std::size_t k = 0; k < 120; ++k) {
    online.compensate(state, planned.time[k], planned.q[k], planned.qd[k], acceleration[k], Vector6::Zero(), reference,
                      velocity, state);
  }
  const std::size_t k = 120;
  online.compensate(state, planned.time[k], planned.q[k], planned.qd[k], acceleration[k], Vector6::Zero(), reference,
                    velocity, once);
  online.compensate(state, planned.time[k], planned.q[k], planned.qd[k], acceleration[k], Vector6::Zero(), again,
                    again_velocity, twice);
  EXPECT_EQ(reference, again);
  EXPECT_EQ(velocity, again_velocity);
  EXPECT_EQ(once.delta, twice.delta);
  EXPECT_NE(once.delta, state.delta) << "the drive filter moved during the move";
  EXPECT_THROW(online.compensate(once, planned.time[k], planned.q[k], planned.qd[k], acceleration[k], Vector6::Zero(),
                                 reference, velocity, twice),
               InvalidArgument);
  JointVector not_finite = acceleration[k];
  not_finite[2] = std::nan("");
  EXPECT_THROW(online.compensate(once, planned.time[k + 1], planned.q[k + 1], planned.qd[k + 1], not_finite,
                                 Vector6::Zero(), reference, velocity, twice),
               InvalidArgument);
  std::vector<DriveParameters> five(set.drives.begin(), set.drives.begin() + 5);
  EXPECT_THROW(OnlineDynamicCompensator(set.model, five), InvalidArgument);
}

// With a payload and a process force, given to the compensation as to the robot, the same holds.
TEST(DynamicCompensation, APayloadAndAToolWrenchAreCompensatedToo) {
  const ParameterSet set = loadParameterSet(kParameters, rx170());
  const JointTrajectory planned = septicMove(0.8);
  DynamicCompensationOptions options;
  options.tolerance_rad = 2e-7;
  options.plant = DynamicCompensationOptions::tightPlantOptions(1e-8);
  options.payload_mass = 40.0;
  options.payload_com = Eigen::Vector3d(0.0, 0.05, 0.12);
  options.tool_wrench << 150.0, -80.0, -200.0, 5.0, 0.0, -3.0;
  std::vector<JointVector> reference, velocity;
  compensateDynamically(set.model, set.drives, planned, reference, velocity, options);
  FlexibleJointPlant robot(set.model, set.drives, options.plant);
  robot.setPayload(options.payload_mass, options.payload_com);
  robot.setToolWrench(options.tool_wrench);
  EXPECT_LT(largestLinkError(runReference(robot, planned.time, reference, velocity), planned.q), 1e-6);
  // The same references without the load leave the links off by what the load deflects.
  FlexibleJointPlant unloaded(set.model, set.drives, options.plant);
  EXPECT_GT(largestLinkError(runReference(unloaded, planned.time, reference, velocity), planned.q), 1e-5);
}

// The inertial torque a context carries is one more load the joints deflect under.
TEST(DynamicCompensation, TheInertialTorqueAddsToTheLoad) {
  const ParameterSet set = loadParameterSet(kParameters, rx170());
  JointErrorWorkspace ws(*rx170());
  JointContext ctx(6);
  ctx.q = joints({10, 40, 70, 5, 30, 0});
  computeLoadTorque(set.model, set.model.allEffects(), ws, ctx);
  const JointVector static_load = ctx.load_torque;
  ctx.inertial_torque = (JointVector(6) << 50, -120, 30, 2, -4, 1).finished();
  computeLoadTorque(set.model, set.model.allEffects(), ws, ctx);
  EXPECT_LT((ctx.load_torque - static_load - ctx.inertial_torque).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(DynamicCompensation, MalformedTrajectoriesAndDrivesAreRefusedWithTheReason) {
  const ParameterSet set = loadParameterSet(kParameters, rx170());
  std::vector<JointVector> reference, velocity;
  JointTrajectory planned = septicMove(0.5);
  auto refused = [&](const JointTrajectory& trajectory, const std::vector<DriveParameters>& drives,
                     const std::string& fragment) {
    try {
      compensateDynamically(set.model, drives, trajectory, reference, velocity);
      ADD_FAILURE() << "accepted; expected an error saying " << fragment;
    } catch (const InvalidArgument& error) {
      EXPECT_NE(std::string(error.what()).find(fragment), std::string::npos) << error.what();
    }
  };
  JointTrajectory short_one = planned;
  short_one.time.resize(2);
  short_one.q.resize(2);
  short_one.qd.resize(2);
  refused(short_one, set.drives, "at least three samples");
  JointTrajectory backwards = planned;
  backwards.time[5] = backwards.time[4];
  refused(backwards, set.drives, "sample 5: times must be finite and increasing");
  JointTrajectory not_finite = planned;
  not_finite.q[7][2] = std::nan("");
  refused(not_finite, set.drives, "planned position");
  refused(planned, std::vector<DriveParameters>(set.drives.begin(), set.drives.begin() + 5), "5 drives");
}

}  // namespace
}  // namespace jointcomp
