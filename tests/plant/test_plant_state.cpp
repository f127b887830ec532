// Determinism and the state round trip of the flexible-joint plant. The same inputs must give
// bit-identical outputs (two plants, run one after the other or interleaved step by step); a state saved
// mid-motion and restored, into the same plant or into a fresh one, must continue bit for bit as the run
// that went on from the save.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/plant/plant_test_support.hpp"

#include "model/io/parameter_file.hpp"
#include "model/plant/flexible_joint_plant.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp {
namespace {

using namespace plant_testing;

constexpr double kPeriod = 0.004;  // s, reference updates

JointVector home() {
  JointVector q(6);
  q << 0.0, 60.0, 60.0, 0.0, 60.0, 0.0;
  return q * kDegree;
}

// A smooth motion of every joint: 0.1 rad sinusoids of different frequencies (phase chosen so that
// the reference starts at home with a velocity: the plant must catch up).
void referenceAt(double t, JointVector& position, JointVector& velocity) {
  position = home();
  velocity.resize(6);
  for (int j = 0; j < 6; ++j) {
    const double w = 2.0 * kPi * (0.4 + 0.15 * j);
    position[j] += 0.1 * std::sin(w * t);
    velocity[j] = 0.1 * w * std::cos(w * t);
  }
}

// What one period of a run produces.
struct Sample {
  std::vector<double> values;
  bool operator==(const Sample& other) const {
    return values.size() == other.values.size() &&
           std::memcmp(values.data(), other.values.data(), values.size() * sizeof(double)) == 0;
  }
};

Sample sampleOf(FlexibleJointPlant& plant) {
  Sample s;
  const JointVector parts[] = {plant.linkPositions(), plant.linkVelocities(), plant.motorPositions(),
                               plant.motorVelocities(), plant.motorTorques()};
  for (const JointVector& part : parts) s.values.insert(s.values.end(), part.data(), part.data() + part.size());
  s.values.push_back(plant.time());
  return s;
}

// Periods [first, last) of the moving reference: set the reference at the start of each, advance to
// its end, record.
std::vector<Sample> runPeriods(FlexibleJointPlant& plant, int first, int last) {
  std::vector<Sample> out;
  JointVector position, velocity;
  for (int k = first; k < last; ++k) {
    referenceAt(k * kPeriod, position, velocity);
    plant.setReference(position, velocity);
    plant.advance((k + 1) * kPeriod);
    out.push_back(sampleOf(plant));
  }
  return out;
}

std::unique_ptr<FlexibleJointPlant> makePlant() {
  const JointErrorModel model = loadParameterFile(kParameters, rx170());
  auto plant = std::make_unique<FlexibleJointPlant>(model, loadDriveParameters(kParameters, model.robot()));
  plant->reset(home());
  return plant;
}

void expectIdentical(const std::vector<Sample>& a, const std::vector<Sample>& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t k = 0; k < a.size(); ++k) {
    if (!(a[k] == b[k])) {
      for (std::size_t i = 0; i < a[k].values.size(); ++i) {
        ASSERT_EQ(a[k].values[i], b[k].values[i]) << what << ": period " << k << ", value " << i;
      }
    }
  }
}

constexpr int kHalf = 125;  // 0.5 s

TEST(PlantState, RestoredStateContinuesBitForBit) {
  auto plant = makePlant();
  plant->setPayload(8.0, Eigen::Vector3d(0.0, 0.03, 0.12));
  runPeriods(*plant, 0, kHalf);
  const PlantState saved = plant->saveState();
  const std::vector<Sample> continuation = runPeriods(*plant, kHalf, 2 * kHalf);
  // The run moved: the links went through the motion (and the result is not trivially constant).
  EXPECT_GT(std::abs(continuation.back().values[1] - continuation.front().values[1]), 1e-3);

  plant->restoreState(saved);
  EXPECT_EQ(plant->time(), saved.time);
  expectIdentical(continuation, runPeriods(*plant, kHalf, 2 * kHalf), "same plant, restored");

  // A fresh plant without the payload, given the saved state, knows everything too.
  auto fresh = makePlant();
  fresh->restoreState(saved);
  expectIdentical(continuation, runPeriods(*fresh, kHalf, 2 * kHalf), "fresh plant, restored");
}

