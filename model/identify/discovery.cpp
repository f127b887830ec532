#include "model/identify/discovery.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <set>

#include "model/common/errors.hpp"
#include "model/common/median.hpp"
#include "model/compensation/metrics.hpp"
#include "model/effects/registry.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {
namespace {

// An accepted candidate: its index among the offered ones, its coefficients and their sigmas.
struct Active {
  int candidate = 0;
  Eigen::VectorXd theta;
  Eigen::VectorXd sigma;
  double prior_weight = 0.0;  // the weight of the candidate's prior cross-validation chose (0: none)
};

const EffectRegistry& registryOf(const DiscoveryOptions& options) {
  return options.registry ? *options.registry : EffectRegistry::builtin();
}

bool wanted(const DiscoveryOptions& options, const std::string& type) {
  return options.types.empty() || std::find(options.types.begin(), options.types.end(), type) != options.types.end();
}

// The used rows as the families see them: commands, motor angles, the side of each joint's lost motion
// (remembered along the command sequence, prepareCalibrationData), load torques, times and temperatures.
DiscoveryData discoveryData(const JointErrorModel& prior, const MeasurementCampaign& campaign,
                            const CalibrationData& data, const DiscoveryOptions& options) {
  const int rows = static_cast<int>(data.size());
  DiscoveryData d;
  d.robot = &prior.robot();
  d.gears = &prior.gears();
  d.command = data.command;
  d.approach = data.approach;
  d.load_torque = data.load_torque;
  d.torque_known = data.torque_known;
  d.velocity_scale = options.velocity_scale;
  d.max_harmonic_order = options.max_harmonic_order;
  double tsum = 0.0;
  int tcount = 0;
  for (int i = 0; i < rows; ++i) {
    const std::size_t k = static_cast<std::size_t>(data.row[i]);
    const double temperature =
        k < campaign.temperature.size() ? campaign.temperature[k] : std::numeric_limits<double>::quiet_NaN();
    d.temperature.push_back(temperature);
    d.time.push_back(campaign.time[k]);
    if (std::isfinite(temperature)) {
      tsum += temperature;
      ++tcount;
    }
    JointVector motor;
    prior.gears().motorAngles(data.command[i], motor);
    d.motor.push_back(motor);
  }
  d.have_temperature = tcount == rows && rows > 0;
  d.temperature0 = d.have_temperature ? tsum / tcount : 20.0;
  d.time0 = campaign.time.empty() ? 0.0 : campaign.time.front();
  return d;
}

// Every candidate the wanted families offer: for each joint every family in the registry's order, then
// each family once for the whole robot. With each, its family and the calibration parameters it frees
// (indices of GeometricParameterLayout).
struct Features {
  std::vector<DiscoveryCandidate> candidates;
  std::vector<const DiscoveryFamily*> family;
  std::vector<std::vector<int>> releases;
};

std::vector<int> layoutIndices(const DiscoveryCandidate& candidate, const GeometricParameterLayout& layout) {
  std::vector<int> indices;
  for (CalibrationParameter parameter : candidate.releases) {
    if (parameter == CalibrationParameter::Offset) indices.push_back(layout.offset(candidate.joint));
    if (parameter == CalibrationParameter::Compliance) indices.push_back(layout.compliance(candidate.joint));
    if (parameter == CalibrationParameter::InstrumentScale) {
      for (int s = 0; s < layout.setups; ++s) indices.push_back(layout.instrumentScale(s));  // each set-up's
    }
    if (parameter == CalibrationParameter::Placement) {
      for (int k = 0; k < 6; ++k) indices.push_back(layout.placement(candidate.joint, k));
    }
  }
  return indices;
}

Features offerCandidates(const DiscoveryData& data, int setups, const DiscoveryOptions& options) {
  Features f;
  std::vector<const DiscoveryFamily*> families;
  for (const auto& family : registryOf(options).discoveryFamilies()) {
    if (wanted(options, family->name())) families.push_back(family.get());
  }
  const int n = data.robot->dof();
  const GeometricParameterLayout layout(n, setups);
  for (int joint = 0; joint <= n; ++joint) {
    for (const DiscoveryFamily* family : families) {
      const std::size_t first = f.candidates.size();
      family->offer(data, joint < n ? joint : -1, f.candidates);
      for (std::size_t c = first; c < f.candidates.size(); ++c) {
        const DiscoveryCandidate& candidate = f.candidates[c];
        if (candidate.columns.rows() != data.rows() && candidate.columns.cols() > 0) {
          throw InvalidArgument("discover: family '" + family->name() + "' offered " +
                                std::to_string(candidate.columns.rows()) + " rows for " + std::to_string(data.rows()));
        }
        f.family.push_back(family);
        f.releases.push_back(candidate.releases.empty() ? std::vector<int>{} : layoutIndices(candidate, layout));
      }
    }
  }
  return f;
}

// The model: prior plus, family by family in the registry's order, the effect of its accepted candidates.
JointErrorModel buildModel(const JointErrorModel& prior, const std::vector<Active>& active, const Features& f,
                           const DiscoveryData& data, const DiscoveryOptions& options) {
  JointErrorModel model = prior;
  for (const auto& family : registryOf(options).discoveryFamilies()) {
    std::vector<FittedCandidate> accepted;
    for (const Active& a : active) {
      if (f.family[static_cast<std::size_t>(a.candidate)] != family.get()) continue;
      accepted.push_back({&f.candidates[static_cast<std::size_t>(a.candidate)], a.theta, a.sigma});
    }
    if (accepted.empty()) continue;
    std::unique_ptr<Effect> effect = family->makeEffect(data, accepted);
    if (!effect) continue;
    effect->estimate_note = "found by jointcomp discover";
    model.addEffect(std::move(effect));
  }
  return model;
}

// The linearised problem at a calibration: residuals and the columns of every parameter and candidate.
struct Linearised {
  Eigen::VectorXd r;      // weighted residuals, 3 per row
  Eigen::MatrixXd X;      // weighted, unit-norm columns
  Eigen::VectorXd scale;  // column norms (X_raw = X * scale)
  std::vector<int> fold;  // fold of each residual row block (per row)
  // The same rows cut into parts far apart in joint space (jointSpaceParts), for the transfer check.
  std::vector<Eigen::MatrixXd> space_gram;
  std::vector<Eigen::VectorXd> space_xr;
  std::vector<double> space_rr;
  std::vector<Eigen::MatrixXd> gram;  // per fold X_f^T X_f
  std::vector<Eigen::VectorXd> xr;    // per fold X_f^T r_f
  std::vector<double> rr;             // per fold r_f^T r_f
  Eigen::MatrixXd gram_total;
  Eigen::VectorXd xr_total;
  double rr_total = 0.0;
  std::vector<int> base_columns, active_columns;    // indices into X
  std::vector<std::vector<int>> candidate_columns;  // per candidate, empty when not offered
  std::vector<std::vector<int>> active_of;          // per active, its columns
  std::vector<std::vector<double>> joint_residual;  // per joint, per row (pinv mapping)
  std::vector<double> residual_norm;                // per row, |measured - predicted| (m), with the mapping
  std::vector<Eigen::Vector3d> residual;            // per row, measured - predicted (m), with the mapping
  std::vector<std::vector<double>> joint_lever;     // per joint, per row, |dm/dq_j| (m/rad), with the mapping
};

// The per-fold Gram matrices X_f^T X_f, X_f^T r_f and r_f^T r_f, and their totals, for the fast
// leave-one-fold-out fits of fitColumns.
void accumulateFolds(Linearised& lin, int folds, int rows) {
  const int cols = static_cast<int>(lin.X.cols());
  lin.gram.assign(static_cast<std::size_t>(folds), Eigen::MatrixXd::Zero(cols, cols));
  lin.xr.assign(static_cast<std::size_t>(folds), Eigen::VectorXd::Zero(cols));
  lin.rr.assign(static_cast<std::size_t>(folds), 0.0);
  int start = 0;
  for (int fo = 0; fo < folds; ++fo) {
    int end = start;
    while (end < rows && lin.fold[static_cast<std::size_t>(end)] == fo) ++end;
    const auto Xf = lin.X.middleRows(3 * start, 3 * (end - start));
    const auto rf = lin.r.segment(3 * start, 3 * (end - start));
    lin.gram[fo].selfadjointView<Eigen::Lower>().rankUpdate(Xf.transpose());
    lin.gram[fo] = lin.gram[fo].selfadjointView<Eigen::Lower>();
    lin.xr[fo] = Xf.transpose() * rf;
    lin.rr[fo] = rf.squaredNorm();
    start = end;
  }
  lin.gram_total = Eigen::MatrixXd::Zero(cols, cols);
  lin.xr_total = Eigen::VectorXd::Zero(cols);
  for (int fo = 0; fo < folds; ++fo) {
    lin.gram_total += lin.gram[fo];
    lin.xr_total += lin.xr[fo];
    lin.rr_total += lin.rr[fo];
  }
}

// The rows cut into `parts` clusters of the joint vector (k-means, seeded deterministically by farthest
// points from the first row): parts far apart in joint space, as the time folds are in time.
std::vector<int> jointSpaceParts(const std::vector<JointVector>& command, int parts) {
  const int rows = static_cast<int>(command.size());
  std::vector<int> part(static_cast<std::size_t>(rows), 0);
  if (rows < parts) return part;
  std::vector<JointVector> centre = {command.front()};
  std::vector<double> distance(static_cast<std::size_t>(rows), std::numeric_limits<double>::infinity());
  while (static_cast<int>(centre.size()) < parts) {
    int farthest = 0;
    for (int i = 0; i < rows; ++i) {
      double& d = distance[static_cast<std::size_t>(i)];
      d = std::min(d, (command[static_cast<std::size_t>(i)] - centre.back()).squaredNorm());
      if (d > distance[static_cast<std::size_t>(farthest)]) farthest = i;
    }
    centre.push_back(command[static_cast<std::size_t>(farthest)]);
  }
  for (int iteration = 0; iteration < 30; ++iteration) {
    bool moved = false;
    for (int i = 0; i < rows; ++i) {
      int nearest = 0;
      for (int c = 1; c < parts; ++c) {
        if ((command[static_cast<std::size_t>(i)] - centre[static_cast<std::size_t>(c)]).squaredNorm() <
            (command[static_cast<std::size_t>(i)] - centre[static_cast<std::size_t>(nearest)]).squaredNorm())
          nearest = c;
      }
      moved = moved || part[static_cast<std::size_t>(i)] != nearest;
      part[static_cast<std::size_t>(i)] = nearest;
    }
    if (!moved && iteration > 0) break;
    std::vector<int> count(static_cast<std::size_t>(parts), 0);
    for (auto& c : centre) c.setZero();
    for (int i = 0; i < rows; ++i) {
      centre[static_cast<std::size_t>(part[static_cast<std::size_t>(i)])] += command[static_cast<std::size_t>(i)];
      ++count[static_cast<std::size_t>(part[static_cast<std::size_t>(i)])];
    }
    for (int c = 0; c < parts; ++c) {
      if (count[static_cast<std::size_t>(c)] > 0)
        centre[static_cast<std::size_t>(c)] /= count[static_cast<std::size_t>(c)];
    }
  }
  return part;
}

// Gram matrices of the joint-space parts (rows in any order).
void accumulateSpaceParts(Linearised& lin, const std::vector<int>& part, int parts) {
  const int cols = static_cast<int>(lin.X.cols());
  lin.space_gram.assign(static_cast<std::size_t>(parts), Eigen::MatrixXd::Zero(cols, cols));
  lin.space_xr.assign(static_cast<std::size_t>(parts), Eigen::VectorXd::Zero(cols));
  lin.space_rr.assign(static_cast<std::size_t>(parts), 0.0);
  for (int p = 0; p < parts; ++p) {
    std::vector<Eigen::Index> residual_rows;
    for (std::size_t i = 0; i < part.size(); ++i) {
      if (part[i] != p) continue;
      for (int a = 0; a < 3; ++a) residual_rows.push_back(3 * static_cast<Eigen::Index>(i) + a);
    }
    if (residual_rows.empty()) continue;
    const Eigen::MatrixXd Xp = lin.X(residual_rows, Eigen::all);
    const Eigen::VectorXd rp = lin.r(residual_rows);
    Eigen::MatrixXd& gram = lin.space_gram[static_cast<std::size_t>(p)];
    gram.selfadjointView<Eigen::Lower>().rankUpdate(Xp.transpose());
    gram = gram.selfadjointView<Eigen::Lower>();
    lin.space_xr[static_cast<std::size_t>(p)] = Xp.transpose() * rp;
    lin.space_rr[static_cast<std::size_t>(p)] = rp.squaredNorm();
  }
}

// `data`: the fitted rows prepared with `model` (each with its instrument set-up).
Linearised linearise(const JointErrorModel& model, const CalibrationData& data, const GeometricCalibrationResult& cal,
                     const Features& f, const std::vector<Active>& active, const std::vector<bool>& offered, int folds,
                     bool map_joints) {
  const Robot& robot = model.robot();
  const int n = robot.dof();
  GeometricParameterLayout layout(n, data.setups);
  const int rows = static_cast<int>(data.size());
  Linearised lin;
  std::set<int> free(cal.free.begin(), cal.free.end());
  // Column plan. kind 0: layout column; 1: a candidate's feature column times dm/dq_j; 2: a block of dof
  // load-torque columns times -compliance_j dm/dq_j, summed over the joints; 3: a block of dof joint-error
  // columns times dm/dq_j, summed over the joints.
  struct Source {
    int kind;
    int index;   // layout index (kind 0) or candidate
    int column;  // feature column (kind 1) or block (kind 2)
    int joint;
  };
  std::vector<Source> plan;
  auto planFeatures = [&](int c, std::vector<int>& columns, std::vector<int>* also) {
    const DiscoveryCandidate& candidate = f.candidates[static_cast<std::size_t>(c)];
    for (int k = 0; k < candidate.coefficients(n); ++k) {
      columns.push_back(static_cast<int>(plan.size()));
      if (also) also->push_back(static_cast<int>(plan.size()));
      plan.push_back({candidate.through_compliance ? 2 : candidate.joint_error_blocks ? 3 : 1, c, k, candidate.joint});
    }
  };
  for (int idx : cal.free) {
    lin.base_columns.push_back(static_cast<int>(plan.size()));
    plan.push_back({0, idx, 0, 0});
  }
  for (const Active& a : active) {
    std::vector<int> cols;
    planFeatures(a.candidate, cols, &lin.active_columns);
    lin.active_of.push_back(cols);
  }
  lin.candidate_columns.resize(f.candidates.size());
  for (std::size_t c = 0; c < f.candidates.size(); ++c) {
    if (!offered[c]) continue;
    planFeatures(static_cast<int>(c), lin.candidate_columns[c], nullptr);
    for (int idx : f.releases[c]) {
      if (free.count(idx)) continue;
      lin.candidate_columns[c].push_back(static_cast<int>(plan.size()));
      plan.push_back({0, idx, 0, 0});
    }
  }
  const int cols = static_cast<int>(plan.size());
  lin.r.resize(3 * rows);
  lin.X.resize(3 * rows, cols);
  lin.fold.resize(static_cast<std::size_t>(rows));
  if (map_joints) {
    lin.joint_residual.assign(static_cast<std::size_t>(n), std::vector<double>(static_cast<std::size_t>(rows)));
    lin.residual_norm.resize(static_cast<std::size_t>(rows));
    lin.residual.resize(static_cast<std::size_t>(rows));
    lin.joint_lever.assign(static_cast<std::size_t>(n), std::vector<double>(static_cast<std::size_t>(rows)));
  }
  Eigen::MatrixXd J;
  for (int i = 0; i < rows; ++i) {
    const Eigen::Vector3d m = predictMeasurement(robot, cal.estimate, data.command[i], data.load_torque[i],
                                                 data.other_error[i], &J, data.setup[i]);
    const double w = std::sqrt(i < static_cast<int>(cal.weight.size()) ? cal.weight[i] : 1.0);
    lin.r.segment<3>(3 * i) = w * (m - data.measured[i]);
    for (int c = 0; c < cols; ++c) {
      const Source& s = plan[static_cast<std::size_t>(c)];
      if (s.kind == 0) {
        lin.X.block<3, 1>(3 * i, c) = w * J.col(s.index);
        continue;
      }
      const Eigen::MatrixXd& values = f.candidates[static_cast<std::size_t>(s.index)].columns;
      if (s.kind == 1)
        lin.X.block<3, 1>(3 * i, c) = w * values(i, s.column) * J.col(layout.offset(s.joint));
      else {
        Eigen::Vector3d column = Eigen::Vector3d::Zero();
        for (int j = 0; j < n; ++j) {
          const double value = values(i, s.column * n + j);
          if (value == 0.0) continue;
          const double per_joint = s.kind == 2 ? -cal.estimate.compliance[j] * value : value;
          column += per_joint * J.col(layout.offset(j));
        }
        lin.X.block<3, 1>(3 * i, c) = w * column;
      }
    }
    lin.fold[static_cast<std::size_t>(i)] = std::min(folds - 1, static_cast<int>(static_cast<long>(i) * folds / rows));
    if (map_joints) {
      Eigen::MatrixXd Jq(3, n);
      for (int j = 0; j < n; ++j) Jq.col(j) = J.col(layout.offset(j));
      const Eigen::VectorXd dq = Jq.completeOrthogonalDecomposition().solve(-(m - data.measured[i]));
      for (int j = 0; j < n; ++j) lin.joint_residual[static_cast<std::size_t>(j)][static_cast<std::size_t>(i)] = dq[j];
      lin.residual_norm[static_cast<std::size_t>(i)] = (m - data.measured[i]).norm();
      lin.residual[static_cast<std::size_t>(i)] = data.measured[i] - m;
      for (int j = 0; j < n; ++j)
        lin.joint_lever[static_cast<std::size_t>(j)][static_cast<std::size_t>(i)] = Jq.col(j).norm();
    }
  }
  lin.scale.resize(cols);
  for (int c = 0; c < cols; ++c) {
    const double norm = lin.X.col(c).norm();
    lin.scale[c] = norm > 0.0 ? norm : 1.0;
    lin.X.col(c) /= lin.scale[c];
  }
  accumulateFolds(lin, folds, rows);
  accumulateSpaceParts(lin, jointSpaceParts(data.command, folds), folds);
  return lin;
}

Eigen::MatrixXd sub(const Eigen::MatrixXd& m, const std::vector<int>& s) {
  Eigen::MatrixXd out(s.size(), s.size());
  for (std::size_t a = 0; a < s.size(); ++a)
    for (std::size_t b = 0; b < s.size(); ++b) out(static_cast<int>(a), static_cast<int>(b)) = m(s[a], s[b]);
  return out;
}
Eigen::VectorXd sub(const Eigen::VectorXd& v, const std::vector<int>& s) {
  Eigen::VectorXd out(s.size());
  for (std::size_t a = 0; a < s.size(); ++a) out[static_cast<int>(a)] = v[s[a]];
  return out;
}

struct Fit {
  double rss = 0.0;              // full-data residual sum of squares after the step
  double cv = 0.0;               // CV sum of squares
  std::vector<double> cv_fold;   // its part on each fold (time block), predicted from the other folds
  std::vector<double> cv_space;  // the same for the joint-space parts
  int rank = 0;
  Eigen::VectorXd d;        // step (scaled columns), minimises |r + X d|
  Eigen::MatrixXd inverse;  // pseudo-inverse of the Gram matrix (scaled)
};

Eigen::VectorXd solve(const Eigen::MatrixXd& g, const Eigen::VectorXd& b, int* rank) {
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(g);
  qr.setThreshold(1e-10);
  if (rank) *rank = static_cast<int>(qr.rank());
  return qr.solve(b);
}

// A quadratic prior on some of a fit's columns, in the fit's scaled units: the fit minimises
// |r + X d|^2 + (t + d)^T P (t + d), t the coefficients those columns already hold.
struct Penalty {
  Eigen::MatrixXd matrix;  // |s| x |s|; empty: none
  Eigen::VectorXd held;    // P t
};

Fit fitColumns(const Linearised& lin, const std::vector<int>& s, bool need_inverse, const Penalty& penalty = {}) {
  Fit fit;
  const bool penalised = penalty.matrix.size() > 0;
  const Eigen::MatrixXd g = sub(lin.gram_total, s);
  const Eigen::VectorXd b = sub(lin.xr_total, s);
  const Eigen::MatrixXd prior = penalised ? penalty.matrix : Eigen::MatrixXd::Zero(g.rows(), g.cols());
  const Eigen::VectorXd held = penalised ? penalty.held : Eigen::VectorXd::Zero(b.size());
  fit.d = -solve(g + prior, b + held, &fit.rank);
  fit.rss = std::max(0.0, lin.rr_total + 2.0 * fit.d.dot(b) + fit.d.dot(g * fit.d));
  for (std::size_t fo = 0; fo < lin.gram.size(); ++fo) {
    const Eigen::MatrixXd gf = sub(lin.gram[fo], s);
    const Eigen::VectorXd bf = sub(lin.xr[fo], s);
    const Eigen::VectorXd d = -solve(g - gf + prior, b - bf + held, nullptr);
    fit.cv_fold.push_back(std::max(0.0, lin.rr[fo] + 2.0 * d.dot(bf) + d.dot(gf * d)));
    fit.cv += fit.cv_fold.back();
  }
  for (std::size_t p = 0; p < lin.space_gram.size(); ++p) {
    const Eigen::MatrixXd gp = sub(lin.space_gram[p], s);
    const Eigen::VectorXd bp = sub(lin.space_xr[p], s);
    const Eigen::VectorXd d = -solve(g - gp + prior, b - bp + held, nullptr);
    fit.cv_space.push_back(std::max(0.0, lin.space_rr[p] + 2.0 * d.dot(bp) + d.dot(gp * d)));
  }
  if (need_inverse) fit.inverse = (g + prior).completeOrthogonalDecomposition().pseudoInverse();
  return fit;
}

// Adds a candidate's prior to `penalty` for the fit of columns `s`: weight times its prior, in the scaled
// units of the candidate's feature columns `columns`, normalised so that weight 1 weighs like the data of
// one column (unit norm); `theta` the coefficients those columns already hold (SI).
void addPrior(const Linearised& lin, const std::vector<int>& s, const std::vector<int>& columns,
              const Eigen::MatrixXd& prior, double weight, const Eigen::VectorXd& theta, Penalty& penalty) {
  if (weight <= 0.0 || prior.size() == 0) return;
  if (penalty.matrix.size() == 0) {
    penalty.matrix = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(s.size()), static_cast<Eigen::Index>(s.size()));
    penalty.held = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(s.size()));
  }
  const int k = static_cast<int>(prior.rows());
  std::vector<int> position(static_cast<std::size_t>(k), -1);
  for (int a = 0; a < k; ++a) {
    const auto at = std::find(s.begin(), s.end(), columns[static_cast<std::size_t>(a)]);
    if (at != s.end()) position[static_cast<std::size_t>(a)] = static_cast<int>(at - s.begin());
  }
  Eigen::MatrixXd scaled(k, k);
  Eigen::VectorXd held_scaled(k);
  for (int a = 0; a < k; ++a) {
    held_scaled[a] = theta.size() == k ? theta[a] * lin.scale[columns[static_cast<std::size_t>(a)]] : 0.0;
    for (int b = 0; b < k; ++b)
      scaled(a, b) = prior(a, b) / (lin.scale[columns[static_cast<std::size_t>(a)]] *
                                    lin.scale[columns[static_cast<std::size_t>(b)]]);
  }
  const double trace = scaled.trace();
  if (!(trace > 0.0)) return;
  scaled *= weight * k / trace;
  const Eigen::VectorXd held = scaled * held_scaled;
  for (int a = 0; a < k; ++a) {
    const int pa = position[static_cast<std::size_t>(a)];
    if (pa < 0) continue;
    penalty.held[pa] += held[a];
    for (int b = 0; b < k; ++b) {
      const int pb = position[static_cast<std::size_t>(b)];
      if (pb >= 0) penalty.matrix(pa, pb) += scaled(a, b);
    }
  }
}

