// The controller's reference across updates (issue 17): with smooth_reference (not the default: it costs
// CVODE steps, model/plant/README.md) it is C2 at every update
// (value, velocity and acceleration just before and just after agree), its velocity and acceleration are
// the derivatives of its value, it becomes the new update's extrapolation once the blend is over, and the
// drives' torques do not jump. Without it the reference jumps, which shows the comparisons can fail.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "tests/plant/plant_test_support.hpp"

#include "model/common/errors.hpp"
#include "model/effects/payload.hpp"
#include "model/io/parameter_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"

namespace jointcomp {
namespace {

using namespace plant_testing;

JointVector home() { return joints({0.0, 60.0, 60.0, 0.0, 60.0, 0.0}); }

// A motion of every joint with a jerk (so that quadratic extrapolation is not exact): 0.1 rad sinusoids.
void motionAt(double t, JointVector& position, JointVector& velocity) {
  position = home();
  velocity.resize(6);
  for (int j = 0; j < 6; ++j) {
    const double w = 2.0 * kPi * (0.7 + 0.3 * j);
    position[j] += 0.1 * std::sin(w * t);
    velocity[j] = 0.1 * w * std::cos(w * t);
  }
}

std::unique_ptr<FlexibleJointPlant> makePlant(PlantOptions options = {}) {
  const JointErrorModel model = loadParameterFile(kParameters, rx170());
  auto plant = std::make_unique<FlexibleJointPlant>(model, loadDriveParameters(kParameters, model.robot()), options);
  plant->reset(home());
  return plant;
}

// Irregular update intervals (4 ms give or take 1.5 ms): the blend's duration follows them.
double updateTime(int k) { return 0.004 * k + 0.0015 * std::sin(1.7 * k); }

void runUpdates(FlexibleJointPlant& plant, int count) {
  JointVector position, velocity;
  for (int k = 0; k < count; ++k) {
    motionAt(updateTime(k), position, velocity);
    plant.setReference(position, velocity);
    plant.advance(updateTime(k + 1));
  }
}

struct ReferenceValues {
  JointVector position, velocity, acceleration;
};

ReferenceValues referenceOf(const FlexibleJointPlant& plant, double t) {
  ReferenceValues r;
  plant.referenceAt(t, r.position, r.velocity, r.acceleration);
  return r;
}

// A stop (velocity 0) after a motion at 1 rad/s: the reference holds the position given instead of
// extrapolating the last interval's -100 rad/s^2 (issue 41), and the plant settles there, watchdog quiet.
TEST(PlantReference, AStopHoldsItsPositionInsteadOfExtrapolatingTheLastDeceleration) {
  for (bool smooth : {false, true}) {
    PlantOptions options;
    options.smooth_reference = smooth;
    auto plant = makePlant(options);
    JointVector position = home(), velocity = JointVector::Zero(6);
    velocity[0] = 1.0;  // joint 1 turns at 1 rad/s, updated every 10 ms
    for (int k = 0; k < 10; ++k) {
      position[0] = home()[0] + 0.01 * k;
      plant->setReference(position, velocity);
      plant->advance(0.01 * (k + 1));
    }
    const JointVector target = position;
    plant->setReference(target, JointVector::Zero(6));
    const double stop = plant->time();
    for (double later : {0.02, 0.5, 2.0}) {  // after the blend (one interval) and far beyond it
      const ReferenceValues r = referenceOf(*plant, stop + later);
      EXPECT_NEAR((r.position - target).cwiseAbs().maxCoeff(), 0.0, 1e-12) << "smooth " << smooth << " at +" << later;
      EXPECT_EQ(r.velocity.cwiseAbs().maxCoeff(), 0.0);
      EXPECT_EQ(r.acceleration.cwiseAbs().maxCoeff(), 0.0);
    }
    ASSERT_NO_THROW(plant->advance(stop + 0.5));
    EXPECT_LT(std::fabs(plant->linkPositions()[0] - target[0]), 0.05);  // before: the reference 12.5 rad away
  }
}

TEST(PlantReference, IsC2AcrossAnUpdateAndTheMotorTorquesDoNotJump) {
  for (bool smooth : {true, false}) {
    PlantOptions options;
    options.smooth_reference = smooth;
    auto plant = makePlant(options);
    constexpr int kUpdates = 40;
    runUpdates(*plant, kUpdates);
    const double t = plant->time();
    const ReferenceValues before = referenceOf(*plant, t);
    const JointVector torque_before = plant->motorTorques();
    JointVector position, velocity;
    motionAt(t, position, velocity);
    plant->setReference(position, velocity);
    const ReferenceValues after = referenceOf(*plant, t);
    const JointVector torque_after = plant->motorTorques();
    const double position_jump = (after.position - before.position).cwiseAbs().maxCoeff();
    const double velocity_jump = (after.velocity - before.velocity).cwiseAbs().maxCoeff();
    const double acceleration_jump = (after.acceleration - before.acceleration).cwiseAbs().maxCoeff();
    const double torque_jump = (torque_after - torque_before).cwiseAbs().maxCoeff();
    if (smooth) {
      EXPECT_LE(position_jump, 1e-15) << "rad";
      EXPECT_LE(velocity_jump, 1e-13) << "rad/s";
      EXPECT_LE(acceleration_jump, 1e-10) << "rad/s^2";
      EXPECT_LE(torque_jump, 1e-9) << "N m";
    } else {
      // The update does jump without the blend: the extrapolation's error over 4 ms of this motion.
      EXPECT_GT(position_jump, 1e-7) << "rad";
      EXPECT_GT(velocity_jump, 1e-5) << "rad/s";
      EXPECT_GT(torque_jump, 1e-3) << "N m";
    }
  }
}

TEST(PlantReference, VelocityAndAccelerationAreTheDerivativesAndTheBlendEndsOnTheNewExtrapolation) {
  PlantOptions options;
  options.smooth_reference = true;
  auto plant = makePlant(options);
  constexpr int kUpdates = 40;
  runUpdates(*plant, kUpdates);
  const double t = plant->time();
  const double previous_update = updateTime(kUpdates - 1);
  JointVector previous_position, previous_velocity, position, velocity;
  motionAt(previous_update, previous_position, previous_velocity);
  motionAt(t, position, velocity);
  plant->setReference(position, velocity);
  const double duration = t - previous_update;
  // Central differences inside the blend (u = 0.1 ... 0.9) and beyond it.
  constexpr double kStep = 1e-6;  // s
  for (double u : {0.1, 0.35, 0.6, 0.9, 1.4}) {
    const double at = t + u * duration;
    const ReferenceValues here = referenceOf(*plant, at);
    const ReferenceValues ahead = referenceOf(*plant, at + kStep);
    const ReferenceValues behind = referenceOf(*plant, at - kStep);
    const JointVector velocity_by_difference = (ahead.position - behind.position) / (2.0 * kStep);
    const JointVector acceleration_by_difference = (ahead.velocity - behind.velocity) / (2.0 * kStep);
    EXPECT_LE((velocity_by_difference - here.velocity).cwiseAbs().maxCoeff(), 1e-7) << "u = " << u;
    EXPECT_LE((acceleration_by_difference - here.acceleration).cwiseAbs().maxCoeff(), 1e-5) << "u = " << u;
  }
  // Once the blend is over: the new update extrapolated with the acceleration between the last two.
  const JointVector acceleration = (velocity - previous_velocity) / duration;
  for (double u : {1.0, 1.5}) {
    const double dt = u * duration;
    const ReferenceValues r = referenceOf(*plant, t + dt);
    const JointVector expected = position + velocity * dt + 0.5 * acceleration * dt * dt;
    EXPECT_LE((r.position - expected).cwiseAbs().maxCoeff(), 1e-14) << "u = " << u;
    EXPECT_LE((r.velocity - (velocity + acceleration * dt)).cwiseAbs().maxCoeff(), 1e-12) << "u = " << u;
  }
}

// A saved state holds the blend: a fresh plant restored from it continues bit for bit, and forgetting the
// blend (the parts a state without one may leave empty) changes the continuation.
TEST(PlantReference, ASavedStateCarriesTheBlend) {
  PlantOptions options;
  options.smooth_reference = true;
  auto plant = makePlant(options);
  runUpdates(*plant, 20);
  JointVector position, velocity;
  motionAt(plant->time(), position, velocity);
  plant->setReference(position, velocity);
  const PlantState saved = plant->saveState();
  ASSERT_GT(saved.blend_duration, 0.0);
  const double end = plant->time() + 0.004;
  plant->advance(end);
  const JointVector continued = plant->linkPositions();

  auto fresh = makePlant(options);
  fresh->restoreState(saved);
  fresh->advance(end);
  const JointVector restored = fresh->linkPositions();
  for (int j = 0; j < 6; ++j) EXPECT_EQ(continued[j], restored[j]) << "joint " << j + 1;

  PlantState without = saved;
  without.blend_duration = 0.0;
  for (JointVector* part : {&without.blend_offset, &without.blend_offset_velocity, &without.blend_offset_acceleration,
                            &without.feedforward_offset, &without.feedforward_offset_rate}) {
    part->resize(0);
  }
  fresh->restoreState(without);
  fresh->advance(end);
  EXPECT_GT((fresh->linkPositions() - continued).cwiseAbs().maxCoeff(), 0.0);
  PlantState damaged = saved;
  damaged.blend_offset[2] = std::nan("");
  EXPECT_THROW(fresh->restoreState(damaged), InvalidArgument);
}

// Without a blend its offsets are never read, and setReference does not clear them at every update: they
// must be zero already, after a restored state without a blend (even one that holds offsets) and after the
// first update of a plant that does not blend taking over a state that does.
TEST(PlantReference, WithoutABlendItsOffsetsAreZero) {
  PlantOptions smooth;
  smooth.smooth_reference = true;
  auto blending = makePlant(smooth);
  runUpdates(*blending, 20);
  const PlantState saved = blending->saveState();
  ASSERT_GT(saved.blend_duration, 0.0);
  ASSERT_GT(saved.blend_offset.cwiseAbs().maxCoeff(), 0.0);
  const auto offsetsOf = [](const PlantState& state) {
    double largest = 0.0;
    for (const JointVector* part : {&state.blend_offset, &state.blend_offset_velocity, &state.blend_offset_acceleration,
                                    &state.feedforward_offset, &state.feedforward_offset_rate}) {
      EXPECT_EQ(part->size(), 6);
      largest = std::max(largest, part->cwiseAbs().maxCoeff());
    }
    return largest;
  };

  auto plain = makePlant();
  PlantState ended = saved;
  ended.blend_duration = 0.0;  // the offsets stay in the state
  plain->restoreState(ended);
  EXPECT_EQ(offsetsOf(plain->saveState()), 0.0);

  plain->restoreState(saved);  // a blend under way: it runs on until the next update
  EXPECT_GT(offsetsOf(plain->saveState()), 0.0);
  JointVector position, velocity;
  motionAt(plain->time(), position, velocity);
  plain->setReference(position, velocity);
  const PlantState after = plain->saveState();
  EXPECT_EQ(after.blend_duration, 0.0);
  EXPECT_EQ(offsetsOf(after), 0.0);
}

// The static feed-forward and its rate come from the joints' sines (gravity in joint frames) unless a load
// needs the tool's pose. A payload effect of no mass adds nothing but reads the poses, so that plant takes
// the forward kinematics' way. At tight tolerances (so that CVODE's step choices, which rounding can tip,
// move the links by less than the comparison) both follow the same updates to within 1e-10 rad; a payload
// of 5 kg, which the comparison must see, moves them by far more.
TEST(PlantReference, TheFeedforwardFromTheSinesIsTheForwardKinematicsOne) {
  const JointErrorModel model = loadParameterFile(kParameters, rx170());
  PlantOptions tight;
  tight.relative_tolerance = 1e-11;
  tight.absolute_tolerance = 1e-13;
  const auto plantWithPayload = [&](double mass) {
    JointErrorModel with = model;
    with.addEffect(std::make_unique<PayloadEffect>(model.robot(), mass, Eigen::Vector3d(0.0, 0.02, 0.1)));
    auto plant = std::make_unique<FlexibleJointPlant>(with, loadDriveParameters(kParameters, model.robot()), tight);
    plant->reset(home());
    return plant;
  };
  auto from_sines = makePlant(tight);
  auto from_poses = plantWithPayload(0.0);
  auto loaded = plantWithPayload(5.0);
  for (FlexibleJointPlant* plant : {from_sines.get(), from_poses.get(), loaded.get()}) runUpdates(*plant, 100);
  const double apart = (from_sines->linkPositions() - from_poses->linkPositions()).cwiseAbs().maxCoeff();
  const double loaded_apart = (loaded->linkPositions() - from_sines->linkPositions()).cwiseAbs().maxCoeff();
  std::cout << "[ plant ] feed-forward from the sines against the poses' way: links " << apart
            << " rad apart (a 5 kg payload: " << loaded_apart << " rad)\n";
  EXPECT_LT(apart, 1e-10);
  EXPECT_GT(loaded_apart, 1e-5);
}

}  // namespace
}  // namespace jointcomp
