#include "model/experiment/spiral_experiment.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

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

EffectMask spiralRunMask(const JointErrorModel& nominal, int run) {
  if (run < 0 || run > 2) throw InvalidArgument("run is " + std::to_string(run) + ", must be 0, 1 or 2");
  if (run == 0) return 0;
  EffectMask mask = nominal.loadsAnd({});
  if (nominal.jointSprings() >= 0) mask |= EffectMask(1) << nominal.jointSprings();
  if (run == 1) return mask;
  for (int i = 0; i < nominal.effectCount(); ++i) {
    const Effect& effect = nominal.effect(i);
    if (effect.role() == EffectRole::JointError && effect.dependsOnCommand()) mask |= EffectMask(1) << i;
  }
  return mask;
}

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

PreparedSpiral prepareSpiralRuns(const JointErrorModel& nominal, const SpiralExperimentSpec& spec,
                                 const std::function<void(const std::string&)>& progress) {
  const Robot& robot = nominal.robot();
  for (int joint : spec.compensated_joints) {
    if (joint < 0 || joint >= robot.dof()) {
      throw InvalidArgument("compensated joint " + std::to_string(joint + 1) + " does not exist: robot '" + robot.name +
                            "' has joints 1 to " + std::to_string(robot.dof()));
    }
  }
  if (spec.dynamic_correction && spec.drives.empty()) {
    throw InvalidArgument(
        "the dynamic correction needs the plant (drives in the parameter file), not the "
        "quasi-static robot");
  }
  PreparedSpiral prepared;
  tell(progress, "planning the spiral (feed rate, inverse kinematics)");
  prepared.planned = planSpiralTrajectory(robot, spec.spiral, spec.feed_rate, spec.seed_posture);
  const char* run_names[4] = {"without correction", "stiffness correction", "stiffness and kinematic correction",
                              "stiffness, kinematic and dynamic correction"};
  const int run_count = spec.dynamic_correction ? 4 : 3;
  if (spec.first_run < 0 || spec.first_run >= run_count) {
    throw InvalidArgument("first_run is " + std::to_string(spec.first_run) + ", must be from 0 to " +
                          std::to_string(run_count - 1));
  }
  prepared.runs.resize(run_count - spec.first_run);
  prepared.reference_velocity.assign(run_count - spec.first_run, prepared.planned.qd);
  for (int r = spec.first_run; r < run_count; ++r) {
    SpiralRun& run = prepared.runs[r - spec.first_run];
    run.index = r;
    run.name = run_names[r];
    tell(progress, "run " + std::to_string(r + 1) + "/" + std::to_string(run_count) + ": compensating " + run.name);
    // The controller interpolates with the planned velocities, or with the dynamic references' own.
    std::vector<JointVector>& reference_velocity = prepared.reference_velocity[r - spec.first_run];
    const auto computing = std::chrono::steady_clock::now();
    if (r < 3) {
      run.compensation = compensateTrajectory(nominal, spiralRunMask(nominal, r), prepared.planned.q,
                                              prepared.planned.qd, run.reference, spec.compensation);
    } else {
      run.dynamic_compensation = compensateDynamically(nominal, spec.drives, prepared.planned, run.reference,
                                                       reference_velocity, spec.dynamic);
    }
    run.compensation_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - computing).count();
    if (spec.compensated_joints.empty()) continue;
    for (std::size_t k = 0; k < run.reference.size(); ++k) {
      for (int j = 0; j < robot.dof(); ++j) {
        bool selected = false;
        for (int c : spec.compensated_joints) selected = selected || c == j;
        if (!selected) {
          run.reference[k][j] = prepared.planned.q[k][j];
          reference_velocity[k][j] = prepared.planned.qd[k][j];
        }
      }
    }
  }
  return prepared;
}