std::vector<std::string> fixedNames(const std::vector<std::string>& names, const std::set<int>& released,
                                    const DiscoveryOptions& options, int dof) {
  std::vector<std::string> fixed = options.calibration.fixed;
  if (options.base_geometry) return fixed;
  GeometricParameterLayout layout(dof);
  for (int idx = 9; idx < layout.instrumentScale(); ++idx) {  // the scale: fit_instrument_scale
    if (!released.count(idx)) fixed.push_back(names[static_cast<std::size_t>(idx)]);
  }
  return fixed;
}

// Z errors (base frame, measured - predicted) of prepared rows under given parameters, each in the frame
// of its set-up.
std::vector<double> zErrors(const JointErrorModel& model, const GeometricParameters& parameters,
                            const CalibrationData& data) {
  std::vector<Eigen::Matrix3d> base_from_instrument;
  for (int s = 0; s < parameters.setUpCount(); ++s) {
    base_from_instrument.push_back(parameters.ofSetUp(s).instrumentFromBase().linear().transpose());
  }
  std::vector<double> z;
  for (std::size_t i = 0; i < data.size(); ++i) {
    const Eigen::Vector3d m = predictMeasurement(model.robot(), parameters, data.command[i], data.load_torque[i],
                                                 data.other_error[i], nullptr, data.setup[i]);
    z.push_back((base_from_instrument[static_cast<std::size_t>(data.setup[i])] * (data.measured[i] - m)).z());
  }
  return z;
}

