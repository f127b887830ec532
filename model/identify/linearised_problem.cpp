#include "model/identify/linearised_problem.hpp"

#include <algorithm>
#include <limits>
#include <numeric>

namespace jointcomp {

RowGrouping makeGrouping(std::string kind, const std::vector<int>& group_of_row, int groups, int sub_blocks) {
  RowGrouping g;
  g.kind = std::move(kind);
  g.rows_of_group.assign(static_cast<std::size_t>(groups), 0);
  for (int group : group_of_row) ++g.rows_of_group[static_cast<std::size_t>(group)];
  // Each group's rows, in row order, cut into sub-blocks of about equal size.
  std::vector<int> first_block(static_cast<std::size_t>(groups), 0);
  std::vector<int> per_block(static_cast<std::size_t>(groups), 1);
  for (int group = 0; group < groups; ++group) {
    const int rows = g.rows_of_group[static_cast<std::size_t>(group)];
    const int blocks = std::max(1, std::min(sub_blocks, rows));
    first_block[static_cast<std::size_t>(group)] = g.blocks();
    per_block[static_cast<std::size_t>(group)] = std::max(1, (rows + blocks - 1) / blocks);
    for (int b = 0; b < blocks; ++b) g.group_of_block.push_back(group);
  }
  std::vector<int> seen(static_cast<std::size_t>(groups), 0);
  g.block_of_row.resize(group_of_row.size());
  for (std::size_t i = 0; i < group_of_row.size(); ++i) {
    const std::size_t group = static_cast<std::size_t>(group_of_row[i]);
    const int within = seen[group]++ / per_block[group];
    const int last = (group + 1 < first_block.size() ? first_block[group + 1] : g.blocks()) - 1;
    g.block_of_row[i] = std::min(first_block[group] + within, last);
  }
  return g;
}

RowGrouping timeBlocks(int rows, int folds, int sub_blocks) {
  std::vector<int> group(static_cast<std::size_t>(rows));
  for (int i = 0; i < rows; ++i)
    group[static_cast<std::size_t>(i)] = std::min(folds - 1, static_cast<int>(static_cast<long>(i) * folds / rows));
  return makeGrouping("time block", group, folds, sub_blocks);
}

namespace {

int nearestCentre(const JointVector& q, const std::vector<JointVector>& centre, const std::vector<bool>& usable) {
  int nearest = -1;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t c = 0; c < centre.size(); ++c) {
    if (!usable[c]) continue;
    const double d = (q - centre[c]).squaredNorm();
    if (d < best) {
      best = d;
      nearest = static_cast<int>(c);
    }
  }
  return nearest;
}

// k-means of the joint vectors into `parts` clusters, seeded by farthest points from the first row.
std::vector<JointVector> kMeansCentres(const std::vector<JointVector>& command, int parts, std::vector<int>& part) {
  const std::size_t rows = command.size();
  std::vector<JointVector> centre = {command.front()};
  std::vector<double> distance(rows, std::numeric_limits<double>::infinity());
  while (static_cast<int>(centre.size()) < parts) {
    std::size_t farthest = 0;
    for (std::size_t i = 0; i < rows; ++i) {
      distance[i] = std::min(distance[i], (command[i] - centre.back()).squaredNorm());
      if (distance[i] > distance[farthest]) farthest = i;
    }
    centre.push_back(command[farthest]);
  }
  const std::vector<bool> all(centre.size(), true);
  for (int iteration = 0; iteration < 30; ++iteration) {
    bool moved = false;
    for (std::size_t i = 0; i < rows; ++i) {
      const int nearest = nearestCentre(command[i], centre, all);
      moved = moved || part[i] != nearest;
      part[i] = nearest;
    }
    if (!moved && iteration > 0) break;
    std::vector<int> count(centre.size(), 0);
    for (auto& c : centre) c.setZero();
    for (std::size_t i = 0; i < rows; ++i) {
      centre[static_cast<std::size_t>(part[i])] += command[i];
      ++count[static_cast<std::size_t>(part[i])];
    }
    for (std::size_t c = 0; c < centre.size(); ++c) {
      if (count[c] > 0) centre[c] /= count[c];
    }
  }
  return centre;
}

}  // namespace

RowGrouping jointSpaceParts(const std::vector<JointVector>& command, int parts, double min_share, int sub_blocks) {
  const std::size_t rows = command.size();
  std::vector<int> part(rows, 0);
  if (static_cast<int>(rows) < parts || parts < 2) return makeGrouping("joint-space part", part, 1, sub_blocks);
  const std::vector<JointVector> centre = kMeansCentres(command, parts, part);
  // Clusters too small to measure join the nearest large one.
  std::vector<int> count(centre.size(), 0);
  for (int p : part) ++count[static_cast<std::size_t>(p)];
  std::vector<bool> large(centre.size(), false);
  for (std::size_t c = 0; c < centre.size(); ++c) large[c] = count[c] >= min_share * static_cast<double>(rows);
  if (std::none_of(large.begin(), large.end(), [](bool b) { return b; })) large.assign(centre.size(), true);
  std::vector<int> renumber(centre.size(), -1);
  int kept = 0;
  for (std::size_t c = 0; c < centre.size(); ++c) {
    if (large[c]) renumber[c] = kept++;
  }
  for (std::size_t i = 0; i < rows; ++i) {
    const int p = large[static_cast<std::size_t>(part[i])] ? part[i] : nearestCentre(command[i], centre, large);
    part[i] = renumber[static_cast<std::size_t>(p)];
  }
  return makeGrouping("joint-space part", part, kept, sub_blocks);
}

