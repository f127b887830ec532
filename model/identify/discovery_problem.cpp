#include "model/identify/discovery_problem.hpp"

#include <algorithm>
#include <cmath>

#include "model/common/errors.hpp"

namespace jointcomp::discovery_detail {
namespace {

// Row i's weighted 3-vector of a multi-joint block column (load torques through the compliances, or the
// joint errors of every joint) per unit of coefficient `k`.
Eigen::Vector3d blockColumn(const Linearised& lin, const DiscoveryCandidate& candidate,
                            const GeometricCalibrationResult& cal, int i, int k) {
  const int n = lin.problem.dof;
  Eigen::Vector3d column = Eigen::Vector3d::Zero();
  for (int j = 0; j < n; ++j) {
    const double value = candidate.columns(i, k * n + j);
    if (value == 0.0) continue;
    const double per_joint = candidate.through_compliance ? -cal.estimate.compliance[j] * value : value;
    column += per_joint * lin.problem.joint_column.block<3, 1>(3 * i, j);
  }
  return column;
}

// The base columns: the calibration's free parameters (the accepted effects are pieces of the refit).
void fillBase(Linearised& lin, const GeometricCalibrationResult& cal) {
  lin.problem.base.resize(3 * lin.problem.rows, static_cast<Eigen::Index>(cal.free.size()));
  for (std::size_t c = 0; c < cal.free.size(); ++c)
    lin.problem.base.col(static_cast<Eigen::Index>(c)) = lin.layout_jacobian.col(cal.free[c]);
}

void mapToJoints(Linearised& lin, int i, const Eigen::MatrixXd& jq, const Eigen::Vector3d& error) {
  const int n = lin.problem.dof;
  const Eigen::VectorXd dq = jq.completeOrthogonalDecomposition().solve(-error);
  double moved = 0.0;  // sum over the joints of |dm/dq_j dq_j|^2
  for (int j = 0; j < n; ++j) {
    lin.joint_residual[static_cast<std::size_t>(j)][static_cast<std::size_t>(i)] = dq[j];
    lin.joint_lever[static_cast<std::size_t>(j)][static_cast<std::size_t>(i)] = jq.col(j).norm();
    moved += (jq.col(j) * dq[j]).squaredNorm();
  }
  for (int j = 0; j < n; ++j) {
    const double part = (jq.col(j) * dq[j]).squaredNorm();
    lin.joint_share[static_cast<std::size_t>(j)][static_cast<std::size_t>(i)] =
        moved > 0.0 ? error.squaredNorm() * part / moved : 0.0;
  }
  lin.residual_norm[static_cast<std::size_t>(i)] = error.norm();
  lin.residual[static_cast<std::size_t>(i)] = -error;
}

}  // namespace

Linearised linearise(const JointErrorModel& model, const CalibrationData& data, const GeometricCalibrationResult& cal,
                     const Features& features, const std::vector<Active>& active, const Cuts& cuts, bool map_joints) {
  const Robot& robot = model.robot();
  const int n = robot.dof();
  const GeometricParameterLayout layout(n, data.setups);
  const int rows = static_cast<int>(data.size());
  Linearised lin;
  lin.problem.rows = rows;
  lin.problem.dof = n;
  lin.problem.r.resize(3 * rows);
  lin.problem.joint_column.resize(3 * rows, n);
  if (map_joints) {
    lin.joint_residual.assign(static_cast<std::size_t>(n), std::vector<double>(static_cast<std::size_t>(rows)));
    lin.joint_lever = lin.joint_residual;
    lin.joint_share = lin.joint_residual;
    lin.residual_norm.resize(static_cast<std::size_t>(rows));
    lin.residual.resize(static_cast<std::size_t>(rows));
  }
  Eigen::MatrixXd J;
  for (int i = 0; i < rows; ++i) {
    const Eigen::Vector3d m = KinematicCalibration::predict(robot, cal.estimate, data, static_cast<std::size_t>(i), &J);
    if (i == 0) lin.layout_jacobian.resize(3 * rows, J.cols());
    const double w = std::sqrt(i < static_cast<int>(cal.weight.size()) ? cal.weight[i] : 1.0);
    lin.problem.r.segment<3>(3 * i) = w * (m - data.measured[i]);
    lin.layout_jacobian.middleRows(3 * i, 3) = w * J;
    Eigen::MatrixXd jq(3, n);
    for (int j = 0; j < n; ++j) jq.col(j) = J.col(layout.offset(j));
    lin.problem.joint_column.middleRows(3 * i, 3) = w * jq;
    if (map_joints) mapToJoints(lin, i, jq, m - data.measured[i]);
  }
  fillBase(lin, cal);
  for (const Active& a : active) lin.active.push_back(candidatePiece(lin, features, a.candidate, cal));
  lin.problem.groupings.push_back(timeBlocks(rows, cuts.folds, cuts.sub_blocks));
  lin.problem.groupings.push_back(jointSpaceParts(data.command, cuts.folds, cuts.min_share, cuts.sub_blocks));
  for (int j = 0; j < n; ++j)
    lin.problem.groupings.push_back(angleRanges(data.command, j, cuts.angle_ranges, cuts.sub_blocks));
  lin.problem.groupings.push_back(timeBlocks(rows, cuts.folds, 1));  // the refits' CV: whole blocks
  const RowGrouping& time = lin.problem.groupings.front();
  for (int i = 0; i < rows; ++i)
    lin.time_block.push_back(
        time.group_of_block[static_cast<std::size_t>(time.block_of_row[static_cast<std::size_t>(i)])]);
  accumulateBase(lin.problem);
  return lin;
}

CandidatePiece candidatePiece(const Linearised& lin, const Features& features, int candidate,
                              const GeometricCalibrationResult& cal) {
  const std::vector<int>& free = cal.free;
  const DiscoveryCandidate& c = features.candidates[static_cast<std::size_t>(candidate)];
  const int rows = lin.problem.rows;
  const int n = lin.problem.dof;
  std::vector<int> releases;
  for (int idx : features.releases[static_cast<std::size_t>(candidate)]) {
    if (std::find(free.begin(), free.end(), idx) == free.end()) releases.push_back(idx);
  }
  const bool blocks = c.through_compliance || c.joint_error_blocks;
  const int own = c.coefficients(n);
  CandidatePiece out;
  const int dense = static_cast<int>(releases.size()) + (blocks ? own : 0);
  out.piece.dense.resize(3 * rows, dense);
  int at = 0;
  if (blocks) {
    for (int k = 0; k < own; ++k, ++at) {
      out.coefficients.push_back(at);
      for (int i = 0; i < rows; ++i) out.piece.dense.block<3, 1>(3 * i, at) = blockColumn(lin, c, cal, i, k);
    }
  }
  for (int idx : releases) out.piece.dense.col(at++) = lin.layout_jacobian.col(idx);
  if (!blocks && own > 0) {
    out.piece.features = &features.sparse[static_cast<std::size_t>(candidate)];
    out.piece.joint = c.joint;
    for (int k = 0; k < own; ++k) out.coefficients.push_back(dense + k);
  }
  return out;
}

void addPrior(const FitSystem& system, const std::vector<int>& columns, const Eigen::MatrixXd& prior, double weight,
              const Eigen::VectorXd& theta, Penalty& penalty) {
  if (weight <= 0.0 || prior.size() == 0) return;
  const int total = system.columns();
  if (penalty.empty()) {
    penalty.matrix = Eigen::MatrixXd::Zero(total, total);
    penalty.held = Eigen::VectorXd::Zero(total);
  }
  const int k = static_cast<int>(prior.rows());
  Eigen::MatrixXd scaled(k, k);
  Eigen::VectorXd held_scaled(k);
  for (int a = 0; a < k; ++a) {
    const double sa = system.scale[columns[static_cast<std::size_t>(a)]];
    held_scaled[a] = theta.size() == k ? theta[a] * sa : 0.0;
    for (int b = 0; b < k; ++b) scaled(a, b) = prior(a, b) / (sa * system.scale[columns[static_cast<std::size_t>(b)]]);
  }
  const double trace = scaled.trace();
  if (!(trace > 0.0)) return;
  scaled *= weight * k / trace;
  const Eigen::VectorXd held = scaled * held_scaled;
  for (int a = 0; a < k; ++a) {
    const int pa = columns[static_cast<std::size_t>(a)];
    penalty.held[pa] += held[a];
    for (int b = 0; b < k; ++b) penalty.matrix(pa, columns[static_cast<std::size_t>(b)]) += scaled(a, b);
  }
}

Penalty activePenalty(const Linearised& lin, const FitSystem& system, const Features& features,
                      const std::vector<Active>& active) {
  Penalty penalty;
  for (std::size_t k = 0; k < active.size() && k < lin.active.size(); ++k) {
    const Active& a = active[k];
    const Eigen::MatrixXd& prior = features.candidates[static_cast<std::size_t>(a.candidate)].prior;
    if (prior.size() == 0) continue;
    std::vector<int> columns;
    for (int c : lin.active[k].coefficients) columns.push_back(system.piece_first[k + 1] + c);
    addPrior(system, columns, prior, a.roughness_weight, a.theta, penalty);
    const Eigen::MatrixXd ridge = Eigen::MatrixXd::Identity(prior.rows(), prior.cols());
    addPrior(system, columns, ridge, a.ridge_weight, a.theta, penalty);
  }
  return penalty;
}

}  // namespace jointcomp::discovery_detail