PathRoughness roughness(const std::vector<double>& z, bool held_out, int campaign) {
  PathRoughness p;
  p.held_out = held_out;
  p.campaign = campaign;
  p.rows = static_cast<int>(z.size());
  if (!z.empty()) {
    p.ra = averageAbsoluteDeviation(z);
    p.rz = peakToPeakDeviation(z);
  }
  return p;
}

std::vector<double> jointRms(const Linearised& lin) {
  std::vector<double> out;
  for (const auto& v : lin.joint_residual) {
    double s = 0.0;
    for (double x : v) s += x * x;
    out.push_back(v.empty() ? 0.0 : std::sqrt(s / static_cast<double>(v.size())));
  }
  return out;
}

}  // namespace

bool isPathCampaign(const MeasurementCampaign& campaign) {
  const auto protocol = campaign.metadata.find("protocol");
  if (protocol != campaign.metadata.end() && protocol->second == "spiral") return true;
  if (campaign.time.size() < 20) return false;
  std::vector<double> steps;
  for (std::size_t k = 1; k < campaign.time.size(); ++k) steps.push_back(campaign.time[k] - campaign.time[k - 1]);
  const double typical_step = median(std::move(steps));
  return typical_step > 0.0 && typical_step <= 0.1;
}

const std::vector<std::string>& discoveryEffectTypes() {
  static const std::vector<std::string> types = EffectRegistry::builtin().discoveryVocabulary();
  return types;
}

