#include "model/experiment/spiral_experiment.hpp"

#include <chrono>

#include "model/common/errors.hpp"
#include "model/common/random.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;

void tell(const std::function<void(const std::string&)>& progress, const std::string& what) {
  if (progress) progress(what);
}

}  // namespace

SpiralSpec SpiralExperimentSpec::defaultSpiral() {
  SpiralSpec spiral;
  spiral.centre = Eigen::Vector3d(1.2, 0.0, 0.2);
  return spiral;
}

JointTrajectory planSpiralTrajectory(const Robot& robot, const SpiralSpec& spiral, const FeedRateSpec& feed_rate,
                                     JointVector seed_posture) {
  const std::vector<FeedRateSample> samples = planFeedRate(logarithmicSpiral(spiral), feed_rate);
  if (seed_posture.size() == 0) {
    seed_posture = JointVector::Zero(robot.dof());
    if (robot.dof() >= 5) {
      seed_posture[1] = 60 * kDegree;
      seed_posture[2] = 60 * kDegree;
      seed_posture[4] = 60 * kDegree;
    }
  }
  return planJointTrajectory(robot, samples, toolPointingDown(), seed_posture);
}

SpiralExperimentResult runSpiralExperiment(const JointErrorModel& nominal, const SpiralExperimentSpec& spec,
                                           const std::function<void(const std::string&)>& progress) {
  return runSpiralExperiment(nominal, perturbedModel(nominal, spec.truth), spec, progress);
}

SpiralExperimentResult runSpiralExperiment(const JointErrorModel& nominal, const JointErrorModel& truth,
                                           const SpiralExperimentSpec& spec,
                                           const std::function<void(const std::string&)>& progress) {
  const Robot& robot = nominal.robot();
  const Robot& true_robot = truth.robot();
  if (true_robot.dof() != robot.dof()) {
    throw InvalidArgument("the truth robot '" + true_robot.name + "' has " + std::to_string(true_robot.dof()) +
                          " joints, the nominal robot '" + robot.name + "' " + std::to_string(robot.dof()));
  }
  for (int joint : spec.compensated_joints) {
    if (joint < 0 || joint >= robot.dof()) {
      throw InvalidArgument("compensated joint " + std::to_string(joint + 1) + " does not exist: robot '" + robot.name +
                            "' has joints 1 to " + std::to_string(robot.dof()));
    }
  }
  SpiralExperimentResult result;
  tell(progress, "planning the spiral (feed rate, inverse kinematics)");
  result.planned = planSpiralTrajectory(robot, spec.spiral, spec.feed_rate, spec.seed_posture);

  const EffectMask truth_mask = truth.allEffects();
  const EffectMask run_masks[3] = {0, nominal.loadsAnd({"compliance"}),
                                   nominal.loadsAnd({"compliance", "transmission_error"})};
  const char* run_names[4] = {"without correction", "stiffness correction", "stiffness and kinematic correction",
                              "stiffness, kinematic and dynamic correction"};

  JointErrorWorkspace ws(robot);
  JointErrorWorkspace true_ws(true_robot);
  result.dynamic = !spec.drives.empty();
  std::unique_ptr<FlexibleJointPlant> plant;
  if (result.dynamic) plant = std::make_unique<FlexibleJointPlant>(truth, spec.drives, spec.plant);
  if (spec.dynamic_correction && !result.dynamic) {
    throw InvalidArgument(
        "the dynamic correction needs the plant (drives in the parameter file), not the "
        "quasi-static robot");
  }
  const int run_count = spec.dynamic_correction ? 4 : 3;
  result.runs.resize(run_count);
  for (int r = 0; r < run_count; ++r) {
    SpiralRun& run = result.runs[r];
    run.name = run_names[r];
    tell(progress, "run " + std::to_string(r + 1) + "/" + std::to_string(run_count) + ": " + run.name);
    // The controller interpolates with the planned velocities, or with the dynamic references' own.
    std::vector<JointVector> reference_velocity = result.planned.qd;
    const auto computing = std::chrono::steady_clock::now();
    if (r < 3) {
      run.compensation = compensateTrajectory(nominal, run_masks[r], result.planned.q, result.planned.qd, run.reference,
                                              spec.compensation);
    } else {
      run.dynamic_compensation =
          compensateDynamically(nominal, spec.drives, result.planned, run.reference, reference_velocity, spec.dynamic);
    }
    run.compensation_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - computing).count();
    if (!spec.compensated_joints.empty()) {
      for (std::size_t k = 0; k < run.reference.size(); ++k) {
        for (int j = 0; j < robot.dof(); ++j) {
          bool selected = false;
          for (int c : spec.compensated_joints) selected = selected || c == j;
          if (!selected) {
            run.reference[k][j] = result.planned.q[k][j];
            reference_velocity[k][j] = result.planned.qd[k][j];
          }
        }
      }
    }
    // Each run has its own tracker noise; the dynamic correction's is the static one's it is compared with.
    DeterministicRandom noise(spec.noise_seed * 1000003ULL + static_cast<std::uint64_t>(std::min(r, 2)));
    const std::size_t count = run.reference.size();
    run.actual.resize(count);
    run.measured.resize(count);
    run.error.resize(count);
    const auto started = std::chrono::steady_clock::now();
    if (result.dynamic) {
      plant->reset(run.reference[0], result.planned.time[0]);
      for (std::size_t k = 0; k < count; ++k) {
        plant->setReference(run.reference[k], reference_velocity[k]);
        run.actual[k] = plant->linkPositions();
        if (k + 1 < count) plant->advance(result.planned.time[k + 1]);
      }
    } else {
      JointContext ctx(robot.dof());
      for (std::size_t k = 0; k < count; ++k) {
        ctx.command = run.reference[k];
        ctx.velocity = result.planned.qd[k];
        ctx.time = result.planned.time[k];
        const FixedPointReport settled = settleStatically(truth, truth_mask, true_ws, ctx, spec.compensation);
        if (!settled.converged) {
          throw SolverError("the simulated robot did not settle at sample " + std::to_string(k));
        }
        run.actual[k] = ctx.q;
      }
    }
    result.simulation_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    for (std::size_t k = 0; k < count; ++k) {
      // The tool goes where the true robot's geometry puts it (the nominal one when the truth shares it).
      forwardKinematics(true_robot, true_ws.robot, run.actual[k]);
      const Eigen::Vector3d position = true_ws.robot.tool_pose.translation();
      const double sigma = spec.noise.sigma(position);
      // One draw per statement: the order of a constructor's arguments is unspecified (GCC evaluates them
      // last to first, clang first to last), so three draws in one call gave each compiler other noise.
      // z, y, x is the order of the GCC build the stored results come from.
      const double noise_z = noise.normal();
      const double noise_y = noise.normal();
      const double noise_x = noise.normal();
      const Eigen::Vector3d measured = position + sigma * Eigen::Vector3d(noise_x, noise_y, noise_z);
      run.measured[k] = measured;
      run.error[k] = measured - result.planned.tool_position[k];
    }
    run.metrics = accuracyMetrics(run.error);
  }
  if (plant) result.plant_statistics = plant->statistics();
  return result;
}

}  // namespace jointcomp
