// The paper's experiment (Olabi et al. 2012, Table II) on the shipped RX170: with the default spec the
// stiffness-and-kinematic run must reduce Ra and Rz at least as much as the paper did (85 % and 48 %), the
// stiffness-only run lies between, the numbers are bit-identical from run to run, and a spiral out of reach
// is reported with the path sample that cannot be reached.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/experiment/spiral_experiment.hpp"
#include "model/io/parameter_file.hpp"
#include "model/robot/kinematics.hpp"
#include "model/robot/load_urdf.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

std::shared_ptr<const Robot> rx170() {
  static const std::shared_ptr<const Robot> robot =
      std::make_shared<const Robot>(loadRobotFromUrdfFile(std::string(JOINTCOMP_DATA_DIR) + "/robots/rx170.urdf"));
  return robot;
}

const JointErrorModel& nominal() {
  static const JointErrorModel model =
      loadParameterFile(std::string(JOINTCOMP_DATA_DIR) + "/params/rx170.json", rx170());
  return model;
}

const SpiralExperimentResult& defaultResult() {
  static const SpiralExperimentResult result = runSpiralExperiment(nominal(), SpiralExperimentSpec{});
  return result;
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(SpiralExperiment, DefaultSpecReproducesThePapersReductions) {
  const SpiralExperimentResult& result = defaultResult();
  const AccuracyMetrics& none = result.runs[0].metrics;
  const AccuracyMetrics& stiffness = result.runs[1].metrics;
  const AccuracyMetrics& both = result.runs[2].metrics;
  for (const SpiralRun& run : result.runs) {
    std::cout << "[ spiral ] " << run.name << ": Ra " << run.metrics.ra * 1e3 << " mm, Rz " << run.metrics.rz * 1e3
              << " mm\n";
  }
  const double ra_reduction = 1.0 - both.ra / none.ra;
  const double rz_reduction = 1.0 - both.rz / none.rz;
  std::cout << "[ spiral ] reductions: Ra " << 100 * ra_reduction << " %, Rz " << 100 * rz_reduction << " %\n";
  RecordProperty("ra_reduction_percent", std::to_string(100 * ra_reduction));
  RecordProperty("rz_reduction_percent", std::to_string(100 * rz_reduction));
  // Paper: Ra 0.2032 -> 0.0312 mm (-84.6 %), Rz 0.2882 -> 0.1502 mm (-47.9 %).
  EXPECT_GE(ra_reduction, 0.85);
  EXPECT_GE(rz_reduction, 0.48);
  // The stiffness correction alone helps, but less.
  EXPECT_LT(stiffness.ra, none.ra);
  EXPECT_GT(stiffness.ra, both.ra);
  EXPECT_LT(stiffness.rz, none.rz);
  EXPECT_GT(stiffness.rz, both.rz);
  // Uncorrected, the error is of the paper's order: a tenth of a millimetre, not microns or centimetres.
  EXPECT_GT(none.ra, 0.02e-3);
  EXPECT_LT(none.ra, 2e-3);
}

TEST(SpiralExperiment, RunsAreCompleteAndNamed) {
  const SpiralExperimentResult& result = defaultResult();
  const std::size_t n = result.planned.size();
  ASSERT_GT(n, 1000u);
  EXPECT_EQ(result.runs[0].name, "without correction");
  EXPECT_EQ(result.runs[1].name, "stiffness correction");
  EXPECT_EQ(result.runs[2].name, "stiffness and kinematic correction");
  for (const SpiralRun& run : result.runs) {
    EXPECT_EQ(run.reference.size(), n) << run.name;
    EXPECT_EQ(run.actual.size(), n) << run.name;
    EXPECT_EQ(run.measured.size(), n) << run.name;
    EXPECT_EQ(run.error.size(), n) << run.name;
  }
  // Without correction the references are the plan.
  for (std::size_t k = 0; k < n; k += 97) EXPECT_EQ(result.runs[0].reference[k], result.planned.q[k]);
  // The error is what was measured minus the planned point, and the measured point is the forward
  // kinematics of where the links went plus tracker noise of some micrometres.
  RobotWorkspace fk(*rx170());
  for (const SpiralRun& run : result.runs) {
    for (std::size_t k = 0; k < n; k += 97) {
      EXPECT_LT((run.error[k] - (run.measured[k] - result.planned.tool_position[k])).norm(), 1e-15);
      forwardKinematics(*rx170(), fk, run.actual[k]);
      EXPECT_LT((run.measured[k] - fk.tool_pose.translation()).norm(), 50e-6) << run.name << ", sample " << k;
    }
  }
}

TEST(SpiralExperiment, IsDeterministic) {
  const SpiralExperimentResult& first = defaultResult();
  const SpiralExperimentResult second = runSpiralExperiment(nominal(), SpiralExperimentSpec{});
  for (int r = 0; r < 3; ++r) {
    const AccuracyMetrics& a = first.runs[r].metrics;
    const AccuracyMetrics& b = second.runs[r].metrics;
    EXPECT_TRUE(sameBits(a.ra, b.ra)) << "run " << r;
    EXPECT_TRUE(sameBits(a.rz, b.rz)) << "run " << r;
    EXPECT_TRUE(sameBits(a.rms, b.rms)) << "run " << r;
    EXPECT_TRUE(sameBits(a.max, b.max)) << "run " << r;
    EXPECT_TRUE(sameBits(a.mean, b.mean)) << "run " << r;
    ASSERT_EQ(first.runs[r].error.size(), second.runs[r].error.size());
    for (std::size_t k = 0; k < first.runs[r].error.size(); ++k) {
      ASSERT_EQ(first.runs[r].error[k], second.runs[r].error[k]) << "run " << r << ", sample " << k;
    }
  }
}

TEST(SpiralExperiment, AKeptDrawHasTheBitsOfTheExperimentAndItsLinksAreAtTheTruthsFixedPoint) {
  // drawSpiralRuns into a SpiralDraw that held another truth's draw (a Monte Carlo worker's reuse) gives the
  // experiment's bits; and each settled sample, re-evaluated with forward kinematics (not the joint-frame
  // gravity of the settling, not its extrapolated start), satisfies q = command + dq(q, command).
  const SpiralExperimentSpec spec;
  const PreparedSpiral prepared = prepareSpiralRuns(nominal(), spec);
  const JointErrorModel truth = perturbedModel(nominal(), spec.truth);
  SpiralDraw draw;
  SpiralExperimentSpec other_seed = spec;
  other_seed.noise_seed = 3;
  drawSpiralRuns(prepared, nominal(), other_seed, draw);
  drawSpiralRuns(prepared, truth, spec, draw);
  const SpiralExperimentResult& expected = defaultResult();
  JointErrorWorkspace ws(truth.robot());
  double largest_residual = 0.0, largest_deflection = 0.0;
  for (int r = 0; r < 3; ++r) {
    EXPECT_TRUE(sameBits(draw.metrics[r].ra, expected.runs[r].metrics.ra)) << "run " << r;
    EXPECT_TRUE(sameBits(draw.metrics[r].rz, expected.runs[r].metrics.rz)) << "run " << r;
    ASSERT_EQ(draw.error[r].size(), expected.runs[r].error.size());
    for (std::size_t k = 0; k < draw.error[r].size(); ++k) {
      ASSERT_EQ(draw.error[r][k], expected.runs[r].error[k]) << "run " << r << ", sample " << k;
      ASSERT_EQ(draw.actual[r][k], expected.runs[r].actual[k]) << "run " << r << ", sample " << k;
    }
    for (std::size_t k = 0; k < draw.actual[r].size(); k += 7) {
      JointContext ctx(truth.robot().dof());
      ctx.q = draw.actual[r][k];
      ctx.command = prepared.runs[r].reference[k];
      ctx.velocity = prepared.planned.qd[k];
      ctx.time = prepared.planned.time[k];
      updateMotorAngles(truth, ctx);
      computeLoadTorque(truth, truth.allEffects(), ws, ctx);
      JointVector dq = JointVector::Zero(truth.robot().dof());
      addSelectedJointErrors(truth, truth.allEffects(), ctx, dq);
      largest_residual = std::max(largest_residual, (ctx.command + dq - ctx.q).cwiseAbs().maxCoeff());
      largest_deflection = std::max(largest_deflection, dq.cwiseAbs().maxCoeff());
    }
  }
  EXPECT_LT(largest_residual, 1e-11);
  EXPECT_GT(largest_deflection, 1e-4);  // the links did deflect: the check is not of q = command
}

TEST(SpiralExperiment, ADifferentNoiseSeedChangesTheMeasurementsOnly) {
  // The seed does reach the numbers (so that the determinism test above can fail), yet moves the scores by
  // no more than the tracker's noise allows.
  SpiralExperimentSpec spec;
  spec.noise_seed = 8;
  const SpiralExperimentResult other = runSpiralExperiment(nominal(), spec);
  const SpiralExperimentResult& first = defaultResult();
  EXPECT_FALSE(sameBits(other.runs[0].metrics.ra, first.runs[0].metrics.ra));
  for (int r = 0; r < 3; ++r) {
    EXPECT_EQ(other.runs[r].actual.back(), first.runs[r].actual.back()) << "run " << r;
    EXPECT_NEAR(other.runs[r].metrics.ra, first.runs[r].metrics.ra, 5e-6) << "run " << r;
  }
}

TEST(SpiralExperiment, UnreachableSpiralNamesThePathSample) {
  SpiralExperimentSpec spec;
  spec.spiral.centre = Eigen::Vector3d(3.0, 0.0, 0.2);
  try {
    runSpiralExperiment(nominal(), spec);
    FAIL() << "a spiral 3 m away was planned";
  } catch (const UnreachableError& error) {
    EXPECT_THAT(error.what(), HasSubstr("path sample 0"));
  }
}

// The plant's experiment at ten times the paper's feed rate (acceleration and jerk scaled with it, as
// `jointcomp paper --feed-rate` does), with the fourth run.
SpiralExperimentSpec tenTimesThePapersSpeedWithTheDynamicRun(const ParameterSet& set) {
  SpiralExperimentSpec spec;
  spec.drives = set.drives;
  spec.dynamic_correction = true;
  spec.feed_rate.speed *= 10.0;
  spec.feed_rate.acceleration *= 10.0;
  spec.feed_rate.jerk *= 10.0;
  return spec;
}

// The fourth run at ten times the paper's speed, on the plant with model != truth: the dynamic correction
// removes what the static one leaves of the drives' lag and the links' inertia (docs/dynamic-correction.md's table).
TEST(SpiralExperiment, TheDynamicCorrectionFollowsTheSpiralAtTenTimesThePapersSpeed) {
  const ParameterSet set = loadParameterSet(std::string(JOINTCOMP_DATA_DIR) + "/params/rx170.json", rx170());
  const SpiralExperimentSpec spec = tenTimesThePapersSpeedWithTheDynamicRun(set);
  const SpiralExperimentResult result = runSpiralExperiment(set.model, spec);
  ASSERT_EQ(result.runs.size(), 4u);
  const AccuracyMetrics& static_run = result.runs[2].metrics;
  const AccuracyMetrics& dynamic_run = result.runs[3].metrics;
  EXPECT_EQ(result.runs[3].name, "stiffness, kinematic and dynamic correction");
  EXPECT_LT(dynamic_run.rms, 0.1 * static_run.rms);
  EXPECT_LT(dynamic_run.max, 0.1 * static_run.max);
  EXPECT_LT(dynamic_run.rz, 0.5 * static_run.rz);
  EXPECT_LT(dynamic_run.ra, static_run.ra);
  EXPECT_LE(result.runs[3].dynamic_compensation.max_error_rad, spec.dynamic.tolerance_rad);
  EXPECT_GT(result.runs[3].dynamic_compensation.initial_error_rad, result.runs[3].dynamic_compensation.max_error_rad);
}

// The same with the robot equal to the model (the tracker's noise remains): nothing is left of the model's
// mismatch, so issue 18's target holds in full: the dynamic correction's Ra and Rz at most half the static
// one's at ten times the paper's speed. (With model != truth above, Ra stops at the mismatch's 0.024 mm,
// which the static correction leaves at the paper's speed too.)
TEST(SpiralExperiment, WithTheModelEqualToTheRobotTheDynamicCorrectionHalvesRaAndRzAtTenTimesTheSpeed) {
  const ParameterSet set = loadParameterSet(std::string(JOINTCOMP_DATA_DIR) + "/params/rx170.json", rx170());
  const SpiralExperimentSpec spec = tenTimesThePapersSpeedWithTheDynamicRun(set);
  const SpiralExperimentResult result = runSpiralExperiment(set.model, set.model, spec);
  ASSERT_EQ(result.runs.size(), 4u);
  const AccuracyMetrics& static_run = result.runs[2].metrics;
  const AccuracyMetrics& dynamic_run = result.runs[3].metrics;
  std::printf(
      "model = robot, 10x: static Ra %.4f Rz %.4f RMS %.4f max %.4f mm; dynamic Ra %.4f Rz %.4f RMS %.4f "
      "max %.4f mm\n",
      static_run.ra * 1e3, static_run.rz * 1e3, static_run.rms * 1e3, static_run.max * 1e3, dynamic_run.ra * 1e3,
      dynamic_run.rz * 1e3, dynamic_run.rms * 1e3, dynamic_run.max * 1e3);
  EXPECT_LE(dynamic_run.ra, 0.5 * static_run.ra);
  EXPECT_LE(dynamic_run.rz, 0.5 * static_run.rz);
}

TEST(SpiralExperiment, TheDynamicCorrectionNeedsThePlant) {
  SpiralExperimentSpec spec;  // no drives: the quasi-static robot
  spec.dynamic_correction = true;
  EXPECT_THROW(runSpiralExperiment(nominal(), spec), InvalidArgument);
}

}  // namespace
}  // namespace jointcomp