namespace {

// One run of discovery: the fitted data, the candidates, and the model as it grows step by step.
class DiscoveryRun {
public:
  DiscoveryRun(const JointErrorModel& prior, const std::vector<MeasurementCampaign>& fitted,
               const std::vector<int>& setup_of_campaign, const std::vector<MeasurementCampaign>& heldout,
               const DiscoveryOptions& options)
      : prior_(prior),
        fitted_(fitted),
        setup_of_campaign_(setup_of_campaign),
        heldout_(heldout),
        options_(options),
        campaign_(concatenateCampaigns(fitted)),
        names_(geometricParameterNames(prior.robot(),
                                       1 + *std::max_element(setup_of_campaign.begin(), setup_of_campaign.end()))),
        data_(discoveryData(prior, campaign_, fittedRows(prior), options)),
        model_(prior),
        result_(prior) {
    std::size_t first = 0;
    for (const auto& c : fitted) {
      first_row_.push_back(first);
      first += c.size();
      fitted_path_ = fitted_path_ || isPathCampaign(c);
    }
    first_row_.push_back(first);
  }

  DiscoveryResult run() {
    result_.noise_floor = noiseFloor();
    measureCoverage();
    cal_ = calibrate(model_);
    offerFamiliesCandidates();
    lin_ = linearise(model_, fittedRows(model_), cal_, features_, active_, offered_, options_.folds, true);
    result_.joint_residual_rms_initial = jointRms(lin_);
    residuals_ = static_cast<int>(lin_.r.size());
    current_ = lin_.base_columns;
    base_fit_ = fitColumns(lin_, current_, false);
    result_.initial = evaluate(base_fit_.cv);
    state_ = result_.initial;
    report(options_.calibration.progress, "discovery: base fit RMS " +
                                              std::to_string(result_.initial.fitted.rms * 1e3) + " mm, " +
                                              std::to_string(features_.candidates.size()) + " candidates");
    result_.stop_reason = "max_steps reached";
    for (int step = 0; step < options_.max_steps; ++step) {
      if (!takeStep()) break;
      const DiscoveryStep& s = result_.steps.back();
      report(options_.calibration.progress, "discovery step " + std::to_string(step + 1) + ": " + s.type +
                                                (s.joint_name.empty() ? "" : " " + s.joint_name) + s.detail +
                                                ", fitted RMS " + std::to_string(s.after.fitted.rms * 1e3) + " mm");
    }
    report(options_.calibration.progress, "discovery stopped: " + result_.stop_reason);
    finish();
    return std::move(result_);
  }

private:
  struct Choice {
    int index = -1;
    Fit fit;
    double dbic = 0.0;
    int tried = 0;
    std::string runner_up;
    std::string rejected;  // the best candidate that gained overall but did not transfer, and why
    double prior_weight = 0.0;
  };

