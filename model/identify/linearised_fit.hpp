// One fit of discovery's linearised problem (linearised_problem.hpp): the base columns and some candidates'
// pieces, their normal equations per block of each grouping (scaled to unit column norm), the solution on
// all rows, and every leave-one-group-out prediction with its error per group and per block.
#pragma once

#include <vector>

#include <Eigen/Dense>

#include "model/identify/linearised_problem.hpp"

namespace jointcomp {

struct FitSystem {
  std::vector<int> groupings;                      // the problem's groupings; the first is the time blocks
  std::vector<std::vector<Eigen::MatrixXd>> gram;  // [grouping][block], columns x columns, scaled
  std::vector<std::vector<Eigen::VectorXd>> xr;    // [grouping][block]
  std::vector<std::vector<double>> rr;             // [grouping][block]
  std::vector<std::vector<int>> group_of_block;    // [grouping][block]; a group's blocks are consecutive
  Eigen::MatrixXd total_gram;
  Eigen::VectorXd total_xr;
  double total_rr = 0.0;
  Eigen::VectorXd scale;         // column norms (unscaled column = scaled column * scale)
  std::vector<int> piece_first;  // first column of each piece; the base's columns come first
  int columns() const { return static_cast<int>(scale.size()); }
};

// The base columns followed by each piece's, on the given groupings (the time blocks first).
FitSystem assembleSystem(const LinearisedProblem& problem, const std::vector<const ColumnPiece*>& pieces,
                         const std::vector<int>& groupings);

// A quadratic prior in the system's scaled units: the fit minimises |r + X d|^2 + (t + d)^T P (t + d), with
// t the coefficients the penalised columns already hold; held = P t.
struct Penalty {
  Eigen::MatrixXd matrix;  // columns x columns; empty: none
  Eigen::VectorXd held;
  bool empty() const { return matrix.size() == 0; }
};

struct GroupingErrors {
  std::vector<double> group;  // each group's error predicted from the other groups (sum of squares)
  std::vector<double> block;  // the same per sub-block
};

struct Fit {
  double rss = 0.0;                    // on all rows after the step
  double cv = 0.0;                     // leave-one-time-block-out sum of squares
  std::vector<double> cv_fold;         // per time block
  int rank = 0;                        // of the normal equations (with the prior: all columns)
  double dof = 0.0;                    // effective parameters: the rank, or trace of the hat matrix with a prior
  Eigen::VectorXd d;                   // step in scaled columns, minimises |r + X d|^2 (+ prior)
  Eigen::MatrixXd inverse;             // (G + P)^+ when asked for
  std::vector<GroupingErrors> errors;  // per grouping of the system
};

Fit solveSystem(const FitSystem& system, const Penalty& penalty, bool need_inverse);

}  // namespace jointcomp
