#include "model/identify/discovery.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <set>

#include "model/common/errors.hpp"
#include "model/effects/backlash.hpp"
#include "model/effects/compliance.hpp"
#include "model/effects/hysteresis.hpp"
#include "model/effects/joint_offset.hpp"
#include "model/effects/nonlinear_compliance.hpp"
#include "model/effects/payload.hpp"
#include "model/effects/thermal_drift.hpp"
#include "model/effects/transmission_error.hpp"
#include "model/compensation/metrics.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct Candidate {
  std::string type;
  int joint = 0;
  int stage = 0;
  std::string part;
  double cycles = 0.0;
  // Layout indices (offset, compliance, geometric) the candidate releases; with feature columns too
  // (thermal), those come first.
  std::vector<int> geometric;
  int feature = -1;            // first feature column (effect candidates)
  int features = 0;
  // false: feature k is one column, the error of `joint` per unit parameter. true (payload): feature k is
  // a block of dof columns, the load torque of every joint per unit parameter, which enters through the
  // current compliances (dq_j = -compliance_j * tau_j).
  bool through_compliance = false;
  std::string label() const {
    if (through_compliance) return type + " (tool)";
    std::string s = type + " joint " + std::to_string(joint + 1);
    if (type == "harmonic") s += " " + part + " order " + std::to_string(static_cast<int>(cycles));
    if (type == "thermal") s += " (" + part + ")";
    return s;
  }
};

struct Active {
  Candidate candidate;
  Eigen::VectorXd theta;
  Eigen::VectorXd sigma;
};

bool wanted(const DiscoveryOptions& options, const std::string& type) {
  return options.types.empty() || std::find(options.types.begin(), options.types.end(), type) != options.types.end();
}

// Feature values of every effect candidate for every used row (rows x columns).
struct Features {
  Eigen::MatrixXd values;
  std::vector<Candidate> candidates;
  double t0 = 0.0, temperature0 = 20.0;
};