  // A fit's error predicted where the fitted data are not: the time folds' and the joint-space parts' CV
  // together (the parts, far apart in joint space, see how a table fares between the angles it fitted).
  static double transferError(const Fit& fit) {
    double space = 0.0;
    for (double e : fit.cv_space) space += e;
    return fit.cv + space;
  }

  // The weights of a candidate's prior that cross-validation chooses from: 0 and five decades up to the most.
  std::vector<double> priorWeights() const {
    std::vector<double> weights = {0.0};
    for (int k = 4; k >= 0 && options_.max_prior_weight > 0.0; --k)
      weights.push_back(options_.max_prior_weight * std::pow(10.0, -k));
    return weights;
  }

  // The accepted candidates' priors for a fit of the columns `s`, at the coefficients they hold.
  Penalty activePenalty(const std::vector<int>& s) const {
    Penalty penalty;
    for (std::size_t k = 0; k < active_.size() && k < lin_.active_of.size(); ++k) {
      const Active& a = active_[k];
      addPrior(lin_, s, lin_.active_of[k], features_.candidates[static_cast<std::size_t>(a.candidate)].prior,
               a.prior_weight, a.theta, penalty);
    }
    return penalty;
  }
  static constexpr double kFoldHurt = 0.01;  // a fold's CV error may rise by 1 % at most

  // The joint angles the fitted rows visited, and how far each held-out campaign goes beyond them.
  void measureCoverage() {
    result_.coverage = jointCoverage(data_.command, kCoverageHalfWidth);
    for (const MeasurementCampaign& h : heldout_) {
      std::vector<JointVector> rows;
      for (std::size_t k = 0; k < h.size(); ++k) {
        if (h.command[k].allFinite()) rows.push_back(h.command[k]);
      }
      HeldoutCoverage c;
      for (int j = 0; j < prior_.robot().dof(); ++j) {
        c.fraction_outside.push_back(result_.coverage.fractionOutside(j, rows));
        c.flagged = c.flagged || c.fraction_outside.back() > kCoverageFlagFraction;
      }
      if (!rows.empty()) c.median_pose_distance = medianDistanceToNearest(data_.command, rows);
      result_.heldout_coverage.push_back(c);
    }
  }