// The counts of the integrator's work go on across its restarts (a step in the load, a restored state), which
// zero CVODE's own: a run's counts are those of a plant that did the same work in pieces.
TEST(PlantState, WorkCountsAddUpAcrossRestarts) {
  auto plant = makePlant();
  runPeriods(*plant, 0, kHalf);
  const PlantStatistics first = plant->statistics();
  const PlantState saved = plant->saveState();
  plant->setToolWrench((Vector6() << 0.0, 0.0, -20.0, 0.0, 0.0, 0.0).finished());  // a restart
  runPeriods(*plant, kHalf, 2 * kHalf);
  const PlantStatistics second = plant->statistics();
  plant->restoreState(saved);  // another
  runPeriods(*plant, kHalf, kHalf + 10);
  const PlantStatistics third = plant->statistics();

  // A fresh plant counting the second half alone, from the saved state with the same load.
  auto alone = makePlant();
  alone->restoreState(saved);
  alone->setToolWrench((Vector6() << 0.0, 0.0, -20.0, 0.0, 0.0, 0.0).finished());
  const PlantStatistics alone_before = alone->statistics();
  runPeriods(*alone, kHalf, 2 * kHalf);
  const PlantStatistics alone_after = alone->statistics();

  EXPECT_GT(first.steps, 0);
  EXPECT_GT(first.rhs_evaluations, first.steps);
  EXPECT_EQ(second.steps - first.steps, alone_after.steps - alone_before.steps);
  EXPECT_EQ(second.rhs_evaluations - first.rhs_evaluations, alone_after.rhs_evaluations - alone_before.rhs_evaluations);
  EXPECT_EQ(second.nonlinear_iterations - first.nonlinear_iterations,
            alone_after.nonlinear_iterations - alone_before.nonlinear_iterations);
  EXPECT_GT(third.steps, second.steps);
  EXPECT_GT(third.rhs_evaluations, second.rhs_evaluations);
}

TEST(PlantState, SavedStateIsTheState) {
  auto plant = makePlant();
  runPeriods(*plant, 0, 10);
  const PlantState saved = plant->saveState();
  ASSERT_EQ(saved.y.size(), 30U);
  const JointVector q = plant->linkPositions(), qd = plant->linkVelocities();
  const JointVector p = plant->motorPositions(), pd = plant->motorVelocities();
  for (int j = 0; j < 6; ++j) {
    EXPECT_EQ(saved.y[j], q[j]);
    EXPECT_EQ(saved.y[6 + j], qd[j]);
    EXPECT_EQ(saved.y[12 + j], p[j]);
    EXPECT_EQ(saved.y[18 + j], pd[j]);
  }
  EXPECT_EQ(saved.time, plant->time());
  EXPECT_DOUBLE_EQ(saved.time, 10 * kPeriod);
}

TEST(PlantState, ReadingTheStateIsTheSavedStateAndChangesNothing) {
  auto reader = makePlant();
  auto quiet = makePlant();
  std::vector<Sample> read_run, quiet_run;
  for (int k = 0; k < 2 * kHalf; ++k) {
    read_run.push_back(runPeriods(*reader, k, k + 1).front());
    const double* y = reader->state();
    const JointVector q = reader->linkPositions();
    for (int j = 0; j < 6; ++j) ASSERT_EQ(y[j], q[j]);
    quiet_run.push_back(runPeriods(*quiet, k, k + 1).front());
  }
  // Saving restarts the integrator's history; reading must not, or the runs would part.
  expectIdentical(quiet_run, read_run, "state read every period");
  const PlantState saved = reader->saveState();
  EXPECT_TRUE(std::equal(saved.y.begin(), saved.y.end(), reader->state()));
}

TEST(PlantState, TwoPlantsWithTheSameInputsAgreeBitForBit) {
  auto a = makePlant();
  auto b = makePlant();
  const std::vector<Sample> first = runPeriods(*a, 0, 2 * kHalf);
  const std::vector<Sample> second = runPeriods(*b, 0, 2 * kHalf);
  expectIdentical(first, second, "one after the other");

  // Interleaved period by period: nothing mutable is shared between two plants.
  auto c = makePlant();
  auto d = makePlant();
  std::vector<Sample> third, fourth;
  for (int k = 0; k < 2 * kHalf; ++k) {
    third.push_back(runPeriods(*c, k, k + 1).front());
    fourth.push_back(runPeriods(*d, k, k + 1).front());
  }
  expectIdentical(first, third, "interleaved, first plant");
  expectIdentical(first, fourth, "interleaved, second plant");
}

}  // namespace
}  // namespace jointcomp
