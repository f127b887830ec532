// The paper's experiment (Olabi et al. 2012, Table II): the logarithmic spiral followed by a simulated
// robot whose true joint errors differ from the nominal model, in three runs (no correction, stiffness
// correction, stiffness and kinematic correction), scored on the tracker-measured Z deviation.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "model/compensation/compensator.hpp"
#include "model/compensation/feed_rate.hpp"
#include "model/compensation/joint_trajectory.hpp"
#include "model/compensation/metrics.hpp"
#include "model/compensation/path.hpp"
#include "model/dynamic_compensation/dynamic_compensation.hpp"
#include "model/effects/perturbation.hpp"
#include "model/io/instrument_noise.hpp"
#include "model/plant/flexible_joint_plant.hpp"

namespace jointcomp {

// The tracker of the paper's experiment: the one instrument model (model/io/instrument_noise.hpp) at a
// typical error of half the MPE (MPE about 2 sigma, so 1 sigma = MPE / 4), where simulated campaigns take
// the MPE at its word (MPE / 2).
inline TrackerNoiseModel spiralExperimentTracker() {
  TrackerNoiseModel tracker;
  tracker.constant_m = 3.75e-6;  // (15 um MPE) / 4
  tracker.per_metre = 1.5e-6;    // (6 um/m MPE) / 4
  return tracker;
}

struct SpiralExperimentSpec {
  SpiralSpec spiral = defaultSpiral();
  FeedRateSpec feed_rate;
  PerturbationSpec truth;
  TrackerNoiseModel noise = spiralExperimentTracker();
  std::uint64_t noise_seed = 7;
  JointVector seed_posture;             // IK seed; empty: a forward, elbow-up posture
  std::vector<int> compensated_joints;  // empty: all joints (the paper compensated joint 2 only)
  FixedPointOptions compensation;
  // The simulated robot: the flexible-joint plant (drives not empty) or, with no drives, the
  // quasi-static robot (kinematics, elastostatics and transmission error only).
  std::vector<DriveParameters> drives;
  PlantOptions plant;
  // A fourth run, "stiffness, kinematic and dynamic correction" (the plant only): the references of
  // compensateDynamically (model/dynamic_compensation/dynamic_compensation.hpp) for the nominal model and drives.
  bool dynamic_correction = false;
  DynamicCompensationOptions dynamic;
  // The first run made (0 to 3): the later runs of another model need no uncorrected run of their own
  // (it does not depend on the model), a perfect model's floor only the corrected runs.
  int first_run = 0;

  // The paper's spiral: a = 24 mm, b = 0.15, theta 0 to 4 pi, in the plane Z = 200 mm, centred at
  // X = 1.2 m in front of the robot where the arm reaches out and joint 2 carries most of the error.
  static SpiralSpec defaultSpiral();
};

struct SpiralRun {
  int index = 0;                          // 0 to 3, in the order below (spec.first_run may skip some)
  std::string name;                       // "without correction", ...
  std::vector<JointVector> reference;     // commanded joints
  std::vector<JointVector> actual;        // where the simulated links went
  std::vector<Eigen::Vector3d> measured;  // tool position measured by the tracker (with noise)
  std::vector<Eigen::Vector3d> error;     // measured - planned
  AccuracyMetrics metrics;
  TrajectoryCompensationReport compensation;
  DynamicCompensationReport dynamic_compensation;  // the fourth run's
  double compensation_seconds = 0.0;               // CPU time computing the references
};

struct SpiralExperimentResult {
  JointTrajectory planned;
  bool dynamic = false;              // the plant (true) or the quasi-static robot
  PlantStatistics plant_statistics;  // summed over the runs
  double simulation_seconds = 0.0;   // wall-clock time spent simulating the robot
  std::vector<SpiralRun> runs;       // the paper's three, and the dynamic correction's when asked for, from
                                     // spec.first_run on
};

// The spiral as a joint trajectory: feed-rate planned, tool pointing down, inverse kinematics from
// `seed_posture` (empty: forward and elbow-up, joints 2, 3 and 5 at 60 deg when the robot has them).
// Throws UnreachableError naming the sample when a point is out of reach.
JointTrajectory planSpiralTrajectory(const Robot& robot, const SpiralSpec& spiral, const FeedRateSpec& feed_rate,
                                     JointVector seed_posture = {});

// The effects run `run` (0 to 2) of the paper's spiral compensates: none; the loads and the joint springs
// (stiffness); those and the gears' errors that follow the command (kinematic: transmission errors, periodic
// tables), each effect found by its role. InvalidArgument for another run.
EffectMask spiralRunMask(const JointErrorModel& nominal, int run);

// What every follower of one nominal model shares: the planned spiral and each run's references (the
// compensation uses the nominal model only), computed once for many truths (Monte Carlo draws).
struct PreparedSpiral {
  JointTrajectory planned;
  std::vector<SpiralRun> runs;                               // name, reference, compensation and its time
  std::vector<std::vector<JointVector>> reference_velocity;  // what the controller interpolates with, per run
};

// Plans the spiral with nominal.robot() and compensates each run with `nominal` (spec.drives for the
// fourth run's dynamic correction). Throws InvalidArgument for a compensated joint that does not exist.
PreparedSpiral prepareSpiralRuns(const JointErrorModel& nominal, const SpiralExperimentSpec& spec,
                                 const std::function<void(const std::string&)>& progress = {});

// The prepared runs followed by `truth` (same number of joints as the prepared plan), measured with the
// tracker noise of spec.noise_seed; runSpiralExperiment is prepareSpiralRuns then this.
SpiralExperimentResult followSpiralRuns(const PreparedSpiral& prepared, const JointErrorModel& truth,
                                        const SpiralExperimentSpec& spec,
                                        const std::function<void(const std::string&)>& progress = {});

// One truth's draw of the prepared runs without the plan and the references (the PreparedSpiral has them):
// per run where the links went, the measured-minus-planned errors and their metrics. A Monte Carlo keeps one
// per thread from draw to draw, so that a draw reuses these vectors instead of allocating the path again.
struct SpiralDraw {
  std::vector<std::vector<JointVector>> actual;     // per prepared run
  std::vector<std::vector<Eigen::Vector3d>> error;  // per prepared run: measured - planned (m)
  std::vector<AccuracyMetrics> metrics;             // per prepared run
  PlantStatistics plant_statistics;                 // summed over the runs
  double simulation_seconds = 0.0;                  // wall-clock time spent simulating the robot
};

// followSpiralRuns into `draw` (the same bits): its vectors are resized, and keep their memory when they fit.
void drawSpiralRuns(const PreparedSpiral& prepared, const JointErrorModel& truth, const SpiralExperimentSpec& spec,
                    SpiralDraw& draw);

// `progress` (may be empty) is told what is being done, for tools that show it.
SpiralExperimentResult runSpiralExperiment(const JointErrorModel& nominal, const SpiralExperimentSpec& spec,
                                           const std::function<void(const std::string&)>& progress = {});

// The same with the simulated robot's truth given (spec.truth is not used): the compensation uses
// `nominal`, the robot follows `truth` (its joint errors, and its geometry when measured), as Monte Carlo
// runs over a parameter distribution need. Both must have the same number of joints.
SpiralExperimentResult runSpiralExperiment(const JointErrorModel& nominal, const JointErrorModel& truth,
                                           const SpiralExperimentSpec& spec,
                                           const std::function<void(const std::string&)>& progress = {});

}  // namespace jointcomp
