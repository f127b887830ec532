// Where a residual lies, for a discovery that stops well above the noise floor: which joints carry it (the
// residual mapped to the joints), which orders of which angle repeat in it (a periodogram of each joint's
// residual against its output angle and its motor angle), and how it spreads over time (blocks of
// consecutive rows), and how much of it is a function of the pose at all (its nearest poses measured at other
// times predict it or not). It names where to look next; it fits nothing into the model.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "model/common/periodogram.hpp"
#include "model/common/types.hpp"
#include "model/robot/robot.hpp"

namespace jointcomp {

// One order of a periodic component of a joint's residual.
struct ResidualOrder {
  int joint = 0;
  std::string angle;           // "output" (the joint's angle) or "motor" (its motor angle)
  int order = 0;               // cycles per revolution of that angle
  double amplitude_rad = 0.0;  // of a cos + b sin, fitted alone with a constant
  bool stands_out = false;     // above kOrderStandsOut times the median amplitude of the scanned orders
};

constexpr int kMaxScannedOutputOrder = 24;
constexpr int kMaxScannedMotorOrder = 8;
constexpr double kUnexplainedFactor = 1.5;  // a fitted RMS above this many noise floors is reported

// How much of a residual is a function of the pose that holds from one visit to the next, at the campaign's
// own sampling: each row's residual is predicted by the mean of its k nearest rows in joint space (plain
// radians), once among the rows measured at least min_gap_s before or after it, once among all rows. Noise
// independent between rows leaves sqrt(1 + 1/k) times its RMS; a smooth function of the pose plus such noise
// leaves only the noise's part. So smooth_share = 1 - left^2 / ((1 + 1/k) rms^2) is a lower bound of the share
// of the residual's variance that a model of the pose could take: lower when the function varies faster than
// the campaign samples the pose. Rows close in time and in pose that agree while rows far in time do not point
// to something that changes between visits (drift, set-up), not to a missing joint effect.
struct PosePredictability {
  bool computed = false;  // false: too few rows, or no row has k neighbours measured min_gap_s away
  int neighbours = 0;
  double min_gap_s = 0.0;
  int scored_rows = 0;                       // rows predicted (every row up to max_scored_rows, else a stride)
  double residual_rms = 0.0;                 // m, 3-D RMS of the scored rows
  double left_other_times_rms = 0.0;         // m, left after the mean of the nearest rows min_gap_s away in time
  double left_any_time_rms = 0.0;            // m, left after the mean of the nearest rows at any time
  double median_distance_other_times = 0.0;  // rad, median mean distance to those neighbours in joint space
  double median_distance_any_time = 0.0;     // rad
  double smooth_share = 0.0;                 // in [0, 1], from left_other_times_rms (see above)
};

constexpr int kPoseNeighbours = 3;
constexpr double kPoseMinGapSeconds = 600.0;
constexpr int kPoseMaxScoredRows = 4000;
constexpr std::size_t kPoseMaxCandidateRows = 50000;  // neighbours are looked for among at most this many rows
// Beyond this median distance (rad) to the neighbours, the summary says the poses are too sparse to tell.
constexpr double kPoseSparseDistance = 0.3;

// Throws InvalidArgument when the three vectors differ in size or a row has a non-finite value (naming it).
PosePredictability posePredictability(const std::vector<JointVector>& q, const std::vector<Eigen::Vector3d>& residual,
                                      const std::vector<double>& time, int neighbours = kPoseNeighbours,
                                      double min_gap_s = kPoseMinGapSeconds, int max_scored_rows = kPoseMaxScoredRows);

// One or two sentences for reports: "As a function of the pose: the mean of the 3 nearest poses measured ...".
std::string describePosePredictability(const PosePredictability& p);

struct UnexplainedResidual {
  bool above_floor = false;           // the fitted RMS is above kUnexplainedFactor times the noise floor
  bool floor_known = false;           // false: nothing to compare with, so what is left is reported anyway
  double over_floor = 0.0;            // fitted RMS / noise floor (0 when the floor is not known)
  std::vector<int> joints;            // joints by their share of the residual in position, largest first
  std::vector<double> joint_rms_rad;  // per joint (index = joint)
  // per joint, its share of the residual at the target (m, RMS): the shares' squares add up to the residual's
  std::vector<double> joint_rms_m;
  std::vector<ResidualOrder> orders;  // per joint and angle the strongest order, those standing out first
  std::vector<double> block_rms;      // m, 3-D RMS of each block of consecutive rows, in time order
  PosePredictability pose;            // how much of it is a function of the pose (computed when rows have times)
  std::string summary;                // one paragraph naming where it lies
};

struct ResidualRows {
  std::vector<std::vector<double>> joint_residual;  // per joint, per row (rad)
  std::vector<std::vector<double>> joint_lever;     // per joint, per row, |dm/dq_j| (m/rad)
  // per joint, per row, its share of |residual|^2 (m^2): |dm/dq_j dq_j|^2 scaled so a row's shares add up to
  // its |residual|^2 (the mapped joint errors may cancel at the target); empty: |dm/dq_j| dq_j is used
  std::vector<std::vector<double>> joint_share;
  std::vector<JointVector> output_angle;  // per row (rad)
  std::vector<JointVector> motor_angle;   // per row (rad)
  std::vector<double> residual_norm;      // per row, |measured - predicted| (m)
  std::vector<int> block;                 // per row, its time block (0 .. blocks-1, non-decreasing)
  std::vector<Eigen::Vector3d> residual;  // per row, measured - predicted (m); empty: pose not analysed
  std::vector<double> time;               // per row (s), as residual
};

UnexplainedResidual analyseUnexplained(const Robot& robot, const ResidualRows& rows, double fitted_rms,
                                       double noise_floor);

}  // namespace jointcomp