  // The families' candidates, offered once the base fit's residual is known (families may scan it).
  void offerFamiliesCandidates() {
    data_.joint_residual =
        linearise(model_, fittedRows(model_), cal_, Features(), {}, {}, options_.folds, true).joint_residual;
    features_ = offerCandidates(data_, cal_.estimate.setUpCount(), options_);
    offered_.assign(features_.candidates.size(), true);
    if (options_.base_geometry) {
      // The textbook base frees the calibration's parameters from the start: only feature columns compete.
      for (std::size_t c = 0; c < features_.candidates.size(); ++c) {
        if (features_.candidates[c].columns.cols() == 0) offered_[c] = false;
      }
    }
    result_.candidates = static_cast<int>(features_.candidates.size());
  }

  double noiseFloor() const {
    if (options_.noise_floor > 0.0) return options_.noise_floor;
    double sigma = campaign_.position_noise;
    for (const auto& h : heldout_) sigma = std::max(sigma, h.position_noise);
    return std::sqrt(3.0) * sigma;  // 3-D RMS of the instrument noise
  }

  // The calibration options of a refit: the user's, with what discovery has not released fixed (and the
  // instrument's scale fitted only once its candidate is accepted).
  GeometricCalibrationOptions calibrationOptions() const {
    GeometricCalibrationOptions cal_options = options_.calibration;
    const int dof = prior_.robot().dof();
    cal_options.fixed = fixedNames(names_, released_, options_, dof);
    cal_options.fit_instrument_scale = released_.count(GeometricParameterLayout(dof).instrumentScale()) > 0;
    return cal_options;
  }

  GeometricCalibrationResult calibrate(const JointErrorModel& model) {
    return calibrateGeometry(model, fitted_, setup_of_campaign_, calibrationOptions());
  }

  // The fitted rows as `model` predicts them: the campaigns' concatenation, each row with its set-up.
  CalibrationData fittedRows(const JointErrorModel& model) const {
    CalibrationData data = prepareCalibrationData(model, campaign_);
    assignCampaigns(data, fitted_, setup_of_campaign_);
    return data;
  }

  // Errors on the fitted rows, on every held-out campaign (frame re-fitted) and the paths' Ra and Rz.
  DiscoveryState evaluate(double cv_sse) const {
    DiscoveryState state;
    state.fitted = cal_.after;
    if (fitted_path_) {
      const CalibrationData data = fittedRows(model_);
      const std::vector<double> z = zErrors(model_, cal_.estimate, data);
      for (std::size_t c = 0; c < fitted_.size(); ++c) {
        if (!isPathCampaign(fitted_[c])) continue;
        std::vector<double> part;
        for (std::size_t i = 0; i < z.size(); ++i) {
          const std::size_t row = static_cast<std::size_t>(data.row[i]);
          if (row >= first_row_[c] && row < first_row_[c + 1]) part.push_back(z[i]);
        }
        state.paths.push_back(roughness(part, false, static_cast<int>(c)));
      }
    }
    const GeometricCalibrationOptions cal_options = calibrationOptions();
    for (std::size_t k = 0; k < heldout_.size(); ++k) {
      const HoldoutEvaluation e = evaluateOnCampaign(model_, cal_.estimate, heldout_[k], true, cal_options);
      state.heldout.push_back(e.statistics);
      if (isPathCampaign(heldout_[k])) {
        state.paths.push_back(roughness(zErrors(model_, e.parameters, prepareCalibrationData(model_, heldout_[k])),
                                        true, static_cast<int>(k)));
      }
    }
    state.cv_rms = std::sqrt(cv_sse / std::max(1, residuals_));
    return state;
  }

  // The candidate to accept. It must lower the time-blocked CV error by min_cv_gain and the extended BIC,
  // and it must transfer: predicted from the other folds, it may not make any fold (a block of consecutive
  // rows, far from the others in time) worse by more than kFoldHurt of that fold's error; a term that helps
  // one part of the data and hurts another fits the data, not the robot. Of the candidates whose CV error
  // is statistically tied with the best one (the difference within one standard error of the fold-wise
  // differences, or within a quarter of the required gain), the one with the fewest parameters wins: an
  // offset rather than the joint's whole placement.
  Choice choose() const {
    Choice choice;
    for (std::size_t c = 0; c < features_.candidates.size(); ++c)
      choice.tried += offered_[c] && !lin_.candidate_columns[c].empty();
    if (choice.tried == 0) return choice;
    const double log_n = std::log(static_cast<double>(residuals_));
    const double penalty_m = 2.0 * std::log(static_cast<double>(choice.tried));
    double runner_cv = std::numeric_limits<double>::infinity();
    double rejected_cv = std::numeric_limits<double>::infinity();
    struct Passing {
      int index;
      Fit fit;
      double dbic;
      int added;
      double prior_weight;
    };
    std::vector<Passing> passing;
    for (std::size_t c = 0; c < features_.candidates.size(); ++c) {
      if (!offered_[c] || lin_.candidate_columns[c].empty()) continue;
      const DiscoveryCandidate& candidate = features_.candidates[c];
      std::vector<int> s = current_;
      s.insert(s.end(), lin_.candidate_columns[c].begin(), lin_.candidate_columns[c].end());
      // A candidate with a prior is fitted at each of its weights; cross-validation on the fitted data
      // picks the weight (the best one that transfers, else the best one).
      const std::vector<int> own(lin_.candidate_columns[c].begin(),
                                 lin_.candidate_columns[c].begin() + candidate.coefficients(prior_.robot().dof()));
      Fit fit;
      double weight = 0.0;
      bool gains = false;
      std::string hurt;
      bool have = false;
      for (const double w : candidate.prior.size() > 0 ? priorWeights() : std::vector<double>{0.0}) {
        Penalty penalty = activePenalty(s);
        addPrior(lin_, s, own, candidate.prior, w, Eigen::VectorXd(), penalty);
        Fit trial = fitColumns(lin_, s, false, penalty);
        const int trial_added = trial.rank - base_fit_.rank;
        if (trial_added <= 0 || trial.rss <= 0.0 || base_fit_.rss <= 0.0) continue;
        const double trial_dbic = residuals_ * std::log(trial.rss / base_fit_.rss) + trial_added * log_n + penalty_m;
        const bool trial_gains = trial.cv < base_fit_.cv * (1.0 - options_.min_cv_gain) && trial_dbic < 0.0;
        const std::string trial_hurt = trial_gains ? hurtFold(trial) : std::string();
        const bool passes = trial_gains && trial_hurt.empty();
        const bool passed = gains && hurt.empty();
        if (!have || (passes && !passed) || (passes == passed && transferError(trial) < transferError(fit))) {
          fit = trial;
          weight = w;
          gains = trial_gains;
          hurt = trial_hurt;
          have = true;
        }
      }
      if (!have) continue;
      const int added = fit.rank - base_fit_.rank;
      const double dbic = residuals_ * std::log(fit.rss / base_fit_.rss) + added * log_n + penalty_m;
      if (gains && hurt.empty()) {
        passing.push_back({static_cast<int>(c), fit, dbic, added, weight});
        continue;
      }
      if (gains && fit.cv < rejected_cv) {
        rejected_cv = fit.cv;
        choice.rejected = features_.candidates[c].label() + ": " + hurt;
      }
      if (fit.cv < runner_cv) {
        runner_cv = fit.cv;
        choice.runner_up = features_.candidates[c].label();
      }
    }
    const Passing* best = nullptr;
    for (const Passing& p : passing) {
      if (!best || p.fit.cv < best->fit.cv) best = &p;
    }
    const Passing* chosen = nullptr;
    for (const Passing& p : passing) {
      if (!tied(p.fit, best->fit)) continue;
      if (!chosen || p.added < chosen->added || (p.added == chosen->added && p.fit.cv < chosen->fit.cv)) chosen = &p;
    }
    if (!chosen) return choice;
    choice.index = chosen->index;
    choice.fit = chosen->fit;
    choice.prior_weight = chosen->prior_weight;
    choice.dbic = chosen->dbic;
    for (const Passing& p : passing) {
      if (&p != chosen && p.fit.cv < runner_cv) {
        runner_cv = p.fit.cv;
        choice.runner_up = features_.candidates[static_cast<std::size_t>(p.index)].label();
      }
    }
    return choice;
  }

