// Where a residual lies, for a discovery that stops well above the noise floor: which joints carry it (the
// residual mapped to the joints), which orders of which angle repeat in it (a periodogram of each joint's
// residual against its output angle and its motor angle), and how it spreads over time (blocks of
// consecutive rows). It names where to look next; it fits nothing into the model.
#pragma once

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

struct UnexplainedResidual {
  bool above_floor = false;           // the fitted RMS is above kUnexplainedFactor times the noise floor
  bool floor_known = false;           // false: nothing to compare with, so what is left is reported anyway
  double over_floor = 0.0;            // fitted RMS / noise floor (0 when the floor is not known)
  std::vector<int> joints;            // joints by their share of the residual in position, largest first
  std::vector<double> joint_rms_rad;  // per joint (index = joint)
  std::vector<double> joint_rms_m;    // per joint: RMS of |dm/dq_j| dq_j, its share at the target
  std::vector<ResidualOrder> orders;  // per joint and angle the strongest order, those standing out first
  std::vector<double> block_rms;      // m, 3-D RMS of each block of consecutive rows, in time order
  std::string summary;                // one paragraph naming where it lies
};

struct ResidualRows {
  std::vector<std::vector<double>> joint_residual;  // per joint, per row (rad)
  std::vector<std::vector<double>> joint_lever;     // per joint, per row, |dm/dq_j| (m/rad)
  std::vector<JointVector> output_angle;            // per row (rad)
  std::vector<JointVector> motor_angle;             // per row (rad)
  std::vector<double> residual_norm;                // per row, |measured - predicted| (m)
  std::vector<int> block;                           // per row, its time block (0 .. blocks-1, non-decreasing)
};

UnexplainedResidual analyseUnexplained(const Robot& robot, const ResidualRows& rows, double fitted_rms,
                                       double noise_floor);

}  // namespace jointcomp