Features buildFeatures(const JointErrorModel& prior, const MeasurementCampaign& campaign, const CalibrationData& data,
                       const DiscoveryOptions& options) {
  const Robot& robot = prior.robot();
  const GearTrain& gears = prior.gears();
  const int n = robot.dof();
  const int rows = static_cast<int>(data.size());
  Features f;
  GeometricParameterLayout layout(n);
  // Temperature present?
  double tsum = 0.0;
  int tcount = 0;
  for (int i = 0; i < rows; ++i) {
    const std::size_t k = static_cast<std::size_t>(data.row[i]);
    if (k < campaign.temperature.size() && std::isfinite(campaign.temperature[k])) {
      tsum += campaign.temperature[k];
      ++tcount;
    }
  }
  const bool have_temperature = tcount == rows && rows > 0;
  f.temperature0 = have_temperature ? tsum / tcount : 20.0;
  f.t0 = campaign.time.empty() ? 0.0 : campaign.time.front();

  std::vector<std::vector<double>> columns;
  auto addColumn = [&](std::vector<double> c) {
    columns.push_back(std::move(c));
    return static_cast<int>(columns.size()) - 1;
  };
  std::vector<JointVector> motor(static_cast<std::size_t>(rows));
  std::vector<JointVector> velocity(static_cast<std::size_t>(rows));
  for (int i = 0; i < rows; ++i) {
    gears.motorAngles(data.command[i], motor[i]);
    const std::size_t k = static_cast<std::size_t>(data.row[i]);
    velocity[i] = JointVector::Zero(n);
    if (k > 0 && campaign.command[k - 1].allFinite()) {
      const double dt = campaign.time[k] > campaign.time[k - 1] ? campaign.time[k] - campaign.time[k - 1] : 1.0;
      velocity[i] = (campaign.command[k] - campaign.command[k - 1]) / dt;
    }
  }
  for (int j = 0; j < n; ++j) {
    if (wanted(options, "offset")) f.candidates.push_back({"offset", j, 0, "", 0.0, {layout.offset(j)}, -1, 0});
    if (wanted(options, "compliance") && data.torque_known) {
      f.candidates.push_back({"compliance", j, 0, "", 0.0, {layout.compliance(j)}, -1, 0});
    }
    if (wanted(options, "geometric")) {
      Candidate c{"geometric", j, 0, "", 0.0, {}, -1, 0};
      for (int k = 0; k < 6; ++k) c.geometric.push_back(layout.placement(j, k));
      f.candidates.push_back(c);
    }
    if (wanted(options, "nonlinear_compliance") && data.torque_known) {
      std::vector<double> c(static_cast<std::size_t>(rows));
      for (int i = 0; i < rows; ++i) c[i] = NonlinearComplianceEffect::feature(data.load_torque[i][j]);
      f.candidates.push_back({"nonlinear_compliance", j, 0, "", 0.0, {}, addColumn(std::move(c)), 1});
    }
    if (wanted(options, "backlash")) {
      std::vector<double> c(static_cast<std::size_t>(rows));
      for (int i = 0; i < rows; ++i) c[i] = BacklashEffect::feature(velocity[i][j], options.velocity_scale);
      f.candidates.push_back({"backlash", j, 0, "", 0.0, {}, addColumn(std::move(c)), 1});
    }
    if (wanted(options, "hysteresis") && data.torque_known) {
      std::vector<double> c(static_cast<std::size_t>(rows));
      for (int i = 0; i < rows; ++i) c[i] = HysteresisEffect::feature(velocity[i][j], data.load_torque[i][j], options.velocity_scale);
      f.candidates.push_back({"hysteresis", j, 0, "", 0.0, {}, addColumn(std::move(c)), 1});
    }
    if (wanted(options, "thermal")) {
      // With the joint's offset (when it is not free yet): a drift is known up to the zero it drifts
      // from, and the reference temperature or time of the feature is only the campaign's mean or start,
      // so the two variants compete on the shape of the drift alone.
      if (have_temperature) {
        std::vector<double> c(static_cast<std::size_t>(rows));
        for (int i = 0; i < rows; ++i) c[i] = campaign.temperature[static_cast<std::size_t>(data.row[i])] - f.temperature0;
        f.candidates.push_back({"thermal", j, 0, "temperature", 0.0, {layout.offset(j)}, addColumn(std::move(c)), 1});
      }
      std::vector<double> c(static_cast<std::size_t>(rows));
      for (int i = 0; i < rows; ++i) c[i] = campaign.time[static_cast<std::size_t>(data.row[i])] - f.t0;
      f.candidates.push_back({"thermal", j, 0, "time", 0.0, {layout.offset(j)}, addColumn(std::move(c)), 1});
    }
    if (wanted(options, "harmonic")) {
      std::vector<double> frequencies;  // cycles per joint revolution already offered
      std::vector<double> ratios;  // distinct parts only: the angle of a part is motor_j / ratio
      const int stages = gears.stageCount(j);
      for (int s = 1; s <= stages + 1; ++s) {
        // Ratio of the part's angle to the joint angle, from a unit joint move.
        JointVector unit = JointVector::Zero(n), m(n);
        unit[j] = 1.0;
        gears.motorAngles(unit, m);
        const double ratio = gears.stageInputAngle(j, s, m);
        bool seen = false;
        for (double r : ratios) seen = seen || std::abs(r - ratio) <= 1e-9 * std::max(1.0, std::abs(r));
        if (seen) continue;
        ratios.push_back(ratio);
        const std::string part = s == 1 ? "motor" : s == stages + 1 ? "output" : "stage_" + std::to_string(s);
        for (int order = 1; order <= options.max_harmonic_order; ++order) {
          // A part's order k at the frequency of an earlier part's order is the same column: skip it.
          const double frequency = std::abs(ratio) * order;
          bool duplicate = false;
          for (double fr : frequencies) duplicate = duplicate || std::abs(fr - frequency) <= 1e-9 * std::max(1.0, fr);
          if (duplicate) continue;
          frequencies.push_back(frequency);
          std::vector<double> cs(static_cast<std::size_t>(rows)), cc(static_cast<std::size_t>(rows));
          for (int i = 0; i < rows; ++i) {
            const double x = order * gears.stageInputAngle(j, s, motor[i]);
            cs[i] = std::sin(x);
            cc[i] = std::cos(x);
          }
          const int first = addColumn(std::move(cs));
          addColumn(std::move(cc));
          f.candidates.push_back({"harmonic", j, s, part, static_cast<double>(order), {}, first, 2});
        }
      }
    }
  }
  if (wanted(options, "payload") && data.torque_known) {
    // An undeclared mass m at c (tool frame): tau = -J_c^T (m g), linear in m and in m c, since
    // J_c = J_o - [R c]x J_w. Feature block k: d tau / d(m, m c_x, m c_y, m c_z) at the commanded pose.
    RobotWorkspace ws(robot);
    std::vector<std::vector<double>> block(static_cast<std::size_t>(4 * n), std::vector<double>(static_cast<std::size_t>(rows)));
    JointVector at_origin(n), at_unit(n);
    for (int i = 0; i < rows; ++i) {
      forwardKinematics(robot, ws, data.command[i]);
      at_origin.setZero();
      PayloadEffect::addTorque(robot, ws, 1.0, Eigen::Vector3d::Zero(), at_origin);
      for (int j = 0; j < n; ++j) block[static_cast<std::size_t>(j)][static_cast<std::size_t>(i)] = at_origin[j];
      for (int k = 0; k < 3; ++k) {
        at_unit.setZero();
        PayloadEffect::addTorque(robot, ws, 1.0, Eigen::Vector3d::Unit(k), at_unit);
        for (int j = 0; j < n; ++j) {
          block[static_cast<std::size_t>((k + 1) * n + j)][static_cast<std::size_t>(i)] = at_unit[j] - at_origin[j];
        }
      }
    }
    int first = -1;
    for (auto& c : block) {
      const int index = addColumn(std::move(c));
      if (first < 0) first = index;
    }
    Candidate c{"payload", -1, 0, "", 0.0, {}, first, 4};
    c.through_compliance = true;
    f.candidates.push_back(c);
  }
  f.values.resize(rows, static_cast<int>(columns.size()));
  for (std::size_t c = 0; c < columns.size(); ++c) {
    for (int i = 0; i < rows; ++i) f.values(i, static_cast<int>(c)) = columns[c][i];
  }
  return f;
}