namespace {

// The quasi-static settling's start at sample k of a run: sample k's command plus the deflection (links minus
// command) extrapolated from up to five samples before it, by the polynomial through them (of degree 4 at
// most: sum over i of (-1)^(i+1) C(m, i) deflection[k - i]). Along the smooth path the quartic's guess is
// within the settling's tolerance at nearly every sample, so one evaluation of the joint errors settles a
// sample where the previous sample's deflection alone needed three; where the deflection jumps (a lost
// motion's reversal) the guess is worse and the iteration takes the steps it needs.
JointVector settlingStart(const std::vector<JointVector>& reference, const std::vector<JointVector>& actual,
                          std::size_t k) {
  static constexpr double kBinomial[6][6] = {{1},          {1, 1},          {1, 2, 1},
                                             {1, 3, 3, 1}, {1, 4, 6, 4, 1}, {1, 5, 10, 10, 5, 1}};
  const std::size_t points = std::min<std::size_t>(k, 5);
  JointVector q = reference[k];
  for (std::size_t i = 1; i <= points; ++i) {
    const double weight = (i % 2 == 1 ? 1.0 : -1.0) * kBinomial[points][i];
    q += weight * (actual[k - i] - reference[k - i]);
  }
  return q;
}

// Where the links of `truth` go under the references of the prepared run `r`: the plant's integration or the
// quasi-static settling, into `actual` (resized to the run's samples).
void simulateRun(const PreparedSpiral& prepared, int r, const JointErrorModel& truth, JointErrorWorkspace& true_ws,
                 FlexibleJointPlant* plant, const SpiralExperimentSpec& spec, std::vector<JointVector>& actual) {
  const JointTrajectory& planned = prepared.planned;
  const std::vector<JointVector>& reference = prepared.runs[r].reference;
  const std::vector<JointVector>& reference_velocity = prepared.reference_velocity[r];
  const std::size_t count = reference.size();
  actual.resize(count);
  if (plant) {
    plant->reset(reference[0], planned.time[0]);
    for (std::size_t k = 0; k < count; ++k) {
      plant->setReference(reference[k], reference_velocity[k]);
      actual[k] = plant->linkPositions();
      if (k + 1 < count) plant->advance(planned.time[k + 1]);
    }
    return;
  }
  const EffectMask truth_mask = truth.allEffects();
  JointContext ctx(truth.robot().dof());
  for (std::size_t k = 0; k < count; ++k) {
    ctx.q = settlingStart(reference, actual, k);
    ctx.command = reference[k];
    ctx.velocity = planned.qd[k];
    ctx.time = planned.time[k];
    const FixedPointReport settled = settleStatically(truth, truth_mask, true_ws, ctx, spec.compensation,
                                                      SettleStart::Given, SettleLoads::JointFrames);
    if (!settled.converged) throw SolverError("the simulated robot did not settle at sample " + std::to_string(k));
    actual[k] = ctx.q;
  }
}

// The tracker's measurement of run number `r` (0 to 3: its own noise stream) of the links `actual`: the
// error against the plan into `error`, the measured points into `measured` when not null; returns the metrics.
AccuracyMetrics measureRun(const JointTrajectory& planned, int r, const Robot& true_robot, JointErrorWorkspace& true_ws,
                           const SpiralExperimentSpec& spec, const std::vector<JointVector>& actual,
                           std::vector<Eigen::Vector3d>* measured, std::vector<Eigen::Vector3d>& error) {
  // Each run has its own tracker noise; the dynamic correction's is the static one's it is compared with.
  DeterministicRandom noise(spec.noise_seed * 1000003ULL + static_cast<std::uint64_t>(std::min(r, 2)));
  const std::size_t count = actual.size();
  if (measured) measured->resize(count);
  error.resize(count);
  for (std::size_t k = 0; k < count; ++k) {
    // The tool goes where the true robot's geometry puts it (the nominal one when the truth shares it).
    forwardKinematics(true_robot, true_ws.robot, actual[k]);
    const Eigen::Vector3d position = true_ws.robot.tool_pose.translation();
    const double sigma = spec.noise.sigma(position);
    // One draw per statement: the order of a constructor's arguments is unspecified (GCC evaluates them
    // last to first, clang first to last), so three draws in one call gave each compiler other noise.
    // z, y, x is the order of the GCC build the stored results come from.
    const double noise_z = noise.normal();
    const double noise_y = noise.normal();
    const double noise_x = noise.normal();
    const Eigen::Vector3d point = position + sigma * Eigen::Vector3d(noise_x, noise_y, noise_z);
    if (measured) (*measured)[k] = point;
    error[k] = point - planned.tool_position[k];
  }
  return accuracyMetrics(error);
}

// Where one run's draw goes: the links, the measured points (null: not kept), the errors and the metrics.
struct RunOutputs {
  std::vector<JointVector>* actual;
  std::vector<Eigen::Vector3d>* measured;
  std::vector<Eigen::Vector3d>* error;
  AccuracyMetrics* metrics;
};

// The prepared runs followed by `truth` into `outputs` (one per prepared run).
void followEachRun(const PreparedSpiral& prepared, const JointErrorModel& truth, const SpiralExperimentSpec& spec,
                   const std::function<void(const std::string&)>& progress, const std::vector<RunOutputs>& outputs,
                   double& simulation_seconds, PlantStatistics& plant_statistics) {
  const Robot& true_robot = truth.robot();
  const int dof = prepared.planned.q.empty() ? true_robot.dof() : static_cast<int>(prepared.planned.q[0].size());
  if (true_robot.dof() != dof) {
    throw InvalidArgument("the truth robot '" + true_robot.name + "' has " + std::to_string(true_robot.dof()) +
                          " joints, the planned spiral " + std::to_string(dof));
  }
  JointErrorWorkspace true_ws(true_robot);
  std::unique_ptr<FlexibleJointPlant> plant;
  if (!spec.drives.empty()) plant = std::make_unique<FlexibleJointPlant>(truth, spec.drives, spec.plant);
  simulation_seconds = 0.0;
  const int runs = static_cast<int>(prepared.runs.size());
  for (int r = 0; r < runs; ++r) {
    const RunOutputs& out = outputs[static_cast<std::size_t>(r)];
    tell(progress, "run " + std::to_string(r + 1) + "/" + std::to_string(runs) + ": " + prepared.runs[r].name);
    const auto started = std::chrono::steady_clock::now();
    simulateRun(prepared, r, truth, true_ws, plant.get(), spec, *out.actual);
    simulation_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    *out.metrics = measureRun(prepared.planned, prepared.runs[r].index, true_robot, true_ws, spec, *out.actual,
                              out.measured, *out.error);
  }
  plant_statistics = plant ? plant->statistics() : PlantStatistics{};
}

}  // namespace

