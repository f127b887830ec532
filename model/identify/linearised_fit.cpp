#include "model/identify/linearised_fit.hpp"

#include <algorithm>

#include "model/common/errors.hpp"

namespace jointcomp {
namespace {

// Places the base's and every piece's sums of one grouping into the system's per-block matrices.
void assembleGrouping(const LinearisedProblem& problem, const std::vector<const ColumnPiece*>& pieces, int grouping,
                      const std::vector<int>& first, int columns, FitSystem& system) {
  const BlockSums& base = problem.base_sums[static_cast<std::size_t>(grouping)];
  const int m = static_cast<int>(problem.base.cols());
  const std::size_t blocks = base.gram.size();
  std::vector<Eigen::MatrixXd> gram(blocks, Eigen::MatrixXd::Zero(columns, columns));
  std::vector<Eigen::VectorXd> xr(blocks, Eigen::VectorXd::Zero(columns));
  for (std::size_t b = 0; b < blocks; ++b) {
    gram[b].topLeftCorner(m, m) = base.gram[b];
    xr[b].head(m) = base.xr[b];
  }
  for (std::size_t p = 0; p < pieces.size(); ++p) {
    const int at = first[p + 1], size = pieces[p]->columns();
    const BlockSums with_base = crossWithBase(problem, *pieces[p], grouping);
    for (std::size_t b = 0; b < blocks; ++b) {
      gram[b].block(0, at, m, size) = with_base.gram[b];
      gram[b].block(at, 0, size, m) = with_base.gram[b].transpose();
    }
    for (std::size_t q = p; q < pieces.size(); ++q) {
      const int at_q = first[q + 1], size_q = pieces[q]->columns();
      const BlockSums cross = crossPieces(problem, *pieces[p], *pieces[q], grouping, p == q);
      for (std::size_t b = 0; b < blocks; ++b) {
        gram[b].block(at, at_q, size, size_q) = cross.gram[b];
        gram[b].block(at_q, at, size_q, size) = cross.gram[b].transpose();
        if (p == q) xr[b].segment(at, size) = cross.xr[b];
      }
    }
  }
  system.gram.push_back(std::move(gram));
  system.xr.push_back(std::move(xr));
  system.rr.push_back(base.rr);
}

}  // namespace

FitSystem assembleSystem(const LinearisedProblem& problem, const std::vector<const ColumnPiece*>& pieces,
                         const std::vector<int>& groupings) {
  FitSystem system;
  system.groupings = groupings;
  system.piece_first = {0};
  int columns = static_cast<int>(problem.base.cols());
  for (const ColumnPiece* piece : pieces) {
    system.piece_first.push_back(columns);
    columns += piece->columns();
  }
  for (int g : groupings) {
    assembleGrouping(problem, pieces, g, system.piece_first, columns, system);
    system.group_of_block.push_back(problem.groupings[static_cast<std::size_t>(g)].group_of_block);
  }
  system.total_gram = Eigen::MatrixXd::Zero(columns, columns);
  system.total_xr = Eigen::VectorXd::Zero(columns);
  for (std::size_t b = 0; b < system.gram.front().size(); ++b) {
    system.total_gram += system.gram.front()[b];
    system.total_xr += system.xr.front()[b];
    system.total_rr += system.rr.front()[b];
  }
  // Unit column norms, so that the priors' weights and the rank threshold mean the same for every column.
  system.scale.resize(columns);
  for (int c = 0; c < columns; ++c) {
    const double norm = std::sqrt(std::max(0.0, system.total_gram(c, c)));
    system.scale[c] = norm > 0.0 ? norm : 1.0;
  }
  const Eigen::VectorXd inverse = system.scale.cwiseInverse();
  auto scaleMatrix = [&](Eigen::MatrixXd& g) { g = inverse.asDiagonal() * g * inverse.asDiagonal(); };
  scaleMatrix(system.total_gram);
  system.total_xr = system.total_xr.cwiseProduct(inverse);
  for (std::size_t g = 0; g < system.gram.size(); ++g) {
    for (std::size_t b = 0; b < system.gram[g].size(); ++b) {
      scaleMatrix(system.gram[g][b]);
      system.xr[g][b] = system.xr[g][b].cwiseProduct(inverse);
    }
  }
  return system;
}

namespace {

// Solves (g) d = -b: the least-squares step; with a prior g is positive definite (LDLT), without it the
// rank-revealing QR gives the minimum-change solution of the identifiable columns.
Eigen::VectorXd solveStep(const Eigen::MatrixXd& g, const Eigen::VectorXd& b, bool penalised, int* rank) {
  if (penalised) {
    Eigen::LDLT<Eigen::MatrixXd> ldlt(g);
    if (ldlt.info() == Eigen::Success && ldlt.isPositive()) {
      if (rank) *rank = static_cast<int>(g.rows());
      return -ldlt.solve(b);
    }
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(g);
  qr.setThreshold(1e-10);
  if (rank) *rank = static_cast<int>(qr.rank());
  return -qr.solve(b);
}

double blockError(const Eigen::MatrixXd& g, const Eigen::VectorXd& xr, double rr, const Eigen::VectorXd& d) {
  return std::max(0.0, rr + 2.0 * d.dot(xr) + d.dot(g * d));
}

}  // namespace

Fit solveSystem(const FitSystem& system, const Penalty& penalty, bool need_inverse) {
  Fit fit;
  const bool penalised = !penalty.empty();
  const int k = system.columns();
  const Eigen::MatrixXd prior = penalised ? penalty.matrix : Eigen::MatrixXd::Zero(k, k);
  const Eigen::VectorXd held = penalised ? penalty.held : Eigen::VectorXd::Zero(k);
  const Eigen::MatrixXd& g = system.total_gram;
  const Eigen::VectorXd& b = system.total_xr;
  fit.d = solveStep(g + prior, b + held, penalised, &fit.rank);
  if (!fit.d.allFinite()) throw SolverError("discover: the linearised fit is not finite");
  fit.rss = blockError(g, b, system.total_rr, fit.d);
  fit.dof = fit.rank;
  if (penalised) {
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(g + prior);
    fit.dof = ldlt.solve(g).trace();
  }
  for (std::size_t grouping = 0; grouping < system.gram.size(); ++grouping) {
    const auto& grams = system.gram[grouping];
    const auto& xrs = system.xr[grouping];
    const auto& rrs = system.rr[grouping];
    const std::vector<int>& group_of_block = system.group_of_block[grouping];
    GroupingErrors errors;
    errors.block.assign(grams.size(), 0.0);
    // The blocks of each group are consecutive in the grouping's numbering.
    std::size_t first = 0;
    while (first < grams.size()) {
      std::size_t end = first + 1;
      Eigen::MatrixXd gg = grams[first];
      Eigen::VectorXd bg = xrs[first];
      while (end < grams.size() && group_of_block[end] == group_of_block[first]) {
        gg += grams[end];
        bg += xrs[end];
        ++end;
      }
      const Eigen::VectorXd d = solveStep(g - gg + prior, b - bg + held, penalised, nullptr);
      double group_error = 0.0;
      for (std::size_t blk = first; blk < end; ++blk) {
        errors.block[blk] = blockError(grams[blk], xrs[blk], rrs[blk], d);
        group_error += errors.block[blk];
      }
      errors.group.push_back(group_error);
      first = end;
    }
    fit.errors.push_back(std::move(errors));
  }
  fit.cv_fold = fit.errors.front().group;
  for (double e : fit.cv_fold) fit.cv += e;
  if (need_inverse) fit.inverse = (g + prior).completeOrthogonalDecomposition().pseudoInverse();
  return fit;
}

}  // namespace jointcomp