// The model: prior plus the effects built from the active features.
JointErrorModel buildModel(const JointErrorModel& prior, const std::vector<Active>& active, const Features& f,
                           const DiscoveryOptions& options) {
  const Robot& robot = prior.robot();
  const std::size_t n = static_cast<std::size_t>(robot.dof());
  std::vector<double> backlash(n, 0.0), hysteresis(n, 0.0), cubic(n, 0.0), thermal(n, 0.0), drift(n, 0.0);
  bool has_backlash = false, has_hysteresis = false, has_cubic = false, has_thermal = false, has_payload = false;
  Eigen::Vector4d payload = Eigen::Vector4d::Zero();  // m, m c
  std::vector<Harmonic> harmonics;
  for (const Active& a : active) {
    const std::string& t = a.candidate.type;
    if (t == "payload") {
      payload += a.theta.head<4>();
      has_payload = true;
      continue;
    }
    const std::size_t j = static_cast<std::size_t>(a.candidate.joint);
    if (t == "backlash") { backlash[j] += a.theta[0]; has_backlash = true; }
    else if (t == "hysteresis") { hysteresis[j] += a.theta[0]; has_hysteresis = true; }
    else if (t == "nonlinear_compliance") { cubic[j] += a.theta[0]; has_cubic = true; }
    else if (t == "thermal") {
      (a.candidate.part == "time" ? drift : thermal)[j] += a.theta[0];
      has_thermal = true;
    } else if (t == "harmonic") {
      Harmonic h;
      h.joint = a.candidate.joint;
      h.stage = a.candidate.stage;
      h.cycles_per_revolution = a.candidate.cycles;
      // a sin x + b cos x = A sin(x + phi), A cos phi = a, A sin phi = b.
      h.amplitude_rad = std::hypot(a.theta[0], a.theta[1]);
      h.phase_rad = std::atan2(a.theta[1], a.theta[0]);
      harmonics.push_back(h);
    }
  }
  JointErrorModel model = prior;
  const std::string note = "found by jointcomp discover";
  if (has_backlash) {
    auto e = std::make_unique<BacklashEffect>(robot, backlash, options.velocity_scale);
    e->estimate_note = note;
    model.addEffect(std::move(e));
  }
  if (has_hysteresis) {
    auto e = std::make_unique<HysteresisEffect>(robot, hysteresis, options.velocity_scale);
    e->estimate_note = note;
    model.addEffect(std::move(e));
  }
  if (has_payload) {
    // c = (m c) / m; a mass too small to carry a centre is put at the tool origin.
    const Eigen::Vector3d com = std::abs(payload[0]) > 1e-9 ? Eigen::Vector3d(payload.tail<3>() / payload[0]) : Eigen::Vector3d::Zero();
    auto e = std::make_unique<PayloadEffect>(robot, payload[0], com);
    e->estimate_note = note;
    model.addEffect(std::move(e));
  }
  if (has_cubic) {
    auto e = std::make_unique<NonlinearComplianceEffect>(robot, cubic);
    e->estimate_note = note;
    model.addEffect(std::move(e));
  }
  if (has_thermal) {
    auto e = std::make_unique<ThermalDriftEffect>(robot, thermal, f.temperature0, drift, f.t0);
    e->estimate_note = note;
    model.addEffect(std::move(e));
  }
  if (!harmonics.empty()) {
    auto e = std::make_unique<TransmissionErrorEffect>(robot, prior.gears(), harmonics);
    e->estimate_note = note;
    model.addEffect(std::move(e));
  }
  return model;
}

// The linearised problem at a calibration: residuals and the columns of every parameter and candidate.
struct Linearised {
  Eigen::VectorXd r;       // weighted residuals, 3 per row
  Eigen::MatrixXd X;       // weighted, unit-norm columns
  Eigen::VectorXd scale;   // column norms (X_raw = X * scale)
  std::vector<int> fold;   // fold of each residual row block (per row)
  std::vector<Eigen::MatrixXd> gram;  // per fold X_f^T X_f
  std::vector<Eigen::VectorXd> xr;    // per fold X_f^T r_f
  std::vector<double> rr;             // per fold r_f^T r_f
  Eigen::MatrixXd gram_total;
  Eigen::VectorXd xr_total;
  double rr_total = 0.0;
  std::vector<int> base_columns, active_columns;            // indices into X
  std::vector<std::vector<int>> candidate_columns;          // per candidate, empty when not offered
  std::vector<std::vector<int>> active_of;                  // per active, its columns
  std::vector<std::vector<double>> joint_residual;          // per joint, per row (pinv mapping)
};