RowGrouping angleRanges(const std::vector<JointVector>& command, int joint, int ranges, int sub_blocks) {
  const std::size_t rows = command.size();
  std::vector<std::size_t> order(rows);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return command[a][joint] < command[b][joint]; });
  std::vector<int> group(rows, 0);
  const int count = std::max(1, std::min(ranges, static_cast<int>(rows)));
  for (std::size_t k = 0; k < rows; ++k) group[order[k]] = std::min(count - 1, static_cast<int>(k * count / rows));
  // Rows of equal angle stay in one range (a grid visits the same angle many times).
  for (std::size_t k = 1; k < rows; ++k) {
    if (command[order[k]][joint] == command[order[k - 1]][joint]) group[order[k]] = group[order[k - 1]];
  }
  RowGrouping g = makeGrouping("joint " + std::to_string(joint + 1) + " angle range", group, count, sub_blocks);
  g.joint = joint;
  return g;
}

SparseFeatures sparseFeatures(const Eigen::MatrixXd& features) {
  SparseFeatures f;
  f.columns = static_cast<int>(features.cols());
  f.start.reserve(static_cast<std::size_t>(features.rows()) + 1);
  const Eigen::MatrixXd by_row = features.transpose();  // one row's values contiguous
  for (Eigen::Index i = 0; i < by_row.cols(); ++i) {
    f.start.push_back(static_cast<int>(f.column.size()));
    for (Eigen::Index k = 0; k < by_row.rows(); ++k) {
      if (by_row(k, i) == 0.0) continue;
      f.column.push_back(static_cast<int>(k));
      f.value.push_back(by_row(k, i));
    }
  }
  f.start.push_back(static_cast<int>(f.column.size()));
  return f;
}

void accumulateBase(LinearisedProblem& problem) {
  const int m = static_cast<int>(problem.base.cols());
  problem.base_joint.assign(static_cast<std::size_t>(problem.dof), Eigen::MatrixXd::Zero(m, problem.rows));
  for (int i = 0; i < problem.rows && m > 0; ++i) {
    const Eigen::MatrixXd products =
        problem.base.middleRows(3 * i, 3).transpose() * problem.joint_column.middleRows(3 * i, 3);
    for (int j = 0; j < problem.dof; ++j) problem.base_joint[static_cast<std::size_t>(j)].col(i) = products.col(j);
  }
  problem.base_sums.clear();
  for (const RowGrouping& grouping : problem.groupings) {
    BlockSums sums;
    sums.gram.assign(static_cast<std::size_t>(grouping.blocks()), Eigen::MatrixXd::Zero(m, m));
    sums.xr.assign(static_cast<std::size_t>(grouping.blocks()), Eigen::VectorXd::Zero(m));
    sums.rr.assign(static_cast<std::size_t>(grouping.blocks()), 0.0);
    // Rows of one block are gathered and multiplied at once.
    std::vector<std::vector<Eigen::Index>> rows_of_block(static_cast<std::size_t>(grouping.blocks()));
    for (int i = 0; i < problem.rows; ++i) {
      auto& list = rows_of_block[static_cast<std::size_t>(grouping.block_of_row[static_cast<std::size_t>(i)])];
      for (int a = 0; a < 3; ++a) list.push_back(3 * static_cast<Eigen::Index>(i) + a);
    }
    for (std::size_t b = 0; b < rows_of_block.size(); ++b) {
      if (rows_of_block[b].empty()) continue;
      const Eigen::MatrixXd x = problem.base(rows_of_block[b], Eigen::all);
      const Eigen::VectorXd r = problem.r(rows_of_block[b]);
      sums.gram[b].selfadjointView<Eigen::Lower>().rankUpdate(x.transpose());
      sums.gram[b] = sums.gram[b].selfadjointView<Eigen::Lower>();
      sums.xr[b] = x.transpose() * r;
      sums.rr[b] = r.squaredNorm();
    }
    problem.base_sums.push_back(std::move(sums));
  }
}

namespace {

BlockSums zeroSums(int blocks, int rows, int cols, bool with_residual) {
  BlockSums sums;
  sums.gram.assign(static_cast<std::size_t>(blocks), Eigen::MatrixXd::Zero(rows, cols));
  if (with_residual) {
    sums.xr.assign(static_cast<std::size_t>(blocks), Eigen::VectorXd::Zero(rows));
    sums.rr.assign(static_cast<std::size_t>(blocks), 0.0);
  }
  return sums;
}

}  // namespace