  // Empty when the candidate's fit, predicted from the other parts, lowers or keeps the error of every
  // time fold and every joint-space part; else which part it hurts.
  std::string hurtFold(const Fit& fit) const {
    auto check = [&](const std::vector<double>& after, const std::vector<double>& before, const char* kind) {
      for (std::size_t p = 0; p < after.size() && p < before.size(); ++p) {
        if (after[p] <= before[p] * (1.0 + kFoldHurt)) continue;
        char text[200];
        std::snprintf(text, sizeof(text), "CV error %+.1f %% overall but %+.1f %% on %s %zu of %zu",
                      100.0 * (fit.cv / base_fit_.cv - 1.0), 100.0 * (after[p] / before[p] - 1.0), kind, p + 1,
                      after.size());
        return std::string(text);
      }
      return std::string();
    };
    std::string hurt = check(fit.cv_fold, base_fit_.cv_fold, "time block");
    return hurt.empty() ? check(fit.cv_space, base_fit_.cv_space, "joint-space part") : hurt;
  }

  // Whether `fit`'s CV error is statistically tied with `best`'s: within one standard error of the
  // fold-wise differences, or within a quarter of the gain a step must bring.
  bool tied(const Fit& fit, const Fit& best) const {
    const double margin = best.cv * 0.25 * options_.min_cv_gain;
    const std::size_t folds = fit.cv_fold.size();
    double mean = 0.0, square = 0.0;
    for (std::size_t fo = 0; fo < folds; ++fo) {
      const double d = fit.cv_fold[fo] - best.cv_fold[fo];
      mean += d;
      square += d * d;
    }
    mean /= static_cast<double>(folds);
    const double variance = folds > 1 ? (square - folds * mean * mean) / static_cast<double>(folds - 1) : 0.0;
    const double standard_error_of_sum = std::sqrt(std::max(0.0, variance) * static_cast<double>(folds));
    return fit.cv - best.cv <= std::max(margin, standard_error_of_sum);
  }

  // Adds the step's solution for the active and the chosen candidate's coefficients (the freed geometry
  // is refitted by the calibration).
  void acceptCoefficients(const Choice& choice) {
    const DiscoveryCandidate& chosen = features_.candidates[static_cast<std::size_t>(choice.index)];
    const int coefficients = chosen.coefficients(prior_.robot().dof());
    if (coefficients == 0) return;
    std::vector<int> s = current_;
    const std::vector<int>& added = lin_.candidate_columns[static_cast<std::size_t>(choice.index)];
    s.insert(s.end(), added.begin(), added.end());
    std::size_t pos = current_.size() - lin_.active_columns.size();
    for (Active& a : active_) {
      for (int k = 0; k < a.theta.size(); ++k, ++pos)
        a.theta[k] += choice.fit.d[static_cast<int>(pos)] / lin_.scale[s[pos]];
    }
    Active fresh{choice.index, Eigen::VectorXd::Zero(coefficients), Eigen::VectorXd::Zero(coefficients),
                 choice.prior_weight};
    for (int k = 0; k < coefficients; ++k, ++pos)
      fresh.theta[k] = choice.fit.d[static_cast<int>(pos)] / lin_.scale[s[pos]];
    active_.push_back(fresh);
  }

  // Refits everything together: calibrates the base with the effects fixed, then a joint Gauss-Newton step
  // of the effects' coefficients with the base; then the final model of the step and its uncertainties.
  void refit() {
    const std::vector<bool> none(features_.candidates.size(), false);
    for (int it = 0; it < options_.refit_iterations; ++it) {
      model_ = buildModel(prior_, active_, features_, data_, options_);
      cal_ = calibrate(model_);
      if (active_.empty()) break;
      lin_ = linearise(model_, fittedRows(model_), cal_, features_, active_, none, options_.folds, false);
      std::vector<int> s = lin_.base_columns;
      s.insert(s.end(), lin_.active_columns.begin(), lin_.active_columns.end());
      const Fit fit = fitColumns(lin_, s, false, activePenalty(s));
      std::size_t pos = lin_.base_columns.size();
      for (Active& a : active_) {
        for (int k = 0; k < a.theta.size(); ++k, ++pos) a.theta[k] += fit.d[static_cast<int>(pos)] / lin_.scale[s[pos]];
      }
    }
    model_ = buildModel(prior_, active_, features_, data_, options_);
    cal_ = calibrate(model_);
    lin_ = linearise(model_, fittedRows(model_), cal_, features_, active_, offered_, options_.folds, false);
    current_ = lin_.base_columns;
    current_.insert(current_.end(), lin_.active_columns.begin(), lin_.active_columns.end());
    base_fit_ = fitColumns(lin_, current_, true, activePenalty(current_));
    // Uncertainties of the effects' parameters: sigma^2 (X^T X)^-1, unscaled.
    const double sigma2 = base_fit_.rss / std::max(1, residuals_ - base_fit_.rank);
    std::size_t pos = lin_.base_columns.size();
    for (Active& a : active_) {
      for (int k = 0; k < a.theta.size(); ++k, ++pos) {
        const double variance = sigma2 * base_fit_.inverse(static_cast<int>(pos), static_cast<int>(pos));
        a.sigma[k] = std::sqrt(std::max(0.0, variance)) / lin_.scale[current_[pos]];
      }
    }
  }