Linearised linearise(const JointErrorModel& model, const MeasurementCampaign& campaign,
                     const GeometricCalibrationResult& cal, const Features& f, const std::vector<Active>& active,
                     const std::vector<bool>& offered, int folds, bool map_joints) {
  const Robot& robot = model.robot();
  const int n = robot.dof();
  GeometricParameterLayout layout(n);
  const CalibrationData data = prepareCalibrationData(model, campaign);
  const int rows = static_cast<int>(data.size());
  Linearised lin;
  std::set<int> free(cal.free.begin(), cal.free.end());
  // Column plan.
  // kind 0: layout column; 1: feature column times dm/dq_j; 2: block of dof feature columns (load torques)
  // times -compliance_j dm/dq_j, summed over the joints.
  struct Source { int kind; int index; int joint; };
  std::vector<Source> plan;
  for (int idx : cal.free) { lin.base_columns.push_back(static_cast<int>(plan.size())); plan.push_back({0, idx, 0}); }
  for (const Active& a : active) {
    std::vector<int> cols;
    for (int c = 0; c < a.candidate.features; ++c) {
      cols.push_back(static_cast<int>(plan.size()));
      lin.active_columns.push_back(static_cast<int>(plan.size()));
      if (a.candidate.through_compliance) plan.push_back({2, a.candidate.feature + c * n, -1});
      else plan.push_back({1, a.candidate.feature + c, a.candidate.joint});
    }
    lin.active_of.push_back(cols);
  }
  lin.candidate_columns.resize(f.candidates.size());
  for (std::size_t c = 0; c < f.candidates.size(); ++c) {
    if (!offered[c]) continue;
    const Candidate& cand = f.candidates[c];
    for (int k = 0; k < cand.features; ++k) {
      lin.candidate_columns[c].push_back(static_cast<int>(plan.size()));
      if (cand.through_compliance) plan.push_back({2, cand.feature + k * n, -1});
      else plan.push_back({1, cand.feature + k, cand.joint});
    }
    for (int idx : cand.geometric) {
      if (free.count(idx)) continue;
      lin.candidate_columns[c].push_back(static_cast<int>(plan.size()));
      plan.push_back({0, idx, 0});
    }
  }
  const int cols = static_cast<int>(plan.size());
  lin.r.resize(3 * rows);
  lin.X.resize(3 * rows, cols);
  lin.fold.resize(static_cast<std::size_t>(rows));
  if (map_joints) lin.joint_residual.assign(static_cast<std::size_t>(n), std::vector<double>(static_cast<std::size_t>(rows)));
  Eigen::MatrixXd J;
  for (int i = 0; i < rows; ++i) {
    const Eigen::Vector3d m =
        predictMeasurement(robot, cal.estimate, data.command[i], data.load_torque[i], data.other_error[i], &J);
    const double w = std::sqrt(i < static_cast<int>(cal.weight.size()) ? cal.weight[i] : 1.0);
    lin.r.segment<3>(3 * i) = w * (m - data.measured[i]);
    for (int c = 0; c < cols; ++c) {
      const Source& s = plan[static_cast<std::size_t>(c)];
      if (s.kind == 0) lin.X.block<3, 1>(3 * i, c) = w * J.col(s.index);
      else if (s.kind == 1) lin.X.block<3, 1>(3 * i, c) = w * f.values(i, s.index) * J.col(layout.offset(s.joint));
      else {
        Eigen::Vector3d column = Eigen::Vector3d::Zero();
        for (int j = 0; j < n; ++j) column -= cal.estimate.compliance[j] * f.values(i, s.index + j) * J.col(layout.offset(j));
        lin.X.block<3, 1>(3 * i, c) = w * column;
      }
    }
    lin.fold[static_cast<std::size_t>(i)] = std::min(folds - 1, static_cast<int>(static_cast<long>(i) * folds / rows));
    if (map_joints) {
      Eigen::MatrixXd Jq(3, n);
      for (int j = 0; j < n; ++j) Jq.col(j) = J.col(layout.offset(j));
      const Eigen::VectorXd dq = Jq.completeOrthogonalDecomposition().solve(-(m - data.measured[i]));
      for (int j = 0; j < n; ++j) lin.joint_residual[static_cast<std::size_t>(j)][static_cast<std::size_t>(i)] = dq[j];
    }
  }
  lin.scale.resize(cols);
  for (int c = 0; c < cols; ++c) {
    const double norm = lin.X.col(c).norm();
    lin.scale[c] = norm > 0.0 ? norm : 1.0;
    lin.X.col(c) /= lin.scale[c];
  }
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
  double rss = 0.0;     // full-data residual sum of squares after the step
  double cv = 0.0;      // CV sum of squares
  int rank = 0;
  Eigen::VectorXd d;    // step (scaled columns), minimises |r + X d|
  Eigen::MatrixXd inverse;  // pseudo-inverse of the Gram matrix (scaled)
};

