// PlantOptions::step_past_updates_s: CVODE steps through updates shorter than its own steps, the state at each
// update is interpolated from its last step, and an update's reference takes over from CVODE's next step on,
// unless it departs from the reference CVODE already integrated by more than step_past_tolerance_rad (then
// CVODE restarts at the update, and a jump of the input takes effect on time).
// Against the plant that stops at every update: fewer steps at 1 ms updates, the same motion within a few
// microradians (the updates land late), the same motion within the tolerances when the reference never
// changes (so the interpolated state is the state at the update, not CVODE's ahead of it), and a saved state or
// a restart continues from the state at the update.
#include <cmath>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "tests/plant/plant_test_support.hpp"

#include "model/common/errors.hpp"
#include "model/io/parameter_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"

namespace jointcomp {
namespace {

using namespace plant_testing;

constexpr double kPast = 0.01;  // s

std::unique_ptr<FlexibleJointPlant> makePlant(double step_past,
                                              double tolerance = PlantOptions().step_past_tolerance_rad) {
  static const JointErrorModel model = loadParameterFile(kParameters, rx170());
  PlantOptions options;
  options.step_past_updates_s = step_past;
  options.step_past_tolerance_rad = tolerance;
  return std::make_unique<FlexibleJointPlant>(model, loadDriveParameters(kParameters, *rx170()), options);
}

void setSwingReference(FlexibleJointPlant& plant, double t) {
  JointVector q, v;
  swingAt(t, q, v);
  plant.setReference(q, v);
}

struct Track {
  std::vector<JointVector> links;  // after each update
  PlantStatistics statistics;
  bool on_time = true;
};

// `updates` updates of `update` seconds from the plant's current time; swing: a new reference at each.
Track follow(FlexibleJointPlant& plant, double update, int updates, bool swing) {
  Track track;
  const double start = plant.time();
  for (int k = 0; k < updates; ++k) {
    const double t = start + k * update;
    if (swing) setSwingReference(plant, t);
    plant.advance(start + (k + 1) * update);
    track.on_time = track.on_time && plant.time() == start + (k + 1) * update;
    track.links.push_back(plant.linkPositions());
  }
  track.statistics = plant.statistics();
  return track;
}

double largestDifference(const Track& a, const Track& b) {
  double largest = 0.0;
  for (std::size_t i = 0; i < a.links.size() && i < b.links.size(); ++i) {
    largest = std::max(largest, (a.links[i] - b.links[i]).cwiseAbs().maxCoeff());
  }
  return largest;
}

// The swing from rest, on a plant that stops at every update and on one that steps past them.
std::pair<Track, Track> swingStoppingAndPast(double update, int updates) {
  auto stopping = makePlant(0.0);
  auto past = makePlant(kPast);
  stopping->reset(swingCentre());
  past->reset(swingCentre());
  return {follow(*stopping, update, updates, true), follow(*past, update, updates, true)};
}

TEST(PlantStepPast, ShortUpdatesCostFewerStepsAndFollowTheStoppingRunWithinMicroradians) {
  const auto [a, b] = swingStoppingAndPast(0.001, 1000);
  EXPECT_TRUE(b.on_time);
  EXPECT_GE(a.statistics.steps, 1000);  // one step per update at least, when it stops at each
  // 173 against 1038: CVODE's steps average about 6 updates. Reading CVODE's report of its next step after
  // one cut to the stop time past the update (CV_ONE_STEP) sent the plant back to stopping at updates: 248.
  EXPECT_LT(b.statistics.steps, 0.2 * a.statistics.steps)
      << b.statistics.steps << " steps against " << a.statistics.steps;
  const double largest = largestDifference(a, b);
  EXPECT_LT(largest, 5e-6);
  EXPECT_GT(largest, 0.0);
  // A smooth swing stays within the departure tolerance: CVODE was ahead at most updates and never restarted.
  EXPECT_GT(b.statistics.updates_stepped_past, 500);
  EXPECT_EQ(b.statistics.updates_restarted, 0);
  EXPECT_EQ(a.statistics.updates_stepped_past, 0);
}

// The swing with a step of 2 mrad on joint 2's reference from `jump_at` on (a master's correction), on the plant
// that stops at every update and on one that steps past them with `tolerance`.
std::pair<Track, Track> swingWithAJump(double tolerance, int jump_at, int updates) {
  auto stopping = makePlant(0.0);
  auto past = makePlant(kPast, tolerance);
  Track tracks[2];
  int which = 0;
  for (FlexibleJointPlant* plant : {stopping.get(), past.get()}) {
    plant->reset(swingCentre());
    for (int k = 0; k < updates; ++k) {
      JointVector q, v;
      swingAt(k * 0.001, q, v);
      if (k >= jump_at) q[1] += 2e-3;
      plant->setReference(q, v);
      plant->advance((k + 1) * 0.001);
      tracks[which].links.push_back(plant->linkPositions());
    }
    tracks[which].statistics = plant->statistics();
    ++which;
  }
  return {tracks[0], tracks[1]};
}

// An input that jumps departs from the reference CVODE already integrated past its update by far more than the
// tolerance: CVODE restarts at the update, the jump takes effect there as on the stopping plant, and the
// motion after it follows the stopping run's within microradians. Without the check (a tolerance of 10 rad)
// the jump lands up to a CVODE step late and the links lag the stopping run's by much more.
TEST(PlantStepPast, AnInputThatJumpsTakesEffectAtItsTime) {
  // The jump comes at the first update from 0.4 s on at which CVODE is ahead (the runs are the same until then).
  auto probe = makePlant(kPast);
  probe->reset(swingCentre());
  int jump_at = -1;
  for (int k = 0; k < 600 && jump_at < 0; ++k) {
    const long before = probe->statistics().updates_stepped_past;
    setSwingReference(*probe, k * 0.001);
    if (k >= 400 && probe->statistics().updates_stepped_past > before) jump_at = k;
    probe->advance((k + 1) * 0.001);
  }
  ASSERT_GE(jump_at, 400) << "CVODE was never ahead of an update";
  const auto [stopping, past] = swingWithAJump(PlantOptions().step_past_tolerance_rad, jump_at, 600);
  const auto [stopping_again, late] = swingWithAJump(10.0, jump_at, 600);
  EXPECT_GE(past.statistics.updates_restarted, 1);
  EXPECT_LE(past.statistics.updates_restarted, 3);  // the jump (and the velocity estimate's echo), not the swing
  EXPECT_EQ(late.statistics.updates_restarted, 0);
  EXPECT_GT(past.statistics.updates_stepped_past, 300);
  const double on_time = largestDifference(stopping, past);
  const double delayed = largestDifference(stopping_again, late);
  EXPECT_LT(on_time, 5e-6);
  EXPECT_GT(delayed, 10.0 * on_time) << "delayed " << delayed << " rad, on time " << on_time << " rad";
}

// Updates of half the horizon (kPast) or more end on their time, as without the option: at 10 ms updates
// CVODE's step would span at most about two, and stepping past them cost more steps than stopping. The
// same run as the stopping plant's, bit for bit; at exactly half too, however the update times round (at
// 5 ms a test without the rounding's allowance stepped past 5 of 200 updates).
TEST(PlantStepPast, UpdatesOfHalfTheHorizonOrMoreEndOnTheirTime) {
  for (const double update : {0.5 * kPast, kPast}) {
    const auto [a, b] = swingStoppingAndPast(update, 200);
    EXPECT_TRUE(b.on_time) << update << " s";
    EXPECT_EQ(b.statistics.updates_stepped_past, 0) << update << " s";
    EXPECT_EQ(b.statistics.steps, a.statistics.steps) << update << " s";
    EXPECT_EQ(largestDifference(a, b), 0.0) << update << " s";
  }
}

// Updates a binary fraction of a second apart (1/1024 s) are as long as the step CVODE reports after ending a
// step on one, which it cut to (end - t)(1 - 4 eps): they are stepped past like those of 1 ms, whose rounded
// lengths differ from update to update.
TEST(PlantStepPast, UpdatesAnExactBinaryFractionApartAreSteppedPast) {
  const auto [a, b] = swingStoppingAndPast(1.0 / 1024.0, 1000);
  EXPECT_TRUE(b.on_time);
  EXPECT_GT(b.statistics.updates_stepped_past, 500);
  EXPECT_LT(b.statistics.steps, 0.25 * a.statistics.steps)  // 223 against 1048; none stepped past before
      << b.statistics.steps << " steps against " << a.statistics.steps;
  EXPECT_LT(largestDifference(a, b), 5e-6);
}

// The reference is set once: both plants integrate the same equations, so the interpolated states agree with
// the stopping run's within the tolerances (CVODE's own state ahead of the update would be 1e-4 rad off).
TEST(PlantStepPast, AReferenceThatNeverChangesGivesTheStoppingRunsMotion) {
  auto stopping = makePlant(0.0);
  auto past = makePlant(kPast);
  const JointVector target = swingCentre() + joints({0.5, -0.4, 0.3, 0.6, -0.5, 0.4});
  for (FlexibleJointPlant* plant : {stopping.get(), past.get()}) {
    plant->reset(swingCentre());
    plant->setReference(target, JointVector::Zero(6));
  }
  const Track a = follow(*stopping, 0.001, 300, false);
  const Track b = follow(*past, 0.001, 300, false);
  EXPECT_TRUE(b.on_time);
  EXPECT_LT(b.statistics.steps, a.statistics.steps);
  double moved = 0.0;
  for (const JointVector& q : a.links) moved = std::max(moved, (q - swingCentre()).cwiseAbs().maxCoeff());
  EXPECT_GT(moved, 1e-3) << "the links move";
  EXPECT_LT(largestDifference(a, b), 1e-6);  // rtol 1e-6 on angles near 1 rad
}

TEST(PlantStepPast, ASavedStateContinuesIdenticallyHereAndInAnotherPlant) {
  auto plant = makePlant(kPast);
  plant->reset(swingCentre());
  follow(*plant, 0.001, 137, true);
  const PlantState saved = plant->saveState();
  const Track first = follow(*plant, 0.001, 200, true);
  plant->restoreState(saved);
  const Track again = follow(*plant, 0.001, 200, true);
  auto other = makePlant(kPast);
  other->restoreState(saved);
  const Track elsewhere = follow(*other, 0.001, 200, true);
  ASSERT_EQ(first.links.size(), 200u);
  for (std::size_t i = 0; i < first.links.size(); ++i) {
    ASSERT_EQ(first.links[i], again.links[i]) << "update " << i;
    ASSERT_EQ(first.links[i], elsewhere.links[i]) << "update " << i;
  }
}

// A restart (here a new tool wrench) starts CVODE afresh from the state at the update, not from its last step
// ahead of it: nothing moves at the restart, and the motion goes on as without it (within the tolerances).
TEST(PlantStepPast, ARestartContinuesFromTheStateAtTheUpdate) {
  auto plant = makePlant(kPast);
  auto reference = makePlant(kPast);
  plant->reset(swingCentre());
  reference->reset(swingCentre());
  follow(*plant, 0.001, 101, true);
  follow(*reference, 0.001, 101, true);
  const JointVector before = plant->linkPositions();
  plant->setToolWrench(Vector6::Zero());
  EXPECT_EQ(plant->linkPositions(), before);
  EXPECT_EQ(plant->time(), reference->time());
  const Track restarted = follow(*plant, 0.001, 20, true);
  const Track going_on = follow(*reference, 0.001, 20, true);
  EXPECT_LT(largestDifference(restarted, going_on), 5e-6);
}

// The static feed-forward is computed when first needed, not at each update (most updates are replaced before
// CVODE steps): forcing it at every update (motorTorques() reads it) changes no bit, also when the tool wrench
// changes after an update (the pending feed-forward is then computed with the loads of its update first).
TEST(PlantStepPast, TheFeedforwardComputedWhenNeededIsTheOneOfItsUpdate) {
  auto lazy = makePlant(kPast);
  auto eager = makePlant(kPast);
  Track tracks[2];
  int which = 0;
  for (FlexibleJointPlant* plant : {lazy.get(), eager.get()}) {
    plant->reset(swingCentre());
    for (int k = 0; k < 300; ++k) {
      setSwingReference(*plant, k * 0.001);
      if (plant == eager.get()) plant->motorTorques();
      if (k % 50 == 25) {
        Vector6 wrench = Vector6::Zero();
        wrench[2] = -20.0 - 0.1 * k;  // N, a process force that grows
        plant->setToolWrench(wrench);
      }
      plant->advance((k + 1) * 0.001);
      tracks[which].links.push_back(plant->linkPositions());
    }
    ++which;
  }
  for (std::size_t i = 0; i < tracks[0].links.size(); ++i) {
    ASSERT_EQ(tracks[0].links[i], tracks[1].links[i]) << "update " << i;
  }
}

TEST(PlantStepPast, OutOfRangeValuesAreRefusedWithTheOptionNamed) {
  for (const double value : {-0.001, 1.5, std::nan("")}) {
    try {
      makePlant(value);
      ADD_FAILURE() << value << " was accepted";
    } catch (const InvalidArgument& error) {
      EXPECT_NE(std::string(error.what()).find("step_past_updates_s"), std::string::npos) << error.what();
    }
    try {
      makePlant(kPast, value * 1e3);  // -1, 1500, NaN rad
      ADD_FAILURE() << value * 1e3 << " rad was accepted";
    } catch (const InvalidArgument& error) {
      EXPECT_NE(std::string(error.what()).find("step_past_tolerance_rad"), std::string::npos) << error.what();
    }
  }
}

}  // namespace
}  // namespace jointcomp
