#include "model/identify/identifiability.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/QR>
#include <Eigen/SVD>

#include "model/common/errors.hpp"

namespace jointcomp {

double scaledConditionNumber(const Eigen::MatrixXd& jacobian, const std::vector<int>& columns) {
  if (columns.empty()) return 1.0;
  Eigen::MatrixXd scaled(jacobian.rows(), static_cast<Eigen::Index>(columns.size()));
  for (std::size_t k = 0; k < columns.size(); ++k) {
    const double norm = jacobian.col(columns[k]).norm();
    if (norm == 0.0) return std::numeric_limits<double>::infinity();
    scaled.col(static_cast<Eigen::Index>(k)) = jacobian.col(columns[k]) / norm;
  }
  // cond(J) = cond(R) for J = Q R: the SVD of the small triangular factor. In place: `scaled` is as large
  // as the Jacobian (a copy per call was a calibration's largest memory per row).
  const Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(scaled);
  const Eigen::Index k = scaled.cols();
  const Eigen::MatrixXd r = qr.matrixQR().topLeftCorner(std::min(k, scaled.rows()), k).triangularView<Eigen::Upper>();
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(r);
  const Eigen::VectorXd& sigma = svd.singularValues();
  if (sigma.size() < k || sigma[sigma.size() - 1] <= 0.0) return std::numeric_limits<double>::infinity();
  return sigma[0] / sigma[sigma.size() - 1];
}

namespace {

// What each fixed column is redundant with: its least-squares fit by the kept columns (the largest four
// contributions of at least a fifth of the largest).
void findRedundancies(const Eigen::MatrixXd& jacobian, IdentifiabilityResult& result) {
  const Eigen::Index m = jacobian.rows();
  if (!result.kept.empty()) {
    Eigen::MatrixXd kept(m, static_cast<Eigen::Index>(result.kept.size()));
    for (std::size_t k = 0; k < result.kept.size(); ++k) {
      kept.col(static_cast<Eigen::Index>(k)) = jacobian.col(result.kept[k]) / result.column_norm[result.kept[k]];
    }
    const Eigen::ColPivHouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(kept);  // in place, as above
    for (int j : result.fixed) {
      if (result.no_effect[static_cast<std::size_t>(j)]) continue;
      const Eigen::VectorXd c = qr.solve(Eigen::VectorXd(jacobian.col(j) / result.column_norm[j]));
      const double largest = c.cwiseAbs().maxCoeff();
      std::vector<Redundancy> list;
      for (std::size_t k = 0; k < result.kept.size(); ++k) {
        const double ck = c[static_cast<Eigen::Index>(k)];
        if (std::abs(ck) >= 0.2 * largest && std::abs(ck) > 1e-6) {
          const int column = result.kept[k];
          list.push_back({column, ck * result.column_norm[j] / result.column_norm[column]});
        }
      }
      std::sort(list.begin(), list.end(), [&](const Redundancy& a, const Redundancy& b) {
        return std::abs(a.ratio * result.column_norm[a.column]) > std::abs(b.ratio * result.column_norm[b.column]);
      });
      if (list.size() > 4) list.resize(4);
      result.redundant_with[static_cast<std::size_t>(j)] = list;
    }
  }
}

}  // namespace

namespace {

void checkIdentifiabilityInputs(const Eigen::MatrixXd& jacobian, const std::vector<int>& priority,
                                const std::vector<double>& typical_change, const IdentifiabilityOptions& options) {
  const Eigen::Index n = jacobian.cols();
  if (!priority.empty() && static_cast<Eigen::Index>(priority.size()) != n) {
    throw InvalidArgument("analyseIdentifiability: " + std::to_string(priority.size()) + " priorities for " +
                          std::to_string(n) + " columns");
  }
  if (!typical_change.empty() && static_cast<Eigen::Index>(typical_change.size()) != n) {
    throw InvalidArgument("analyseIdentifiability: " + std::to_string(typical_change.size()) + " typical changes for " +
                          std::to_string(n) + " columns");
  }
  if (!jacobian.allFinite()) throw InvalidArgument("analyseIdentifiability: the Jacobian is not finite");
  if (!(options.relative_pivot_threshold > 0.0 && options.relative_pivot_threshold < 1.0)) {
    throw InvalidArgument("analyseIdentifiability: the relative pivot threshold must lie in (0, 1)");
  }
}

// The Jacobian's columns scaled to unit norm into `work` (the column norms into result), and the columns with
// an effect (beyond the no-effect tolerance over their typical change) into `remaining`; the others are zero.
void normaliseColumns(const Eigen::MatrixXd& jacobian, const std::vector<double>& typical_change,
                      const IdentifiabilityOptions& options, IdentifiabilityResult& result, Eigen::MatrixXd& work,
                      std::vector<int>& remaining) {
  const Eigen::Index m = jacobian.rows();
  const Eigen::Index n = jacobian.cols();
  const double rows = static_cast<double>(std::max<Eigen::Index>(m, 1));
  for (Eigen::Index j = 0; j < n; ++j) {
    const double norm = jacobian.col(j).norm();
    result.column_norm[j] = norm;
    const double change = typical_change.empty() ? 1.0 : typical_change[static_cast<std::size_t>(j)];
    if (norm * change / std::sqrt(rows) <= options.no_effect_tolerance || norm == 0.0) {
      result.no_effect[static_cast<std::size_t>(j)] = true;
      work.col(j).setZero();
      continue;
    }
    work.col(j) = jacobian.col(j) / norm;
    remaining.push_back(static_cast<int>(j));
  }
}

// Column-pivoted Gram-Schmidt (twice orthogonalised) of the unit columns `work`, pivots restricted to the
// highest priority class: the pivot order and each column's pivot (its norm off the columns before it) into
// result; the columns left below the threshold stay in `remaining`. The orthonormal basis takes the place of
// the columns it was made from: work's first `rank` columns are the basis, `at[j]` is where column j is now
// (a basis of its own had been a third matrix of the Jacobian's size).
void pivotColumns(const std::vector<int>& priority, const IdentifiabilityOptions& options,
                  IdentifiabilityResult& result, Eigen::MatrixXd& work, std::vector<int>& remaining) {
  const Eigen::Index n = work.cols();
  std::vector<Eigen::Index> at(static_cast<std::size_t>(n)), column_at(static_cast<std::size_t>(n));
  for (Eigen::Index j = 0; j < n; ++j) at[static_cast<std::size_t>(j)] = column_at[static_cast<std::size_t>(j)] = j;
  const auto column = [&](int j) { return work.col(at[static_cast<std::size_t>(j)]); };
  int rank = 0;
  Eigen::VectorXd residual_norm = Eigen::VectorXd::Zero(n);
  while (!remaining.empty()) {
    int best = -1;
    for (int j : remaining) {
      residual_norm[j] = column(j).norm();
      if (residual_norm[j] <= options.relative_pivot_threshold) continue;
      if (best < 0) {
        best = j;
        continue;
      }
      const int pj = priority.empty() ? 0 : priority[static_cast<std::size_t>(j)];
      const int pb = priority.empty() ? 0 : priority[static_cast<std::size_t>(best)];
      // Exactly redundant columns have equal norms up to rounding: the earlier column wins such ties, so
      // that the choice does not depend on rounding noise.
      if (pj < pb || (pj == pb && residual_norm[j] > residual_norm[best] * (1.0 + 1e-8))) best = j;
    }
    if (best < 0) break;
    result.pivot[best] = residual_norm[best];
    Eigen::VectorXd q = column(best);
    for (int pass = 0; pass < 2 && rank > 0; ++pass) q -= work.leftCols(rank) * (work.leftCols(rank).transpose() * q);
    q.normalize();
    // Column `best` is done with: the column at position `rank` moves to its place, q takes position `rank`.
    const Eigen::Index from = at[static_cast<std::size_t>(best)];
    const int moved = static_cast<int>(column_at[static_cast<std::size_t>(rank)]);
    if (from != rank) work.col(from) = work.col(rank);
    at[static_cast<std::size_t>(moved)] = from;
    column_at[static_cast<std::size_t>(from)] = moved;
    at[static_cast<std::size_t>(best)] = rank;
    column_at[static_cast<std::size_t>(rank)] = best;
    work.col(rank++) = q;
    result.pivot_order.push_back(best);
    remaining.erase(std::find(remaining.begin(), remaining.end(), best));
    for (int j : remaining) column(j) -= q * q.dot(column(j));
  }
  for (int j : remaining) result.pivot[j] = residual_norm[j];
}

}  // namespace

IdentifiabilityResult analyseIdentifiability(const Eigen::MatrixXd& jacobian, const std::vector<int>& priority,
                                             const std::vector<double>& typical_change,
                                             const IdentifiabilityOptions& options) {
  const Eigen::Index m = jacobian.rows();
  const Eigen::Index n = jacobian.cols();
  checkIdentifiabilityInputs(jacobian, priority, typical_change, options);

  IdentifiabilityResult result;
  result.pivot = Eigen::VectorXd::Zero(n);
  result.column_norm.resize(n);
  result.no_effect.assign(static_cast<std::size_t>(n), false);
  result.redundant_with.resize(static_cast<std::size_t>(n));

  // Unit-norm columns; those without effect take no part.
  {
    Eigen::MatrixXd work(m, n);  // freed before the condition number's and the redundancies' matrices
    std::vector<int> remaining;
    normaliseColumns(jacobian, typical_change, options, result, work, remaining);
    pivotColumns(priority, options, result, work, remaining);
  }

  result.kept = result.pivot_order;
  std::sort(result.kept.begin(), result.kept.end());
  for (Eigen::Index j = 0; j < n; ++j) {
    if (!std::binary_search(result.kept.begin(), result.kept.end(), static_cast<int>(j))) {
      result.fixed.push_back(static_cast<int>(j));
    }
  }
  result.condition_number = scaledConditionNumber(jacobian, result.kept);

  findRedundancies(jacobian, result);
  return result;
}

}  // namespace jointcomp