  // The calibration's estimates of the given layout parameters, where identified.
  void appendCalibrationEstimates(const std::vector<int>& indices, std::vector<NamedEstimate>& out) const {
    for (int idx : indices) {
      for (const ParameterEstimate& p : cal_.parameters) {
        if (p.name == names_[static_cast<std::size_t>(idx)] && p.identified) out.push_back({p.name, p.value, p.sigma});
      }
    }
  }

  // One step: choose, accept, refit, record. False when discovery stops.
  bool takeStep() {
    const Choice choice = choose();
    if (choice.tried == 0) {
      result_.stop_reason = "no candidate left";
      return false;
    }
    if (choice.index < 0) {
      result_.stop_reason = "no candidate lowers the cross-validated error and the BIC on every part of the data";
      result_.rejected_at_stop = choice.rejected;
      return false;
    }
    const std::size_t best = static_cast<std::size_t>(choice.index);
    const DiscoveryCandidate& chosen = features_.candidates[best];
    offered_[best] = false;
    DiscoveryStep record;
    record.type = chosen.type;
    record.joint = chosen.joint;
    record.joint_name =
        chosen.joint >= 0 ? prior_.robot().joints[static_cast<std::size_t>(chosen.joint)].name : std::string();
    record.stage = chosen.stage;
    record.part = chosen.part;
    record.cycles = chosen.cycles;
    record.detail = chosen.detail;
    record.report_fields = chosen.report_fields;
    if (chosen.prior.size() > 0) record.report_fields["prior_weight"] = choice.prior_weight;
    record.cv_rms_before = std::sqrt(base_fit_.cv / residuals_);
    record.cv_rms_after = std::sqrt(choice.fit.cv / residuals_);
    record.delta_bic = choice.dbic;
    record.candidates_tried = choice.tried;
    record.runner_up = choice.runner_up;
    record.rejected = choice.rejected;
    record.before = state_;

    std::vector<int> newly_released;  // calibration parameters this step frees
    const std::set<int> free_before(cal_.free.begin(), cal_.free.end());
    for (int idx : features_.releases[best]) {
      if (!free_before.count(idx)) newly_released.push_back(idx);
      released_.insert(idx);
    }
    acceptCoefficients(choice);
    refit();
    state_ = evaluate(base_fit_.cv);
    record.after = state_;
    if (chosen.columns.cols() == 0) {
      appendCalibrationEstimates(features_.releases[best], record.parameters);
    } else {
      const Active& a = active_.back();
      record.parameters = features_.family[best]->describe({&chosen, a.theta, a.sigma}, model_);
      appendCalibrationEstimates(newly_released, record.parameters);
    }
    result_.steps.push_back(record);
    return true;
  }

  // The joint-space residual and the calibrated model.
  void finish() {
    lin_ = linearise(model_, fittedRows(model_), cal_, features_, active_,
                     std::vector<bool>(features_.candidates.size(), false), options_.folds, true);
    result_.joint_residual_rms_final = jointRms(lin_);
    // Where what is left lies (reported when it is well above the noise floor).
    const ResidualRows rows{lin_.joint_residual, lin_.joint_lever, data_.command, data_.motor,
                            lin_.residual_norm,  lin_.fold,        lin_.residual, data_.time};
    result_.unexplained = analyseUnexplained(prior_.robot(), rows, cal_.after.rms, result_.noise_floor);
    result_.final_state = state_;
    result_.fitted_rows = cal_.used_rows;
    std::vector<std::string> left_out;
    const Robot& robot = prior_.robot();
    result_.model = calibratedJointErrorModel(
        model_, std::make_shared<const Robot>(correctedRobot(robot, cal_.estimate)), cal_, left_out);
    result_.calibration = cal_;
  }

  const JointErrorModel& prior_;
  const std::vector<MeasurementCampaign>& fitted_;
  const std::vector<int> setup_of_campaign_;  // instrument set-up of each fitted campaign
  const std::vector<MeasurementCampaign>& heldout_;
  const DiscoveryOptions& options_;
  const MeasurementCampaign campaign_;
  const std::vector<std::string> names_;
  DiscoveryData data_;
  Features features_;
  std::vector<std::size_t> first_row_;  // each fitted campaign's first row in the concatenation, and the end
  bool fitted_path_ = false;
  std::vector<bool> offered_;
  std::set<int> released_;
  std::vector<Active> active_;
  JointErrorModel model_;
  GeometricCalibrationResult cal_;
  Linearised lin_;
  int residuals_ = 0;
  std::vector<int> current_;
  Fit base_fit_;
  DiscoveryState state_;
  DiscoveryResult result_;
};

}  // namespace

DiscoveryResult discoverEffects(const JointErrorModel& prior, const std::vector<MeasurementCampaign>& fitted,
                                const std::vector<MeasurementCampaign>& heldout, const DiscoveryOptions& options) {
  if (options.folds < 2) throw InvalidArgument("discover: folds must be at least 2");
  if (!std::isfinite(options.max_prior_weight) || options.max_prior_weight < 0.0) {
    throw InvalidArgument("discover: max_prior_weight is " + std::to_string(options.max_prior_weight) +
                          "; it must be finite and >= 0 (0: no prior)");
  }
  if (fitted.empty()) throw InvalidArgument("discover: no fitted campaign");
  // Fitted campaigns from several tracker set-ups are fitted together, each set-up with its own frame.
  const std::vector<int> setups =
      fitted.size() == 1 ? std::vector<int>{0} : instrumentSetUps(prior, fitted, options.calibration).setup_of_campaign;
  return DiscoveryRun(prior, fitted, setups, heldout, options).run();
}

}  // namespace jointcomp