BlockSums crossWithBase(const LinearisedProblem& problem, const ColumnPiece& piece, int grouping) {
  const RowGrouping& g = problem.groupings[static_cast<std::size_t>(grouping)];
  const int m = static_cast<int>(problem.base.cols());
  const int kd = piece.denseColumns();
  BlockSums sums = zeroSums(g.blocks(), m, piece.columns(), false);
  if (m == 0) return sums;  // no base columns: nothing to cross (and no data to take rows of)
  const SparseFeatures* f = piece.features;
  for (int i = 0; i < problem.rows; ++i) {
    Eigen::MatrixXd& gram = sums.gram[static_cast<std::size_t>(g.block_of_row[static_cast<std::size_t>(i)])];
    if (kd > 0)
      gram.leftCols(kd).noalias() += problem.base.middleRows(3 * i, 3).transpose() * piece.dense.middleRows(3 * i, 3);
    if (!f) continue;
    const auto u = problem.base_joint[static_cast<std::size_t>(piece.joint)].col(i);
    for (int e = f->start[static_cast<std::size_t>(i)]; e < f->start[static_cast<std::size_t>(i) + 1]; ++e)
      gram.col(kd + f->column[static_cast<std::size_t>(e)]) += f->value[static_cast<std::size_t>(e)] * u;
  }
  return sums;
}

BlockSums crossPieces(const LinearisedProblem& problem, const ColumnPiece& a, const ColumnPiece& b, int grouping,
                      bool with_residual) {
  const RowGrouping& g = problem.groupings[static_cast<std::size_t>(grouping)];
  const int kda = a.denseColumns(), kdb = b.denseColumns();
  BlockSums sums = zeroSums(g.blocks(), a.columns(), b.columns(), with_residual);
  std::vector<int> ca, cb;
  std::vector<double> va, vb;
  auto nonzero = [](const SparseFeatures* f, int i, std::vector<int>& column, std::vector<double>& value) {
    column.clear();
    value.clear();
    if (!f) return;
    for (int e = f->start[static_cast<std::size_t>(i)]; e < f->start[static_cast<std::size_t>(i) + 1]; ++e) {
      column.push_back(f->column[static_cast<std::size_t>(e)]);
      value.push_back(f->value[static_cast<std::size_t>(e)]);
    }
  };
  for (int i = 0; i < problem.rows; ++i) {
    const std::size_t block = static_cast<std::size_t>(g.block_of_row[static_cast<std::size_t>(i)]);
    Eigen::MatrixXd& gram = sums.gram[block];
    const auto r = problem.r.segment<3>(3 * i);
    nonzero(a.features, i, ca, va);
    nonzero(b.features, i, cb, vb);
    const Eigen::Vector3d ja =
        a.features ? Eigen::Vector3d(problem.joint_column.block(3 * i, a.joint, 3, 1)) : Eigen::Vector3d::Zero();
    const Eigen::Vector3d jb =
        b.features ? Eigen::Vector3d(problem.joint_column.block(3 * i, b.joint, 3, 1)) : Eigen::Vector3d::Zero();
    // A piece without dense columns holds no data: its rows are never formed (an offset from null).
    auto da = [&] { return a.dense.middleRows(3 * i, 3); };
    auto db = [&] { return b.dense.middleRows(3 * i, 3); };
    if (kda > 0 && kdb > 0) gram.topLeftCorner(kda, kdb).noalias() += da().transpose() * db();
    if (kda > 0 && !cb.empty()) {
      const Eigen::VectorXd u = da().transpose() * jb;
      for (std::size_t k = 0; k < cb.size(); ++k) gram.block(0, kdb + cb[k], kda, 1) += vb[k] * u;
    }
    if (kdb > 0 && !ca.empty()) {
      const Eigen::RowVectorXd u = ja.transpose() * db();
      for (std::size_t k = 0; k < ca.size(); ++k) gram.block(kda + ca[k], 0, 1, kdb) += va[k] * u;
    }
    if (!ca.empty() && !cb.empty()) {
      const double dot = ja.dot(jb);
      for (std::size_t p = 0; p < ca.size(); ++p)
        for (std::size_t q = 0; q < cb.size(); ++q) gram(kda + ca[p], kdb + cb[q]) += va[p] * vb[q] * dot;
    }
    if (!with_residual) continue;
    if (kda > 0) sums.xr[block].head(kda).noalias() += da().transpose() * r;
    const double jr = ja.dot(r);
    for (std::size_t k = 0; k < ca.size(); ++k) sums.xr[block][kda + ca[k]] += va[k] * jr;
    sums.rr[block] += r.squaredNorm();
  }
  return sums;
}

}  // namespace jointcomp
