// Discovery's linearised least-squares problem in Gram form. At a calibration, every row i of the fitted
// data has a residual r_i (3 values, weighted) and moves with the columns of the model's free parameters
// (the base: calibration parameters and accepted effects, held densely) and with the columns of each
// candidate effect. A candidate's feature column k of joint j moves row i by v_ik a_ij, a_ij the row's
// weighted dm/dq_j, so its sums are built row by row from the nonzero v_ik alone: a 128-knot table costs
// four products a row, and no candidate's columns are ever stored 3 x rows x columns at once.
//
// Every sum is kept per block of rows in each grouping (RowGrouping: time blocks, parts of the joint space,
// ranges of one joint's angle; each group cut into sub-blocks of consecutive rows), so that one fit gives
// every leave-one-group-out prediction and the spread of each group's change over its sub-blocks.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Dense>

#include "model/common/types.hpp"

namespace jointcomp {

// A cut of the rows into groups for cross-validation, each group into sub-blocks.
struct RowGrouping {
  std::string kind;               // "time block", "joint-space part", "joint 2 angle range"
  int joint = -1;                 // the joint of an angle-range grouping, else -1
  std::vector<int> block_of_row;  // per row
  std::vector<int> group_of_block;
  std::vector<int> rows_of_group;
  int groups() const { return static_cast<int>(rows_of_group.size()); }
  int blocks() const { return static_cast<int>(group_of_block.size()); }
};

// Groups whose rows are consecutive (`group_of_row` nondecreasing or any order), each cut into at most
// `sub_blocks` sub-blocks of consecutive rows (in row order within the group).
RowGrouping makeGrouping(std::string kind, const std::vector<int>& group_of_row, int groups, int sub_blocks);
// `folds` time blocks of consecutive rows.
RowGrouping timeBlocks(int rows, int folds, int sub_blocks);
// `parts` clusters of the joint vector (k-means seeded by farthest points from the first row); a cluster
// with fewer than `min_share` of the rows joins the nearest large one, so every part is large enough to
// measure.
RowGrouping jointSpaceParts(const std::vector<JointVector>& command, int parts, double min_share, int sub_blocks);
// `ranges` ranges of joint `joint`'s angle holding equal numbers of rows (leave-one-angle-range-out).
RowGrouping angleRanges(const std::vector<JointVector>& command, int joint, int ranges, int sub_blocks);

// Sums over the rows of each block: cross products of two sets of columns, their products with the
// residual, and the residual's square.
struct BlockSums {
  std::vector<Eigen::MatrixXd> gram;  // per block, columns of the first set x columns of the second
  std::vector<Eigen::VectorXd> xr;    // per block, first set's columns . r (only for a set with itself)
  std::vector<double> rr;             // per block, r . r
};

// Feature columns stored by row, nonzero values only (a table's row has four).
struct SparseFeatures {
  int columns = 0;
  std::vector<int> start;  // row i's entries: [start[i], start[i + 1])
  std::vector<int> column;
  std::vector<double> value;
};
SparseFeatures sparseFeatures(const Eigen::MatrixXd& features);

// Columns of a candidate: dense ones (3 per row) and feature columns of one joint (one value per row).
struct ColumnPiece {
  Eigen::MatrixXd dense;                     // 3 rows x dense columns, weighted
  const SparseFeatures* features = nullptr;  // joint error per unit coefficient
  int joint = -1;                            // joint of the feature columns
  int denseColumns() const { return static_cast<int>(dense.cols()); }
  int featureColumns() const { return features ? features->columns : 0; }
  int columns() const { return denseColumns() + featureColumns(); }
};

// The problem at one calibration: r, the base columns (dense) and each row's weighted joint columns.
struct LinearisedProblem {
  int rows = 0, dof = 0;
  Eigen::VectorXd r;                        // 3 rows
  Eigen::MatrixXd base;                     // 3 rows x base columns (calibration parameters, then accepted effects)
  Eigen::MatrixXd joint_column;             // 3 rows x dof: a_ij = w_i dm_i/dq_j
  std::vector<Eigen::MatrixXd> base_joint;  // per joint, base columns x rows: column i = base_i^T a_ij
  // 0: time blocks, 1: joint-space parts, 2 + j: joint j's angle ranges, last: time blocks whole (refits)
  std::vector<RowGrouping> groupings;
  std::vector<BlockSums> base_sums;  // per grouping: base x base, base . r, r . r
  int angleGrouping(int joint) const { return 2 + joint; }
  int refitGrouping() const { return static_cast<int>(groupings.size()) - 1; }
};

// Fills base_sums for every grouping and base_joint (call once the base columns and groupings are set).
void accumulateBase(LinearisedProblem& problem);
// Per block of `grouping`, the base columns x the piece's columns (xr, rr left empty).
BlockSums crossWithBase(const LinearisedProblem& problem, const ColumnPiece& piece, int grouping);
// Per block of `grouping`, piece a x piece b (with xr = a . r and rr when `with_residual`).
BlockSums crossPieces(const LinearisedProblem& problem, const ColumnPiece& a, const ColumnPiece& b, int grouping,
                      bool with_residual);

}  // namespace jointcomp