Eigen::VectorXd solve(const Eigen::MatrixXd& g, const Eigen::VectorXd& b, int* rank) {
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(g);
  qr.setThreshold(1e-10);
  if (rank) *rank = static_cast<int>(qr.rank());
  return qr.solve(b);
}

Fit fitColumns(const Linearised& lin, const std::vector<int>& s, bool need_inverse) {
  Fit fit;
  const Eigen::MatrixXd g = sub(lin.gram_total, s);
  const Eigen::VectorXd b = sub(lin.xr_total, s);
  fit.d = -solve(g, b, &fit.rank);
  fit.rss = std::max(0.0, lin.rr_total + 2.0 * fit.d.dot(b) + fit.d.dot(g * fit.d));
  for (std::size_t fo = 0; fo < lin.gram.size(); ++fo) {
    const Eigen::MatrixXd gf = sub(lin.gram[fo], s);
    const Eigen::VectorXd bf = sub(lin.xr[fo], s);
    const Eigen::VectorXd d = -solve(g - gf, b - bf, nullptr);
    fit.cv += std::max(0.0, lin.rr[fo] + 2.0 * d.dot(bf) + d.dot(gf * d));
  }
  if (need_inverse) fit.inverse = g.completeOrthogonalDecomposition().pseudoInverse();
  return fit;
}

std::vector<std::string> fixedNames(const std::vector<std::string>& names, const std::set<int>& released,
                                    const DiscoveryOptions& options, int dof) {
  std::vector<std::string> fixed = options.calibration.fixed;
  if (options.base_geometry) return fixed;
  GeometricParameterLayout layout(dof);
  for (int idx = 9; idx < layout.size(); ++idx) {
    if (!released.count(idx)) fixed.push_back(names[static_cast<std::size_t>(idx)]);
  }
  return fixed;
}

