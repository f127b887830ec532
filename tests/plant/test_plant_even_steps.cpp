// PlantOptions::even_steps: an advance whose rest is more than CVODE's planned step but less than two ends in
// two equal steps, not in the planned step and a sliver (after which CVODE would restart from the sliver's
// size at order 1). Against CVODE alone (even_steps = false) on a smooth motion of every drive: at updates
// longer than CVODE's steps the even ending saves steps and Newton matrices and ends where CVODE alone
// ends (within the tolerances); at updates shorter than CVODE's steps it changes nothing that costs.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "tests/plant/plant_test_support.hpp"

#include "model/io/parameter_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"

namespace jointcomp {
namespace {

using namespace plant_testing;

struct SwingRun {
  PlantStatistics statistics;
  JointVector links, motors;
  bool every_advance_ended_on_time = true;
};

// Every drive swings from rest through a cosine for `seconds` (amplitudes 2 to 4 degrees, 0.1 to 0.2 Hz: slow
// enough that CVODE's steps are a few ms, as on the paper's spiral; swings of 5 to 15 degrees at 0.2 to 0.45 Hz
// held CVODE near 0.4 ms, where no update is short of a step), the reference updated
// every `update` seconds with its value and rate there, as a co-simulation master would.
SwingRun swing(bool even_steps, double update, double seconds) {
  const JointErrorModel model = loadParameterFile(kParameters, rx170());
  PlantOptions options;
  options.even_steps = even_steps;
  FlexibleJointPlant plant(model, loadDriveParameters(kParameters, *rx170()), options);
  const JointVector centre = joints({20.0, 45.0, 70.0, 30.0, 50.0, 10.0});
  const JointVector amplitude = joints({3.0, 2.0, 2.5, 4.0, 3.0, 2.0});
  const double hertz[6] = {0.1, 0.12, 0.14, 0.16, 0.18, 0.2};
  plant.reset(centre);
  SwingRun run;
  const int updates = static_cast<int>(std::lround(seconds / update));
  for (int k = 0; k < updates; ++k) {
    const double t = k * update;
    JointVector q = centre, v = JointVector::Zero(6);
    for (int j = 0; j < 6; ++j) {
      const double w = 2.0 * kPi * hertz[j];
      q[j] += amplitude[j] * (1.0 - std::cos(w * t));
      v[j] = amplitude[j] * w * std::sin(w * t);
    }
    plant.setReference(q, v);
    plant.advance((k + 1) * update);
    run.every_advance_ended_on_time = run.every_advance_ended_on_time && plant.time() == (k + 1) * update;
  }
  run.statistics = plant.statistics();
  run.links = plant.linkPositions();
  run.motors = plant.motorPositions();
  return run;
}

TEST(PlantEvenSteps, UpdatesLongerThanCvodesStepsCostFewerStepsAndEndTheSame) {
  const SwingRun alone = swing(false, 0.01, 2.0);
  const SwingRun even = swing(true, 0.01, 2.0);
  EXPECT_TRUE(even.every_advance_ended_on_time);
  EXPECT_LT(even.statistics.steps, 0.8 * alone.statistics.steps)
      << even.statistics.steps << " steps against " << alone.statistics.steps;
  EXPECT_LT(even.statistics.rhs_evaluations, 0.8 * alone.statistics.rhs_evaluations);
  EXPECT_LT(even.statistics.linear_solver_setups, alone.statistics.linear_solver_setups);
  // Both are within CVODE's tolerances of the true motion (rtol 1e-6 on angles near 1 rad).
  EXPECT_LE((even.links - alone.links).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LE((even.motors - alone.motors).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(PlantEvenSteps, UpdatesShorterThanCvodesStepsCostTheSame) {
  const SwingRun alone = swing(false, 0.001, 0.5);
  const SwingRun even = swing(true, 0.001, 0.5);
  EXPECT_TRUE(even.every_advance_ended_on_time);
  EXPECT_LE(even.statistics.steps, alone.statistics.steps + alone.statistics.steps / 50)
      << even.statistics.steps << " steps against " << alone.statistics.steps;
  EXPECT_LE((even.links - alone.links).cwiseAbs().maxCoeff(), 1e-6);
}

}  // namespace
}  // namespace jointcomp
