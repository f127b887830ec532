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

// The slow swing (plant_test_support.hpp) for `seconds`, the reference updated every `update` seconds.
SwingRun swing(bool even_steps, double update, double seconds) {
  const JointErrorModel model = loadParameterFile(kParameters, rx170());
  PlantOptions options;
  options.even_steps = even_steps;
  FlexibleJointPlant plant(model, loadDriveParameters(kParameters, *rx170()), options);
  plant.reset(swingCentre());
  SwingRun run;
  const int updates = static_cast<int>(std::lround(seconds / update));
  for (int k = 0; k < updates; ++k) {
    JointVector q, v;
    swingAt(k * update, q, v);
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