SpiralExperimentResult followSpiralRuns(const PreparedSpiral& prepared, const JointErrorModel& truth,
                                        const SpiralExperimentSpec& spec,
                                        const std::function<void(const std::string&)>& progress) {
  SpiralExperimentResult result;
  result.planned = prepared.planned;
  result.dynamic = !spec.drives.empty();
  result.runs = prepared.runs;
  std::vector<RunOutputs> outputs;
  for (SpiralRun& run : result.runs) outputs.push_back({&run.actual, &run.measured, &run.error, &run.metrics});
  followEachRun(prepared, truth, spec, progress, outputs, result.simulation_seconds, result.plant_statistics);
  return result;
}

void drawSpiralRuns(const PreparedSpiral& prepared, const JointErrorModel& truth, const SpiralExperimentSpec& spec,
                    SpiralDraw& draw) {
  const std::size_t runs = prepared.runs.size();
  draw.actual.resize(runs);
  draw.error.resize(runs);
  draw.metrics.resize(runs);
  std::vector<RunOutputs> outputs;
  for (std::size_t r = 0; r < runs; ++r)
    outputs.push_back({&draw.actual[r], nullptr, &draw.error[r], &draw.metrics[r]});
  followEachRun(prepared, truth, spec, {}, outputs, draw.simulation_seconds, draw.plant_statistics);
}

SpiralExperimentResult runSpiralExperiment(const JointErrorModel& nominal, const JointErrorModel& truth,
                                           const SpiralExperimentSpec& spec,
                                           const std::function<void(const std::string&)>& progress) {
  if (truth.robot().dof() != nominal.robot().dof()) {
    throw InvalidArgument("the truth robot '" + truth.robot().name + "' has " + std::to_string(truth.robot().dof()) +
                          " joints, the nominal robot '" + nominal.robot().name + "' " +
                          std::to_string(nominal.robot().dof()));
  }
  return followSpiralRuns(prepareSpiralRuns(nominal, spec, progress), truth, spec, progress);
}

}  // namespace jointcomp
