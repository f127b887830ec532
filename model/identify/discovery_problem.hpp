// Discovery's pieces below the run itself (model/identify/discovery*.cpp only): the candidates the registry's
// families offer, the linearised problem at a calibration with the accepted effects as base columns, each
// candidate's columns as a piece, and the evaluation of candidates (alone and in pairs) with the transfer
// statistics that decide whether a fit predicts the data it was not fitted on.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "model/identify/discovery.hpp"
#include "model/identify/linearised_fit.hpp"

namespace jointcomp::discovery_detail {

// An accepted candidate: its index among the offered ones, its coefficients and their sigmas, and the
// weights of its priors that cross-validation chose (0: none).
struct Active {
  int candidate = 0;
  Eigen::VectorXd theta;
  Eigen::VectorXd sigma;
  double roughness_weight = 0.0;
  double ridge_weight = 0.0;
};

// Every candidate the wanted families offer, with its family and the calibration parameters it frees
// (indices of GeometricParameterLayout).
struct Features {
  std::vector<DiscoveryCandidate> candidates;
  std::vector<SparseFeatures> sparse;  // per candidate, its feature columns by row (empty: none)
  std::vector<const DiscoveryFamily*> family;
  std::vector<std::vector<int>> releases;
};

// A candidate's columns as a piece of a fit: the calibration parameters it frees that are not free yet
// (dense), its load or multi-joint blocks (dense), or its feature columns of its joint.
struct CandidatePiece {
  ColumnPiece piece;
  std::vector<int> coefficients;  // the candidate's own coefficients' columns within the piece
};
struct Linearised {
  LinearisedProblem problem;
  Eigen::MatrixXd layout_jacobian;     // 3 rows x calibration parameters, weighted
  std::vector<CandidatePiece> active;  // each accepted candidate's columns (a refit's pieces)
  // With map_joints: the residual mapped to the joints (pinv of dm/dq), per joint, per row (rad), and per row
  // |measured - predicted| (m), the residual itself, and per joint |dm/dq_j| (m/rad).
  std::vector<std::vector<double>> joint_residual;
  std::vector<double> residual_norm;
  std::vector<Eigen::Vector3d> residual;
  std::vector<std::vector<double>> joint_lever;
  std::vector<std::vector<double>> joint_share;  // per joint, per row: its share of |residual|^2 (m^2)
  std::vector<int> time_block;                   // per row
};

// How the rows are cut for cross-validation and the transfer check.
struct Cuts {
  int folds = 5;
  int sub_blocks = 6;
  double min_share = 0.05;
  int angle_ranges = 5;
};

Linearised linearise(const JointErrorModel& model, const CalibrationData& data, const GeometricCalibrationResult& cal,
                     const Features& features, const std::vector<Active>& active, const Cuts& cuts, bool map_joints);

CandidatePiece candidatePiece(const Linearised& lin, const Features& features, int candidate,
                              const GeometricCalibrationResult& cal);

// The accepted candidates' priors in a refit system (base, then lin.active's pieces in order).
Penalty activePenalty(const Linearised& lin, const FitSystem& system, const Features& features,
                      const std::vector<Active>& active);
// Adds a prior, weight times `prior` (SI, over `columns` of the system) normalised so that weight 1 weighs
// like the data of one column; `theta` the coefficients those columns already hold (empty: none).
void addPrior(const FitSystem& system, const std::vector<int>& columns, const Eigen::MatrixXd& prior, double weight,
              const Eigen::VectorXd& theta, Penalty& penalty);

}  // namespace jointcomp::discovery_detail

namespace jointcomp::discovery_detail {

// A candidate (or a pair of them) fitted with the base columns: its best weights of priors, its fit, and
// what decided.
struct Evaluation {
  std::vector<int> candidates;                         // indices into Features::candidates
  std::vector<double> roughness_weight, ridge_weight;  // per member
  Fit fit;
  double delta_bic = 0.0;
  double added = 0.0;                        // effective parameters added
  bool gains = false;                        // lowers the CV error by min_cv_gain and the BIC
  std::string hurt;                          // empty: transfers; else the group it makes significantly worse
  std::string unphysical;                    // empty: every member's fit is physical (DiscoveryFamily::physicalProblem)
  double transfer_error = 0.0;               // CV error of the time blocks and the joint-space parts together
  std::vector<Eigen::VectorXd> member_step;  // per member, its coefficients (SI)
  bool passes() const { return gains && hurt.empty() && unphysical.empty(); }
};

struct Selection {
  const Linearised& lin;
  const DiscoveryData& data;
  const Features& features;
  const std::vector<bool>& offered;
  const GeometricCalibrationResult& cal;
  const Fit& base;  // the base columns (the calibration's free parameters) fitted on every grouping
  const DiscoveryOptions& options;
  const Cuts& cuts;
};

struct Choice {
  bool found = false;
  Evaluation chosen;
  int tried = 0;
  std::string runner_up;
  std::string rejected;  // the best candidate that gained overall but did not transfer, and why
};

// The base columns alone, on every grouping but the last (the refits' whole time blocks).
FitSystem baseSystem(const LinearisedProblem& problem);
// Every offered candidate alone, then pairs of the best of each family on two joints; the one to accept.
Choice chooseCandidate(const Selection& selection);

}  // namespace jointcomp::discovery_detail
