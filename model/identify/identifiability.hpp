// Which parameters a set of measurements can identify: the rank of the identification Jacobian.
//
// The columns of J are scaled to unit norm (so that units do not matter) and put through a QR
// decomposition with column pivoting whose pivots are each chosen column's norm left after removing its
// projection on the columns chosen before it. The pivot choice follows a priority first (so that, of two
// redundant parameters, the one of the higher priority class is kept: the instrument frame before the
// robot's joint offsets, say) and the largest remaining norm within a class (the earlier column on a tie,
// as between exactly redundant columns). A column whose pivot falls
// below the relative threshold is redundant with the columns kept: it is fixed at its nominal value. A
// column whose parameter, changed by its typical amount, moves no measurement by more than
// `no_effect_tolerance` is reported as without effect.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace jointcomp {

struct IdentifiabilityOptions {
  // A column is kept when the part of it (unit norm) that the columns kept before it cannot explain has a
  // norm above this. 1e-4: a kept parameter's standard deviation is at most 1e4 times what it would be
  // were it uncorrelated with the others.
  double relative_pivot_threshold = 1e-4;
  // A parameter changed by its typical amount that moves the residuals by less than this (RMS, in the
  // units of the residuals) has no effect on the measurements.
  double no_effect_tolerance = 1e-9;
};

struct Redundancy {
  int column = 0;      // a kept column
  double ratio = 0.0;  // a unit change of the fixed parameter does what `ratio` units of this one do
};

struct IdentifiabilityResult {
  std::vector<int> kept;                                // column indices, ascending
  std::vector<int> fixed;                               // column indices, ascending
  std::vector<int> pivot_order;                         // kept columns in the order the QR chose them
  Eigen::VectorXd pivot;                                // per column: relative pivot (1 = independent, 0 = no effect)
  Eigen::VectorXd column_norm;                          // per column: |J_j|
  std::vector<bool> no_effect;                          // per column
  std::vector<std::vector<Redundancy>> redundant_with;  // per column; filled for fixed columns with effect
  double condition_number = 1.0;                        // of the kept columns scaled to unit norm
};

// `priority`: per column, lower values are kept first (empty: all equal). `typical_change`: per column, a
// typical size of the parameter's change (for the no-effect test; empty: 1). Throws InvalidArgument for
// sizes that disagree or a Jacobian that is not finite.
IdentifiabilityResult analyseIdentifiability(const Eigen::MatrixXd& jacobian, const std::vector<int>& priority = {},
                                             const std::vector<double>& typical_change = {},
                                             const IdentifiabilityOptions& options = {});

// Condition number (largest over smallest singular value) of the given columns of J, each scaled to unit
// norm; infinity when they are rank deficient.
double scaledConditionNumber(const Eigen::MatrixXd& jacobian, const std::vector<int>& columns);

}  // namespace jointcomp