// Z errors (base frame, measured - predicted) of the rows of a campaign under given parameters, with the
// campaign row of each.
std::vector<double> zErrors(const JointErrorModel& model, const GeometricParameters& parameters,
                            const MeasurementCampaign& campaign, std::vector<int>& rows) {
  const CalibrationData data = prepareCalibrationData(model, campaign);
  const Eigen::Matrix3d base_from_instrument = parameters.instrumentFromBase().linear().transpose();
  std::vector<double> z;
  rows = data.row;
  for (std::size_t i = 0; i < data.size(); ++i) {
    const Eigen::Vector3d m =
        predictMeasurement(model.robot(), parameters, data.command[i], data.load_torque[i], data.other_error[i]);
    z.push_back((base_from_instrument * (data.measured[i] - m)).z());
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
  std::nth_element(steps.begin(), steps.begin() + static_cast<long>(steps.size() / 2), steps.end());
  const double median = steps[steps.size() / 2];
  return median > 0.0 && median <= 0.1;
}

const std::vector<std::string>& discoveryEffectTypes() {
  static const std::vector<std::string> types = {"offset",    "compliance", "nonlinear_compliance", "harmonic",
                                                 "backlash",  "hysteresis", "thermal",              "geometric",
                                                 "payload"};
  return types;
}

MeasurementCampaign concatenateCampaigns(const std::vector<MeasurementCampaign>& campaigns) {
  if (campaigns.empty()) throw InvalidArgument("discover: no fitted campaign");
  MeasurementCampaign all = campaigns.front();
  for (std::size_t c = 1; c < campaigns.size(); ++c) {
    const MeasurementCampaign& m = campaigns[c];
    if (m.dof != all.dof || m.frame != all.frame || !m.has_position) {
      throw InvalidArgument("discover: campaign '" + m.source + "' differs from '" + all.source +
                            "' in joints, frame or positions; fitted campaigns must share one instrument set-up");
    }
    const double shift = (all.time.empty() ? 0.0 : all.time.back() + 1.0) - (m.time.empty() ? 0.0 : m.time.front());
    for (std::size_t k = 0; k < m.size(); ++k) {
      all.time.push_back(m.time[k] + shift);
      all.command.push_back(m.command[k]);
      all.position.push_back(m.position[k]);
      all.temperature.push_back(k < m.temperature.size() ? m.temperature[k] : std::numeric_limits<double>::quiet_NaN());
      all.wrench.push_back(k < m.wrench.size() ? m.wrench[k] : Vector6::Zero());
      all.payload.push_back(k < m.payload.size() ? m.payload[k] : 0.0);
      if (all.has_measured_angles) {
        all.measured_angles.push_back(k < m.measured_angles.size() ? m.measured_angles[k]
                                                                    : JointVector::Constant(all.dof, std::numeric_limits<double>::quiet_NaN()));
      }
    }
    all.source += "+" + m.source;
  }
  return all;
}

DiscoveryResult discoverEffects(const JointErrorModel& prior, const std::vector<MeasurementCampaign>& fitted,
                                const std::vector<MeasurementCampaign>& heldout, const DiscoveryOptions& options) {
  if (options.folds < 2) throw InvalidArgument("discover: folds must be at least 2");
  const MeasurementCampaign campaign = concatenateCampaigns(fitted);
  const Robot& robot = prior.robot();
  const int n = robot.dof();
  const std::vector<std::string> names = geometricParameterNames(robot);
  GeometricParameterLayout layout(n);

  DiscoveryResult result(prior);
  // Noise floor: 3-D RMS of the instrument noise.
  if (options.noise_floor > 0.0) result.noise_floor = options.noise_floor;
  else {
    double sigma = campaign.position_noise;
    for (const auto& h : heldout) sigma = std::max(sigma, h.position_noise);
    result.noise_floor = std::sqrt(3.0) * sigma;
  }

  const CalibrationData data0 = prepareCalibrationData(prior, campaign);
  const Features features = buildFeatures(prior, campaign, data0, options);
  result.candidates = static_cast<int>(features.candidates.size());
  std::vector<bool> offered(features.candidates.size(), true);
  std::set<int> released;
  if (!options.base_geometry) {
    // The frame and target are the base.
  } else {
    for (std::size_t c = 0; c < features.candidates.size(); ++c) {
      if (features.candidates[c].features == 0) offered[c] = false;
    }
  }
  std::vector<Active> active;

  GeometricCalibrationOptions cal_options = options.calibration;
  auto calibrate = [&](const JointErrorModel& model) {
    cal_options.fixed = fixedNames(names, released, options, n);
    return calibrateGeometry(model, campaign, cal_options);
  };
  // Paths among the fitted campaigns: their rows in the concatenation.
  std::vector<std::size_t> first_row{0};
  bool fitted_path = false;
  for (const auto& c : fitted) {
    first_row.push_back(first_row.back() + c.size());
    fitted_path = fitted_path || isPathCampaign(c);
  }
  auto evaluate = [&](const JointErrorModel& model, const GeometricCalibrationResult& cal, double cv_sse,
                      int residuals) {
    DiscoveryState state;
    state.fitted = cal.after;
    if (fitted_path) {
      std::vector<int> rows;
      const std::vector<double> z = zErrors(model, cal.estimate, campaign, rows);
      for (std::size_t c = 0; c < fitted.size(); ++c) {
        if (!isPathCampaign(fitted[c])) continue;
        std::vector<double> part;
        for (std::size_t i = 0; i < z.size(); ++i) {
          const std::size_t row = static_cast<std::size_t>(rows[i]);
          if (row >= first_row[c] && row < first_row[c + 1]) part.push_back(z[i]);
        }
        state.paths.push_back(roughness(part, false, static_cast<int>(c)));
      }
    }
    for (std::size_t k = 0; k < heldout.size(); ++k) {
      const HoldoutEvaluation e = evaluateOnCampaign(model, cal.estimate, heldout[k], true, cal_options);
      state.heldout.push_back(e.statistics);
      if (isPathCampaign(heldout[k])) {
        std::vector<int> rows;
        state.paths.push_back(roughness(zErrors(model, e.parameters, heldout[k], rows), true, static_cast<int>(k)));
      }
    }
    state.cv_rms = std::sqrt(cv_sse / std::max(1, residuals));
    return state;
  };

  JointErrorModel model = prior;
  GeometricCalibrationResult cal = calibrate(model);
  Linearised lin = linearise(model, campaign, cal, features, active, offered, options.folds, true);
  result.joint_residual_rms_initial = jointRms(lin);
  const int residuals = static_cast<int>(lin.r.size());
  const double log_n = std::log(static_cast<double>(residuals));
  std::vector<int> current = lin.base_columns;
  Fit base_fit = fitColumns(lin, current, false);
  result.initial = evaluate(model, cal, base_fit.cv, residuals);
  DiscoveryState state = result.initial;
  result.stop_reason = "max_steps reached";

  for (int step = 0; step < options.max_steps; ++step) {
    int tried = 0;
    for (std::size_t c = 0; c < features.candidates.size(); ++c) tried += offered[c] && !lin.candidate_columns[c].empty();
    if (tried == 0) {
      result.stop_reason = "no candidate left";
      break;
    }
    const double penalty_m = 2.0 * std::log(static_cast<double>(tried));
    int best = -1;
    Fit best_fit;
    double best_dbic = 0.0;
    std::string runner_up;
    double runner_cv = std::numeric_limits<double>::infinity();
    struct Passing {
      int index;
      Fit fit;
      double dbic;
      int added;
    };
    std::vector<Passing> passing;
    for (std::size_t c = 0; c < features.candidates.size(); ++c) {
      if (!offered[c] || lin.candidate_columns[c].empty()) continue;
      std::vector<int> s = current;
      s.insert(s.end(), lin.candidate_columns[c].begin(), lin.candidate_columns[c].end());
      Fit fit = fitColumns(lin, s, false);
      const int added = fit.rank - base_fit.rank;
      if (added <= 0 || fit.rss <= 0.0 || base_fit.rss <= 0.0) continue;
      const double dbic = residuals * std::log(fit.rss / base_fit.rss) + added * log_n + penalty_m;
      if (fit.cv < base_fit.cv * (1.0 - options.min_cv_gain) && dbic < 0.0) {
        passing.push_back({static_cast<int>(c), fit, dbic, added});
      } else if (fit.cv < runner_cv) {
        runner_cv = fit.cv;
        runner_up = features.candidates[c].label();
      }
    }
    // Parsimony: of the passing candidates whose CV error is within a quarter of the required gain of the
    // best one, the one with the fewest parameters (an offset rather than the joint's whole placement).
    double best_cv = std::numeric_limits<double>::infinity();
    for (const Passing& p : passing) best_cv = std::min(best_cv, p.fit.cv);
    const Passing* chosen_passing = nullptr;
    for (const Passing& p : passing) {
      if (p.fit.cv > best_cv * (1.0 + 0.25 * options.min_cv_gain)) continue;
      if (!chosen_passing || p.added < chosen_passing->added ||
          (p.added == chosen_passing->added && p.fit.cv < chosen_passing->fit.cv)) {
        chosen_passing = &p;
      }
    }
    if (chosen_passing) {
      best = chosen_passing->index;
      best_fit = chosen_passing->fit;
      best_dbic = chosen_passing->dbic;
      for (const Passing& p : passing) {
        if (&p != chosen_passing && p.fit.cv < runner_cv) {
          runner_cv = p.fit.cv;
          runner_up = features.candidates[static_cast<std::size_t>(p.index)].label();
        }
      }
    }
    if (best < 0) {
      result.stop_reason = "no candidate lowers the cross-validated error and the BIC";
      break;
    }
    const Candidate& chosen = features.candidates[static_cast<std::size_t>(best)];
    offered[static_cast<std::size_t>(best)] = false;
    DiscoveryStep record;
    record.type = chosen.type;
    record.joint = chosen.joint;
    record.joint_name = chosen.joint >= 0 ? robot.joints[static_cast<std::size_t>(chosen.joint)].name : std::string();
    record.stage = chosen.stage;
    record.part = chosen.part;
    record.cycles = chosen.cycles;
    record.cv_rms_before = std::sqrt(base_fit.cv / residuals);
    record.cv_rms_after = std::sqrt(best_fit.cv / residuals);
    record.delta_bic = best_dbic;
    record.candidates_tried = tried;
    record.runner_up = runner_up;
    record.before = state;

    std::vector<int> newly_released;  // geometry this step frees (a thermal step's offset)
    {
      const std::set<int> free_before(cal.free.begin(), cal.free.end());
      for (int idx : chosen.geometric) {
        if (!free_before.count(idx)) newly_released.push_back(idx);
        released.insert(idx);
      }
    }
    if (chosen.features > 0) {
      // The step of the joint fit for the new and the active features (the released geometry is refitted
      // by the calibration below).
      std::vector<int> s = current;
      s.insert(s.end(), lin.candidate_columns[static_cast<std::size_t>(best)].begin(),
               lin.candidate_columns[static_cast<std::size_t>(best)].end());
      std::size_t pos = current.size() - lin.active_columns.size();
      for (Active& a : active) {
        for (int k = 0; k < a.theta.size(); ++k, ++pos) a.theta[k] += best_fit.d[static_cast<int>(pos)] / lin.scale[s[pos]];
      }
      Active added{chosen, Eigen::VectorXd::Zero(chosen.features), Eigen::VectorXd::Zero(chosen.features)};
      for (int k = 0; k < chosen.features; ++k, ++pos) added.theta[k] = best_fit.d[static_cast<int>(pos)] / lin.scale[s[pos]];
      active.push_back(added);
    }
    // Refit everything together: calibrate the base with the effects fixed, then a joint Gauss-Newton step.
    for (int it = 0; it < options.refit_iterations; ++it) {
      model = buildModel(prior, active, features, options);
      cal = calibrate(model);
      if (active.empty()) break;
      lin = linearise(model, campaign, cal, features, active, std::vector<bool>(features.candidates.size(), false),
                      options.folds, false);
      std::vector<int> s = lin.base_columns;
      s.insert(s.end(), lin.active_columns.begin(), lin.active_columns.end());
      const Fit fit = fitColumns(lin, s, false);
      std::size_t pos = lin.base_columns.size();
      for (Active& a : active) {
        for (int k = 0; k < a.theta.size(); ++k, ++pos) a.theta[k] += fit.d[static_cast<int>(pos)] / lin.scale[s[pos]];
      }
    }
    model = buildModel(prior, active, features, options);
    cal = calibrate(model);
    lin = linearise(model, campaign, cal, features, active, offered, options.folds, false);
    current = lin.base_columns;
    current.insert(current.end(), lin.active_columns.begin(), lin.active_columns.end());
    base_fit = fitColumns(lin, current, true);
    // Uncertainties of the effects' parameters: sigma^2 (X^T X)^-1, unscaled.
    const double sigma2 = base_fit.rss / std::max(1, residuals - base_fit.rank);
    std::size_t pos = lin.base_columns.size();
    for (Active& a : active) {
      for (int k = 0; k < a.theta.size(); ++k, ++pos) {
        a.sigma[k] = std::sqrt(std::max(0.0, sigma2 * base_fit.inverse(static_cast<int>(pos), static_cast<int>(pos)))) /
                     lin.scale[current[pos]];
      }
    }
    state = evaluate(model, cal, base_fit.cv, residuals);
    record.after = state;
    // Parameters of the accepted effect.
    if (chosen.features == 0) {
      for (int idx : chosen.geometric) {
        for (const ParameterEstimate& p : cal.parameters) {
          if (p.name == names[static_cast<std::size_t>(idx)] && p.identified) record.parameters.push_back({p.name, p.value, p.sigma});
        }
      }
    } else {
      const Active& a = active.back();
      const std::string& jn = record.joint_name;
      if (chosen.type == "backlash") record.parameters.push_back({jn + ".backlash_width_rad", a.theta[0], a.sigma[0]});
      else if (chosen.type == "hysteresis") record.parameters.push_back({jn + ".hysteresis_width_rad_per_nm", a.theta[0], a.sigma[0]});
      else if (chosen.type == "payload") {
        // The model's payload (every accepted payload step adds to it): m and c = (m c) / m, with the
        // first-order sigma of the ratio (the covariance of m and m c left out).
        const int index = model.findEffect(PayloadEffect::kType);
        const auto& effect = static_cast<const PayloadEffect&>(model.effect(index));
        const double m = effect.mass();
        record.parameters.push_back({"payload.mass_kg", m, a.sigma[0]});
        const char* axes[3] = {"x", "y", "z"};
        for (int k = 0; k < 3; ++k) {
          const double c = effect.centreOfMass()[k];
          const double sigma = std::abs(m) > 1e-9 ? std::hypot(a.sigma[k + 1], c * a.sigma[0]) / std::abs(m) : 0.0;
          record.parameters.push_back({std::string("payload.com_") + axes[k] + "_m", c, sigma});
        }
      }
      else if (chosen.type == "nonlinear_compliance") record.parameters.push_back({jn + ".cubic_compliance_rad_per_nm3", a.theta[0], a.sigma[0]});
      else if (chosen.type == "thermal") {
        record.parameters.push_back({jn + (chosen.part == "time" ? ".drift_rad_per_s" : ".thermal_rad_per_degc"), a.theta[0], a.sigma[0]});
        for (int idx : newly_released) {
          for (const ParameterEstimate& p : cal.parameters) {
            if (p.name == names[static_cast<std::size_t>(idx)] && p.identified) record.parameters.push_back({p.name, p.value, p.sigma});
          }
        }
      } else if (chosen.type == "harmonic") {
        const double amp = std::hypot(a.theta[0], a.theta[1]);
        const double amp_sigma = amp > 0.0 ? std::hypot(a.theta[0] * a.sigma[0], a.theta[1] * a.sigma[1]) / amp : a.sigma[0];
        record.parameters.push_back({jn + "." + chosen.part + ".harmonic_" + std::to_string(static_cast<int>(chosen.cycles)) + ".amplitude_rad", amp, amp_sigma});
        record.parameters.push_back({jn + "." + chosen.part + ".harmonic_" + std::to_string(static_cast<int>(chosen.cycles)) + ".phase_rad",
                                     std::atan2(a.theta[1], a.theta[0]), amp > 0.0 ? amp_sigma / amp : kPi});
      }
    }
    result.steps.push_back(record);
  }
  // Final: joint-space residual and the calibrated model.
  lin = linearise(model, campaign, cal, features, active, std::vector<bool>(features.candidates.size(), false), options.folds, true);
  result.joint_residual_rms_final = jointRms(lin);
  result.final_state = state;
  result.fitted_rows = cal.used_rows;
  std::vector<std::string> left_out;
  result.model = calibratedJointErrorModel(model, std::make_shared<const Robot>(correctedRobot(robot, cal.estimate)), cal, left_out);
  result.calibration = cal;
  return result;
}

}  // namespace jointcomp
