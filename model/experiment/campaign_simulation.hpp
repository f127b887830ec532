// Simulated measurement campaigns: a "true" robot (a joint-error model that may hold effects the nominal
// model lacks) is commanded through a protocol and measured by simulated instruments with stated noise
// (instrument_noise.hpp), giving a MeasurementCampaign exactly as a real campaign file would.
//
// The robot is the quasi-static one (settleStatically with every effect of the truth, applied wrench and
// payload included), or, for sweeps and the spiral when drives are given, the flexible-joint plant:
// each step is a short ramp followed by a settling time, and the links are measured at its end.
//
// Protocols:
// - stiffness: the paper's axis-by-axis tests. For each tested joint, at one pose, a ladder of loads up
//   and down. The load of a tracker-measured joint is a wrench at the target chosen (from the truth's
//   Jacobian at the commanded pose, J^T w = tau e_j) to load that joint alone, as the axis-by-axis test
//   intends; the level-measured joint (joint 3 by default) gets a vertical force (weights), which loads
//   joints 2 and 3 together, and two electronic levels on the links before and after it give its
//   deflection: qm_j = q_j + (level after - level before). Then a global part: several well-conditioned
//   random poses, each unloaded and under +-force along x, y, z and +-moment about x, y, z. Load sizes:
//   each joint deflects at most max_deflection by the truth's stiffness and carries at most
//   effort_fraction of its URDF effort limit.
// - joint sweep: one joint from `from` to `to` in steps, settling at each (the paper's joint-2 sweep:
//   -50 to +50 deg in 0.05 deg steps, 1 s settling); back-and-forth: the same up and down, `cycles` times.
// - spiral: the paper's logarithmic spiral, planned as in spiral_experiment.hpp, sampled at the tracker
//   rate while the robot moves.
// - random: poses drawn uniformly within the joint limits (shrunk by a margin), away from singularities
//   and with the target above a floor height.
// Every random draw comes from DeterministicRandom(seed): the same inputs give the same file, bit for bit.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "model/compensation/feed_rate.hpp"
#include "model/compensation/path.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/io/instrument_noise.hpp"
#include "model/io/measurement_campaign.hpp"
#include "model/plant/flexible_joint_plant.hpp"

namespace jointcomp {

// The most rows a simulated campaign has, whoever asks (the CLI, the C API's JSON): a joint sweep's
// commands over all its cycles, and random poses. Beyond them a simulation is refused with the number,
// before it allocates anything (a million rows is about 150 MB of campaign file).
constexpr long kMaxSweepRows = 1000000;
constexpr int kMaxRandomPoses = 100000;

enum class CampaignProtocol { Stiffness, JointSweep, Spiral, RandomPoses, BackAndForth };

// "stiffness", "joint-sweep", "spiral", "random", "back-and-forth" (and "joint2-sweep" for the paper's
// joint-2 sweep). Throws InvalidArgument listing the names for an unknown one.
CampaignProtocol protocolFromName(const std::string& name);
std::string protocolName(CampaignProtocol protocol);

struct StiffnessProtocolSpec {
  JointVector pose;                  // empty: defaultStiffnessPose(robot)
  std::vector<int> joints;           // tested joints (0-based); empty: all
  int level_joint = 2;               // joint measured by two levels under a vertical force; -1: none
  int load_levels = 9;               // loads from -max to +max, visited up then down
  double max_deflection_rad = 2e-3;  // per joint, by the truth's stiffness
  double effort_fraction = 0.5;      // of the URDF effort limit (when it gives one)
  int global_poses = 8;              // poses of the global part (0: none)
  double global_force_n = 300.0;     // before scaling down to the deflection and effort limits
  double global_moment_nm = 30.0;
  double global_limit_margin_rad = 0.3;
  double min_conditioning = 0.05;  // sigma_min / sigma_max of the scaled Jacobian of a global pose
  double row_period_s = 5.0;       // time between rows (load change and settling)
};

struct JointSweepSpec {
  int joint = 1;  // 0-based: joint 2
  double from_rad = -50.0 * 3.14159265358979323846 / 180.0;
  double to_rad = 50.0 * 3.14159265358979323846 / 180.0;
  double step_rad = 0.05 * 3.14159265358979323846 / 180.0;
  JointVector pose;       // the other joints; empty: defaultStiffnessPose(robot)
  double settle_s = 1.0;  // settling time at each step
  double move_speed_rad_s = 1.0 * 3.14159265358979323846 / 180.0;  // ramp speed between steps
  int cycles = 1;                                                  // back-and-forth: up-and-down cycles
};

struct RandomPosesSpec {
  int count = 200;
  double limit_margin_rad = 0.1;
  double min_target_height_m = 0.1;  // base frame z of the target
  double min_conditioning = 0.02;
  double row_period_s = 5.0;
};

struct SpiralCampaignSpec {
  SpiralSpec spiral;  // default: the paper's, at X = 1.2 m, Z = 0.2 m (as the spiral experiment)
  FeedRateSpec feed_rate;
  JointVector seed_posture;       // IK seed; empty: forward, elbow-up
  double sample_period_s = 0.02;  // tracker rate: 50 Hz
  SpiralCampaignSpec();
};

// The robot's temperature during the campaign: a warm-up from start towards start + rise,
//   T(t) = start + rise (1 - exp(-t / time_constant)),
// written into the temperature column and seen by the truth's effects (with the row's time). Off by
// default: no temperature column, and the effects see JointContext's 20 degC.
struct TemperatureProfile {
  bool enabled = false;
  double start_degc = 20.0;
  double rise_degc = 10.0;
  double time_constant_s = 1800.0;
  double at(double t) const;
};

struct CampaignSimulationSpec {
  CampaignProtocol protocol = CampaignProtocol::Stiffness;
  std::uint64_t seed = 1;
  bool noise = true;  // false: exact measurements (tests)
  TrackerNoiseModel tracker;
  LevelNoiseModel level;
  Eigen::Vector3d target_in_flange{0.1, 0.0, 0.15};  // m: a reflector off the flange axis, so that
                                                     // the wrist joints move it
  StiffnessProtocolSpec stiffness;
  JointSweepSpec sweep;
  RandomPosesSpec random;
  SpiralCampaignSpec spiral;
  TemperatureProfile temperature;  // quasi-static protocols only (the plant runs at 20 degC)
  // Non-empty: sweeps and the spiral run on the flexible-joint plant. Other protocols stay quasi-static.
  std::vector<DriveParameters> drives;
  PlantOptions plant;
  std::map<std::string, std::string> metadata;  // extra metadata lines (truth file, ...)
};

// The defaults of a protocol: those of the structs above, except back-and-forth, which sweeps -20..+20 deg
// in 0.5 deg steps twice (a hysteresis loop does not need the full range, and two cycles show it repeats).
CampaignSimulationSpec defaultCampaignSpec(CampaignProtocol protocol);

// A non-singular pose in front of the robot: joints 2, 3, 5 at 40, 50, 50 deg (clamped into the limits),
// the rest at 0 (or at mid-range when 0 is outside the limits).
JointVector defaultStiffnessPose(const Robot& robot);

// Throws InvalidArgument naming the field at fault, SolverError when the quasi-static robot does not
// settle, UnreachableError when the spiral is out of reach. `progress` may be empty.
MeasurementCampaign simulateCampaign(const JointErrorModel& truth, const CampaignSimulationSpec& spec,
                                     const std::function<void(const std::string&)>& progress = {});

}  // namespace jointcomp
