// The fit of the kinematic calibration (geometric_calibration.hpp): the starting point, the identifiable
// subset, Levenberg-Marquardt with the robust loss, the covariance, the held-out evaluation.
#include "model/identify/geometric_calibration.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>

#include "model/common/errors.hpp"
#include "model/common/median.hpp"
#include "model/common/random.hpp"
#include "model/effects/backlash.hpp"
#include "model/effects/compliance.hpp"
#include "model/effects/joint_offset.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {
namespace {

constexpr const char* kFixed = "fixed by request";

// Median of a chi distribution with 3 degrees of freedom: |r| of a 3-D normal residual of unit sigma per axis.
constexpr double kChi3Median = 1.5381722;

std::string fmt(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

// The least-squares problem over a subset of the parameters, the others held at `base`.
class CalibrationProblem {
public:
  CalibrationProblem(const Robot& robot, const CalibrationData& data, const Eigen::VectorXd& base,
                     std::vector<int> free)
      : robot_(robot), data_(data), base_(base), free_(std::move(free)), layout_(robot.dof(), data.setups) {}

  int residualCount() const { return 3 * static_cast<int>(data_.size()); }
  const std::vector<int>& freeIndices() const { return free_; }

  Eigen::VectorXd full(const Eigen::VectorXd& x) const {
    Eigen::VectorXd values = base_;
    for (std::size_t k = 0; k < free_.size(); ++k) values[free_[k]] = x[static_cast<Eigen::Index>(k)];
    return values;
  }
  Eigen::VectorXd start() const {
    Eigen::VectorXd x(static_cast<Eigen::Index>(free_.size()));
    for (std::size_t k = 0; k < free_.size(); ++k) x[static_cast<Eigen::Index>(k)] = base_[free_[k]];
    return x;
  }

  // Residuals (and the Jacobian of the free parameters) at the full parameter vector `values`.
  void evaluateFull(const Eigen::VectorXd& values, Eigen::VectorXd& residual, Eigen::MatrixXd* jacobian) const {
    const GeometricParameters parameters = GeometricParameters::fromVector(values, robot_.dof(), data_.setups);
    Eigen::MatrixXd block(3, layout_.size());
    for (std::size_t k = 0; k < data_.size(); ++k) {
      const Eigen::Vector3d predicted =
          predictMeasurement(robot_, parameters, data_.command[k], data_.load_torque[k], data_.other_error[k],
                             jacobian ? &block : nullptr, data_.setup[k]);
      const Eigen::Index row = 3 * static_cast<Eigen::Index>(k);
      residual.segment<3>(row) = predicted - data_.measured[k];
      if (jacobian) {
        for (std::size_t c = 0; c < free_.size(); ++c) {
          jacobian->block<3, 1>(row, static_cast<Eigen::Index>(c)) = block.col(free_[c]);
        }
      }
    }
  }
  void operator()(const Eigen::VectorXd& x, Eigen::VectorXd& residual, Eigen::MatrixXd* jacobian) const {
    evaluateFull(full(x), residual, jacobian);
  }

private:
  const Robot& robot_;
  const CalibrationData& data_;
  Eigen::VectorXd base_;
  std::vector<int> free_;
  GeometricParameterLayout layout_;
};

std::vector<double> rowNorms(const Eigen::VectorXd& residual) {
  std::vector<double> norms(static_cast<std::size_t>(residual.size() / 3));
  for (std::size_t k = 0; k < norms.size(); ++k)
    norms[k] = residual.segment<3>(3 * static_cast<Eigen::Index>(k)).norm();
  return norms;
}

struct FitOutcome {
  Eigen::VectorXd values;  // full parameter vector
  LevenbergMarquardtResult solver;
  double loss_scale = 0.0;
};

// Least squares, then (with a loss) the robust fit with a scale from the least-squares residuals (or the
// one given). Throws SolverError naming `what` when a stage does not converge.
FitOutcome fitSubset(const Robot& robot, const CalibrationData& data, const Eigen::VectorXd& start,
                     const std::vector<int>& free, const GeometricCalibrationOptions& options, double fixed_scale,
                     const std::string& what) {
  LevenbergMarquardtOptions solver = options.solver;
  solver.block_size = 3;
  solver.loss = RobustLoss::None;
  CalibrationProblem problem(robot, data, start, free);
  auto run = [&](const CalibrationProblem& p, LevenbergMarquardtOptions o) {
    if (options.progress) {
      const double residuals = static_cast<double>(p.residualCount());
      const bool robust = o.loss != RobustLoss::None;
      o.on_accepted_step = [&options, &data, &what, residuals, robust](int iterations, double cost) {
        report(options.progress, data.source + ": " + what + (robust ? " (robust)" : "") + ": iteration " +
                                     std::to_string(iterations) + ", RMS " +
                                     fmt("%.4f", std::sqrt(2.0 * cost / residuals) * 1e3) + " mm per axis");
      };
    }
    LevenbergMarquardtResult result = solveLevenbergMarquardt(std::cref(p), p.start(), p.residualCount(), o);
    if (!result.converged) {
      throw SolverError(data.source + ": " + what + ": Levenberg-Marquardt did not converge (" + result.stop_reason +
                        ", cost " + fmt("%.6g", result.cost) + " m^2 after " + std::to_string(result.iterations) +
                        " iterations)");
    }
    return result;
  };
  FitOutcome outcome;
  if (options.loss == RobustLoss::None) {
    outcome.solver = run(problem, solver);
    outcome.values = problem.full(outcome.solver.x);
    return outcome;
  }
  double scale = fixed_scale;
  Eigen::VectorXd values = start;
  if (!(scale > 0.0)) {
    LevenbergMarquardtResult least_squares = run(problem, solver);
    values = problem.full(least_squares.x);
    scale = options.loss_scale > 0.0
                ? options.loss_scale
                : options.loss_scale_sigmas * median(rowNorms(least_squares.residual)) / kChi3Median;
    if (!(scale > 0.0)) {  // exact data: nothing to be robust against
      outcome.solver = std::move(least_squares);
      outcome.values = values;
      return outcome;
    }
  }
  solver.loss = options.loss;
  solver.loss_scale = scale;
  CalibrationProblem robust(robot, data, values, free);
  outcome.solver = run(robust, solver);
  outcome.values = robust.full(outcome.solver.x);
  outcome.loss_scale = scale;
  return outcome;
}

int countBelow(const Eigen::VectorXd& weights, double limit) {
  int count = 0;
  for (Eigen::Index k = 0; k < weights.size(); ++k) count += weights[k] < limit ? 1 : 0;
  return count;
}

void checkPoses(const CalibrationData& data, const std::vector<Eigen::Vector3d>& points, const std::string& source) {
  bool same = true;
  for (std::size_t k = 1; k < data.size() && same; ++k) same = data.command[k] == data.command[0];
  if (same) {
    throw InvalidArgument(source + ": degenerate poses: all " + std::to_string(data.size()) +
                          " usable rows command the same joint positions; a calibration needs poses spread over "
                          "the workspace");
  }
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : points) scatter += (p - mean) * (p - mean).transpose();
  scatter /= static_cast<double>(points.size());
  const Eigen::Vector3d spread = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvalues();
  if (spread[1] < 1e-12) {  // second principal spread below 1 um
    throw InvalidArgument(source + ": degenerate poses: the " + std::to_string(points.size()) +
                          " target points lie on one line (or one point); the instrument frame cannot be fixed");
  }
}

}  // namespace

namespace {

std::vector<Eigen::Vector3d> basePoints(const Robot& robot, const GeometricParameters& parameters,
                                        const CalibrationData& data) {
  GeometricParameters in_base = parameters.ofSetUp(0);
  in_base.frame_translation.setZero();
  in_base.frame_rotation.setZero();
  std::vector<Eigen::Vector3d> points;
  points.reserve(data.size());
  for (std::size_t k = 0; k < data.size(); ++k) {
    points.push_back(predictMeasurement(robot, in_base, data.command[k], data.load_torque[k], data.other_error[k]));
  }
  return points;
}

std::vector<int> frameIndices(const GeometricParameterLayout& layout) {
  std::vector<int> indices;
  for (int s = 0; s < layout.setups; ++s) {
    for (int k = 0; k < 6; ++k) indices.push_back(layout.frame(s) + k);
  }
  return indices;
}

// The rows of one set-up.
CalibrationData setUpRows(const CalibrationData& data, int setup) {
  CalibrationData rows;
  rows.source = data.source;
  rows.torque_known = data.torque_known;
  for (std::size_t k = 0; k < data.size(); ++k) {
    if (data.setup[k] != setup) continue;
    rows.row.push_back(data.row[k]);
    rows.command.push_back(data.command[k]);
    rows.load_torque.push_back(data.load_torque[k]);
    rows.approach.push_back(data.approach[k]);
    rows.other_error.push_back(data.other_error[k]);
    rows.measured.push_back(data.measured[k]);
    rows.setup.push_back(0);
    rows.campaign.push_back(data.campaign[k]);
  }
  return rows;
}

}  // namespace

// ---- calibration -------------------------------------------------------------------------------------

namespace {

// What the calibration may free and why each parameter it does not free is fixed.
struct ParameterChoice {
  std::vector<int> candidates, priority;  // layout indices offered to the identifiability analysis
  std::vector<double> typical;            // their typical changes (scaling)
  std::vector<std::string> reason;        // per parameter: why it is not free
  std::vector<double> pivot;              // per parameter: its relative pivot
  std::vector<std::vector<std::pair<std::string, double>>> redundant;
  std::vector<int> free;  // the identifiable subset
};

// The start: the nominal robot, its frame from the closed-form rigid fit, then fitted robustly like the
// calibration ("before"). Fills the result's nominal and its errors before the calibration.
GeometricParameters startingPoint(const JointErrorModel& prior, const MeasurementCampaign& campaign,
                                  const CalibrationData& data, const GeometricCalibrationOptions& options,
                                  bool fit_frame, const std::vector<std::string>& setup_sources,
                                  GeometricCalibrationResult& result) {
  const Robot& robot = prior.robot();
  const int n = robot.dof();
  const int rows = static_cast<int>(data.size());
  GeometricParameters start = nominalParameters(prior, campaign);
  start.other_setups.resize(static_cast<std::size_t>(data.setups - 1));
  // Each set-up's frame from the closed-form rigid fit of its own rows.
  for (int s = 0; s < data.setups; ++s) {
    const CalibrationData own = setUpRows(data, s);
    const std::string& source = setup_sources[static_cast<std::size_t>(s)];
    if (own.size() < 3) {
      throw InvalidArgument(source + ": too few points: " + std::to_string(own.size()) +
                            " usable rows; an instrument set-up needs at least 3 to fix its frame");
    }
    const std::vector<Eigen::Vector3d> points = basePoints(robot, start, own);
    checkPoses(own, points, source);
    if (!fit_frame || (s == 0 && campaign.has_base_frame)) continue;  // a known base frame is the start
    GeometricParameters single = start.ofSetUp(s);
    single.setInstrumentFromBase(fitRigidTransform(points, own.measured));
    start.setSetUp(s, single);
  }

  // "Before": the nominal robot with only its frames fitted (robustly, like the calibration).
  std::vector<int> frames = frameIndices(GeometricParameterLayout(n, data.setups));
  if (baseFrameKept(options)) frames.erase(frames.begin(), frames.begin() + 6);  // set-up 0's: kept as given
  if (fit_frame && !frames.empty()) {
    const FitOutcome frame_fit = fitSubset(robot, data, start.toVector(), frames, options, 0.0,
                                           "fitting the instrument frame of the nominal robot");
    start = GeometricParameters::fromVector(frame_fit.values, n, data.setups);
  }
  result.nominal = start;
  result.nominal_frame_fit = start;
  {
    Eigen::VectorXd residual(3 * rows);
    CalibrationProblem(robot, data, start.toVector(), {}).evaluateFull(start.toVector(), residual, nullptr);
    result.error_before = rowNorms(residual);
    result.before = errorStatistics(result.error_before);
  }

  return start;
}

// Candidates and their priorities; user-fixed and disabled groups take no part.
ParameterChoice candidateParameters(const Robot& robot, const CalibrationData& data,
                                    const GeometricCalibrationOptions& options, bool fit_frame,
                                    const GeometricCalibrationResult& result, const std::string& source) {
  const GeometricParameterLayout layout(robot.dof(), data.setups);
  ParameterChoice choice;
  std::vector<int>& candidates = choice.candidates;
  std::vector<int>& priority = choice.priority;
  std::vector<double>& typical = choice.typical;
  std::vector<std::string>& reason = choice.reason;
  std::set<std::string> user_fixed(options.fixed.begin(), options.fixed.end());
  for (const std::string& name : user_fixed) {
    if (std::find(result.names.begin(), result.names.end(), name) == result.names.end()) {
      throw InvalidArgument(source + ": cannot fix '" + name + "': no such calibration parameter");
    }
  }
  reason.resize(result.names.size());
  for (int i = 0; i < layout.size(); ++i) {
    const std::string& name = result.names[static_cast<std::size_t>(i)];
    int group;
    bool enabled;
    double change;
    if (layout.isFrame(i)) {
      group = 0, enabled = fit_frame, change = 1e-3;  // m for the translations, rad for the rotations
      if (!fit_frame) reason[static_cast<std::size_t>(i)] = "the campaign is in the base frame: no frame to fit";
    } else if (layout.isInstrumentScale(i)) {
      group = 1, enabled = options.fit_instrument_scale, change = 1e-5;  // with the frame and target
      if (!enabled) reason[static_cast<std::size_t>(i)] = "an instrument property: fitted only when asked";
    } else if (i < 9) {
      group = 1, enabled = options.fit_target, change = 1e-3;
    } else if (i < layout.placement(0, 0)) {
      group = 2, enabled = options.fit_offsets, change = 1e-3;
    } else if (i < layout.compliance(0)) {
      const int k = (i - layout.placement(0, 0)) % 6;
      group = k < 3 ? 3 : 4, enabled = options.fit_placements, change = 1e-3;
    } else {
      group = 5, enabled = options.fit_compliance && data.torque_known, change = 1e-6;
      if (!data.torque_known) {
        reason[static_cast<std::size_t>(i)] = "robot '" + robot.name + "' has a link without inertial (" +
                                              robot.link_without_inertial + "): no load torque, no compliance";
      }
    }
    if (user_fixed.count(name)) {
      reason[static_cast<std::size_t>(i)] = kFixed;
      continue;
    }
    if (!enabled) {
      if (reason[static_cast<std::size_t>(i)].empty()) reason[static_cast<std::size_t>(i)] = "not fitted (option)";
      continue;
    }
    candidates.push_back(i);
    priority.push_back(group);
    typical.push_back(change);
  }
  if (candidates.empty()) throw InvalidArgument(source + ": no calibration parameter is free");

  return choice;
}

// Identifiability at the start point: the free subset, the others with their reason; throws for a frame
// that cannot be identified or too few rows for the free parameters.
void chooseIdentifiable(const Robot& robot, const CalibrationData& data, const GeometricParameters& start,
                        const GeometricCalibrationOptions& options, bool fit_frame, GeometricCalibrationResult& result,
                        ParameterChoice& choice, const std::string& source) {
  const int rows = static_cast<int>(data.size());
  const std::vector<int>& candidates = choice.candidates;
  std::vector<std::string>& reason = choice.reason;
  std::vector<int>& free = choice.free;
  Eigen::MatrixXd start_jacobian(3 * rows, static_cast<Eigen::Index>(candidates.size()));
  {
    Eigen::VectorXd residual(3 * rows);
    CalibrationProblem(robot, data, start.toVector(), candidates)
        .evaluateFull(start.toVector(), residual, &start_jacobian);
  }
  const IdentifiabilityResult identifiability =
      analyseIdentifiability(start_jacobian, choice.priority, choice.typical, options.identifiability);
  result.condition_number_at_start = identifiability.condition_number;
  std::vector<double>& pivot = choice.pivot;
  auto& redundant = choice.redundant;
  pivot.assign(result.names.size(), 0.0);
  redundant.assign(result.names.size(), {});
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    const int i = candidates[c];
    pivot[static_cast<std::size_t>(i)] = identifiability.pivot[static_cast<Eigen::Index>(c)];
    if (std::binary_search(identifiability.kept.begin(), identifiability.kept.end(), static_cast<int>(c))) {
      free.push_back(i);
      continue;
    }
    if (identifiability.no_effect[c]) {
      reason[static_cast<std::size_t>(i)] = "no effect on the measurements";
      continue;
    }
    std::string with;
    for (const Redundancy& r : identifiability.redundant_with[c]) {
      const std::string& other = result.names[static_cast<std::size_t>(candidates[static_cast<std::size_t>(r.column)])];
      redundant[static_cast<std::size_t>(i)].emplace_back(other, r.ratio);
      with += (with.empty() ? "" : ", ") + other;
    }
    reason[static_cast<std::size_t>(i)] = "redundant (relative pivot " +
                                          fmt("%.1e", identifiability.pivot[static_cast<Eigen::Index>(c)]) + ")" +
                                          (with.empty() ? std::string() : " with " + with);
  }
  if (fit_frame) {
    std::string missing;
    for (int i : frameIndices(GeometricParameterLayout(robot.dof(), data.setups))) {
      if (std::find(free.begin(), free.end(), i) != free.end() || reason[static_cast<std::size_t>(i)] == kFixed) {
        continue;
      }
      missing += (missing.empty() ? "" : "; ") + result.names[static_cast<std::size_t>(i)] + ": " +
                 reason[static_cast<std::size_t>(i)];
    }
    if (!missing.empty()) {
      throw InvalidArgument(source + ": degenerate poses: the instrument frame is not identifiable from these " +
                            std::to_string(rows) + " rows (" + missing + ")");
    }
  }
  if (free.empty()) throw InvalidArgument(source + ": degenerate poses: no calibration parameter is identifiable");
  const int needed = 2 * static_cast<int>(free.size());
  if (3 * rows < needed) {
    throw InvalidArgument(source + ": too few points: " + std::to_string(rows) + " usable rows (" +
                          std::to_string(3 * rows) + " residuals) for " + std::to_string(free.size()) +
                          " identifiable parameters; the calibration needs at least twice as many residuals as "
                          "parameters (" +
                          std::to_string((needed + 2) / 3) + " rows)");
  }
}

// The rows' load torques (and the prior's other joint errors, which may depend on them) from the robot
// `estimate` describes.
void useTorquesOf(const JointErrorModel& prior, const GeometricParameters& estimate,
                  const std::vector<MeasurementCampaign>& campaigns, const std::vector<int>& setup_of_campaign,
                  CalibrationData& data) {
  const CalibrationData again = prepareCalibrationData(asWritten(prior, estimate).model, campaigns, setup_of_campaign);
  data.load_torque = again.load_torque;
  data.other_error = again.other_error;
}

// The fit; a compliance that comes out outside its physical constraint (ComplianceEffect::implausibility:
// not positive, too soft, deflecting too far over the rows' torques) is held at its nominal value and the
// fit repeated.
FitOutcome fitKeepingCompliancePlausible(const Robot& robot, const CalibrationData& data,
                                         const Eigen::VectorXd& nominal_values,
                                         const GeometricCalibrationOptions& options, ParameterChoice& choice) {
  const int n = robot.dof();
  const GeometricParameterLayout layout(n);
  std::vector<int>& free = choice.free;
  std::vector<std::string>& reason = choice.reason;
  std::vector<double> largest(static_cast<std::size_t>(n), 0.0);  // N m, per joint over the rows
  for (const JointVector& torque : data.load_torque) {
    for (int j = 0; j < n; ++j)
      largest[static_cast<std::size_t>(j)] = std::max(largest[static_cast<std::size_t>(j)], std::abs(torque[j]));
  }
  FitOutcome fit = fitSubset(robot, data, nominal_values, free, options, 0.0, "calibrating");
  for (int round = 0; round < n; ++round) {
    std::vector<int> dropped;
    for (int j = 0; j < n; ++j) {
      const int i = layout.compliance(j);
      if (std::find(free.begin(), free.end(), i) == free.end()) continue;
      const std::string problem = ComplianceEffect::implausibility(fit.values[i], largest[static_cast<std::size_t>(j)],
                                                                   robot.joints[static_cast<std::size_t>(j)].name);
      if (problem.empty()) continue;
      dropped.push_back(i);
      reason[static_cast<std::size_t>(i)] = "fitted " + fmt("%.3g", fit.values[i]) + " rad/(N m), not physical (" +
                                            problem + "): held at nominal " + fmt("%.3g", nominal_values[i]);
    }
    if (dropped.empty()) break;
    for (int i : dropped) {
      free.erase(std::find(free.begin(), free.end(), i));
      fit.values[i] = nominal_values[i];
    }
    fit.solver.jacobian.resize(0, 0);  // not kept through the refit (a matrix of 3 x rows x free)
    fit = fitSubset(robot, data, fit.values, free, options, fit.loss_scale, "calibrating");
  }
  return fit;
}

// Refuses a fit whose geometry no real robot has: the corrections it needs are the URDF's or the data's.
void refuseImplausibleGeometry(const Robot& robot, const GeometricParameters& estimate, const GeometryLimits& limits,
                               const std::string& source) {
  const std::string beyond = geometryBeyondLimits(robot, estimate, limits);
  if (beyond.empty()) return;
  throw ImplausibleGeometry(
      source + ": the calibration's geometry is not a robot's: " + beyond +
      ". A correction this large describes the URDF or the data: check the joint's zero and axis direction "
      "against the maker's DH table, and the campaign's joint order and units (--geometry-limits "
      "OFFSET_DEG,SHIFT_MM,TURN_DEG, or the C API's max_offset_deg, max_placement_shift_mm and "
      "max_placement_turn_deg, allow more)");
}

// The compliance acts on the load torques of the robot the calibration describes (what the written URDF
// gives), not the nominal one's: refit on those. The placements change the torques by a little, so a
// second round changes them by far less than the noise. The residual left in `fit` is the rows' error as
// the written files give it, with the torques of the final geometry.
void refitOnCalibratedTorques(const JointErrorModel& prior, const std::vector<MeasurementCampaign>& campaigns,
                              const std::vector<int>& setup_of_campaign, const GeometricCalibrationOptions& options,
                              const ParameterChoice& choice, CalibrationData& data, FitOutcome& fit) {
  const Robot& robot = prior.robot();
  const auto estimate = [&] { return GeometricParameters::fromVector(fit.values, robot.dof(), data.setups); };
  int iterations = fit.solver.iterations;  // all the fits', as the report counts them
  for (int round = 0; round < 2; ++round) {
    useTorquesOf(prior, estimate(), campaigns, setup_of_campaign, data);
    fit.solver.jacobian.resize(0, 0);  // not kept through the refit (a matrix of 3 x rows x free)
    fit = fitSubset(robot, data, fit.values, choice.free, options, fit.loss_scale, "calibrating");
    iterations += fit.solver.iterations;
  }
  fit.solver.iterations = iterations;
  useTorquesOf(prior, estimate(), campaigns, setup_of_campaign, data);
  CalibrationProblem(robot, data, fit.values, {}).evaluateFull(fit.values, fit.solver.residual, nullptr);
}

// Covariance sigma^2 (J^T W J)^-1 from the unit-scaled, weighted Jacobian of the free parameters.
void estimateCovariance(const FitOutcome& fit, int rows, const std::vector<int>& free, const std::string& source,
                        GeometricCalibrationResult& result) {
  const Eigen::Index k = static_cast<Eigen::Index>(free.size());
  Eigen::MatrixXd weighted = fit.solver.jacobian;
  double weighted_squares = 0.0;
  for (int r = 0; r < rows; ++r) {
    const double w = fit.solver.block_weight[r];
    weighted.middleRows<3>(3 * r) *= std::sqrt(w);
    weighted_squares += w * fit.solver.residual.segment<3>(3 * r).squaredNorm();
  }
  const double dof_residual = static_cast<double>(3 * rows) - static_cast<double>(k);
  result.residual_sigma = std::sqrt(weighted_squares / dof_residual);
  Eigen::VectorXd norms = weighted.colwise().norm();
  for (Eigen::Index c = 0; c < k; ++c) {
    if (norms[c] == 0.0)
      throw SolverError(source + ": parameter " +
                        result.names[static_cast<std::size_t>(free[static_cast<std::size_t>(c)])] +
                        " lost its effect during the fit");
    weighted.col(c) /= norms[c];
  }
  std::vector<int> all(static_cast<std::size_t>(k));
  for (Eigen::Index c = 0; c < k; ++c) all[static_cast<std::size_t>(c)] = static_cast<int>(c);
  result.condition_number = scaledConditionNumber(weighted, all);
  const Eigen::HouseholderQR<Eigen::Ref<Eigen::MatrixXd>> qr(weighted);  // in place: no copy of 3 x rows x free
  const Eigen::MatrixXd r_factor = qr.matrixQR().topRows(k).triangularView<Eigen::Upper>();
  const Eigen::MatrixXd r_inverse = r_factor.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(k, k));
  const Eigen::MatrixXd scaled_covariance = r_inverse * r_inverse.transpose();
  const Eigen::VectorXd inverse_norms = norms.cwiseInverse();
  result.covariance = result.residual_sigma * result.residual_sigma *
                      (inverse_norms.asDiagonal() * scaled_covariance * inverse_norms.asDiagonal());
}

// One estimate per parameter (free: with its sigma; fixed: with its reason), and the compliances that
// cannot be compensated.
void tabulateEstimates(const Robot& robot, const Eigen::VectorXd& nominal_values, const FitOutcome& fit,
                       const ParameterChoice& choice, GeometricCalibrationResult& result) {
  const int n = robot.dof();
  const GeometricParameterLayout layout(n);
  const std::vector<int>& free = choice.free;
  const std::vector<double>& pivot = choice.pivot;
  const std::vector<std::string>& reason = choice.reason;
  const auto& redundant = choice.redundant;
  for (std::size_t i = 0; i < result.names.size(); ++i) {
    ParameterEstimate estimate;
    estimate.name = result.names[i];
    estimate.unit = geometricParameterUnit(estimate.name);
    estimate.nominal = nominal_values[static_cast<Eigen::Index>(i)];
    estimate.value = fit.values[static_cast<Eigen::Index>(i)];
    estimate.pivot = pivot[i];
    const auto found = std::find(free.begin(), free.end(), static_cast<int>(i));
    estimate.identified = found != free.end();
    if (estimate.identified) {
      const Eigen::Index c = found - free.begin();
      estimate.sigma = std::sqrt(result.covariance(c, c));
    } else {
      estimate.fixed_because = reason[i];
      estimate.redundant_with = redundant[i];
    }
    result.parameters.push_back(estimate);
  }

  for (int j = 0; j < n; ++j) {
    const ParameterEstimate& c = result.parameters[static_cast<std::size_t>(layout.compliance(j))];
    if (!(c.value > 0.0)) {
      result.compliance_left_out.push_back(robot.joints[static_cast<std::size_t>(j)].name + ": " +
                                           (c.identified ? "fitted not positive" : c.fixed_because));
    }
  }
}

// The campaigns' source joined as concatenateCampaigns joins it, after checking they agree and are not more
// rows than a calibration takes. What the fit needs of the joined campaign is this and the first campaign's
// frame and target: no copy of the rows is kept.
std::string joinedSource(const std::vector<MeasurementCampaign>& campaigns) {
  checkCampaignsAgree(campaigns);
  std::string source = campaigns.front().source;
  std::size_t rows = 0;
  for (const MeasurementCampaign& c : campaigns) {
    rows += c.size();
    if (&c != &campaigns.front()) source += "+" + c.source;
  }
  if (rows > kMaxCalibrationRows) {
    throw InvalidArgument(source + ": " + std::to_string(rows) + " rows are more than a calibration takes (" +
                          std::to_string(kMaxCalibrationRows) + " rows, about 3.4 KB of memory each)");
  }
  return source;
}

// One target for all campaigns: they may not name different ones.
void checkOneTarget(const std::vector<MeasurementCampaign>& campaigns, const MeasurementCampaign& whole) {
  for (const MeasurementCampaign& c : campaigns) {
    if (c.has_target != whole.has_target || (c.has_target && c.target_in_flange != whole.target_in_flange)) {
      throw InvalidArgument("campaign '" + c.source + "' names another target in the flange than '" +
                            campaigns.front().source + "'; one calibration fits one target");
    }
  }
}

}  // namespace
bool baseFrameKept(const GeometricCalibrationOptions& options) {
  for (const char* p : {"tx_m", "ty_m", "tz_m", "rx_rad", "ry_rad", "rz_rad"}) {
    if (std::find(options.fixed.begin(), options.fixed.end(), std::string("frame.") + p) == options.fixed.end()) {
      return false;
    }
  }
  return true;
}

int InstrumentSetUps::count() const {
  return setup_of_campaign.empty() ? 0 : 1 + *std::max_element(setup_of_campaign.begin(), setup_of_campaign.end());
}

InstrumentSetUps instrumentSetUps(const JointErrorModel& prior, const std::vector<MeasurementCampaign>& campaigns,
                                  const GeometricCalibrationOptions& options) {
  checkCampaignsAgree(campaigns);
  InstrumentSetUps setups;
  setups.setup_of_campaign.assign(campaigns.size(), 0);
  setups.frame_of_campaign.assign(campaigns.size(), Eigen::Isometry3d::Identity());
  if (campaigns.front().frame != MeasurementFrame::Instrument) return setups;
  std::vector<int> first_campaign;  // of each set-up
  for (std::size_t c = 0; c < campaigns.size(); ++c) {
    const Eigen::Isometry3d frame =
        evaluateOnCampaign(prior, nominalParameters(prior, campaigns[c]), campaigns[c], /*refit_frame=*/true, options)
            .parameters.instrumentFromBase();
    setups.frame_of_campaign[c] = frame;
    int found = -1;
    for (std::size_t s = 0; s < first_campaign.size() && found < 0; ++s) {
      const Eigen::Isometry3d relative =
          frame * setups.frame_of_campaign[static_cast<std::size_t>(first_campaign[s])].inverse();
      if (relative.translation().norm() <= kSameSetUpDistance &&
          Eigen::AngleAxisd(relative.linear()).angle() <= kSameSetUpAngle) {
        found = static_cast<int>(s);
      }
    }
    if (found < 0) {
      found = static_cast<int>(first_campaign.size());
      first_campaign.push_back(static_cast<int>(c));
    }
    setups.setup_of_campaign[c] = found;
  }
  return setups;
}

GeometricCalibrationResult calibrateGeometry(const JointErrorModel& prior, const MeasurementCampaign& campaign,
                                             const GeometricCalibrationOptions& options) {
  return calibrateGeometry(prior, std::vector<MeasurementCampaign>{campaign}, options);
}
GeometricCalibrationResult calibrateGeometry(const JointErrorModel& prior,
                                             const std::vector<MeasurementCampaign>& campaigns,
                                             const GeometricCalibrationOptions& options) {
  return calibrateGeometry(
      prior, campaigns,
      campaigns.size() == 1 ? std::vector<int>{0} : instrumentSetUps(prior, campaigns, options).setup_of_campaign,
      options);
}

GeometricCalibrationResult calibrateGeometry(const JointErrorModel& prior,
                                             const std::vector<MeasurementCampaign>& campaigns,
                                             const std::vector<int>& setup_of_campaign,
                                             const GeometricCalibrationOptions& options) {
  const Robot& robot = prior.robot();
  const int n = robot.dof();
  const std::string source = joinedSource(campaigns);
  const MeasurementCampaign& whole = campaigns.front();  // frame, target and base frame: one for all campaigns
  checkOneTarget(campaigns, whole);
  CalibrationData data = prepareCalibrationData(prior, campaigns, setup_of_campaign);
  data.source = source;
  const int setups = data.setups;
  std::vector<std::string> setup_sources(static_cast<std::size_t>(setups));
  for (std::size_t c = 0; c < campaigns.size(); ++c) {
    std::string& named = setup_sources[static_cast<std::size_t>(setup_of_campaign[c])];
    named += (named.empty() ? "" : "+") + campaigns[c].source;
  }
  GeometricCalibrationResult result;
  // Each used row's campaign and its row there.
  std::vector<int> first_row(1, 0);
  for (const MeasurementCampaign& c : campaigns) first_row.push_back(first_row.back() + static_cast<int>(c.size()));
  std::vector<int> own_row;
  for (std::size_t k = 0; k < data.size(); ++k) {
    own_row.push_back(data.row[k] - first_row[static_cast<std::size_t>(data.campaign[k])]);
  }
  result.campaign_of_row = data.campaign;
  for (const MeasurementCampaign& c : campaigns) result.sources.push_back(c.source);
  result.setup_of_campaign = setup_of_campaign;
  const int rows = static_cast<int>(data.size());
  if (rows < std::max(options.minimum_rows, 3)) {
    throw InvalidArgument(source + ": too few points: " + std::to_string(rows) + " usable rows (" +
                          std::to_string(data.skipped_rows) +
                          " without a measured position); the calibration needs "
                          "at least " +
                          std::to_string(std::max(options.minimum_rows, 3)));
  }
  const bool fit_frame = options.fit_frame && whole.frame == MeasurementFrame::Instrument;
  // A known base frame kept as given: no frame is fitted to set-up 0, as for a campaign in the base frame.
  result.frame_fitted =
      whole.frame == MeasurementFrame::Instrument && !(whole.has_base_frame && baseFrameKept(options));

  result.names = geometricParameterNames(robot, setups);
  result.used_rows = rows;
  result.skipped_rows = data.skipped_rows;
  result.row = own_row;
  result.loss = options.loss;

  const GeometricParameters start = startingPoint(prior, whole, data, options, fit_frame, setup_sources, result);
  ParameterChoice choice = candidateParameters(robot, data, options, fit_frame, result, source);
  chooseIdentifiable(robot, data, start, options, fit_frame, result, choice, source);
  report(options.progress, source + ": " + std::to_string(rows) + " rows, " + std::to_string(choice.free.size()) +
                               " of " + std::to_string(choice.candidates.size()) + " parameters identifiable" +
                               (setups > 1 ? ", " + std::to_string(setups) + " instrument set-ups" : std::string()));
  const Eigen::VectorXd nominal_values = start.toVector();
  FitOutcome fit = fitKeepingCompliancePlausible(robot, data, nominal_values, options, choice);
  if (options.calibrated_torques && data.torque_known) {
    refitOnCalibratedTorques(prior, campaigns, setup_of_campaign, options, choice, data, fit);
  }
  result.estimate = GeometricParameters::fromVector(fit.values, n, setups);
  refuseImplausibleGeometry(robot, result.estimate, options.limits, source);
  result.free = choice.free;
  result.loss_scale = fit.loss_scale;
  result.iterations = fit.solver.iterations;
  result.stop_reason = fit.solver.stop_reason;
  result.error_after = rowNorms(fit.solver.residual);
  result.after = errorStatistics(result.error_after);
  result.weight.assign(fit.solver.block_weight.data(), fit.solver.block_weight.data() + fit.solver.block_weight.size());
  result.downweighted_rows = countBelow(fit.solver.block_weight, 0.999);
  result.outlier_rows = countBelow(fit.solver.block_weight, 0.5);
  estimateCovariance(fit, rows, choice.free, source, result);
  tabulateEstimates(robot, nominal_values, fit, choice, result);
  return result;
}
HoldoutEvaluation evaluateOnCampaign(const JointErrorModel& prior, const GeometricParameters& parameters,
                                     const MeasurementCampaign& campaign, bool refit_frame,
                                     const GeometricCalibrationOptions& options) {
  const Robot& robot = prior.robot();
  const CalibrationData data = prepareCalibrationData(prior, campaign);
  const int rows = static_cast<int>(data.size());
  HoldoutEvaluation evaluation;
  evaluation.source = campaign.source;
  evaluation.row = data.row;
  evaluation.skipped_rows = data.skipped_rows;
  GeometricParameters used = parameters.ofSetUp(0);
  if (!options.same_instrument) used.instrument_scale = 0.0;  // another set-up: the fitted scale is not its own
  // A campaign whose known base frame is kept is evaluated in it, like one in the base frame without one.
  const bool known = campaign.has_base_frame && baseFrameKept(options);
  if (known) used.setInstrumentFromBase(campaign.base_frame);
  const bool fit = refit_frame && campaign.frame == MeasurementFrame::Instrument && !known;
  if (campaign.frame == MeasurementFrame::Base) {
    used.frame_translation.setZero();
    used.frame_rotation.setZero();
  }
  if (rows < (fit ? std::max(options.minimum_rows, 3) : 1)) {
    throw InvalidArgument(campaign.source + ": too few points: " + std::to_string(rows) + " usable rows (" +
                          std::to_string(data.skipped_rows) + " without a measured position)");
  }
  Eigen::VectorXd weights = Eigen::VectorXd::Ones(rows);
  Eigen::VectorXd residual(3 * rows);
  if (fit) {
    const std::vector<Eigen::Vector3d> points = basePoints(robot, used, data);
    checkPoses(data, points, campaign.source);
    used.setInstrumentFromBase(fitRigidTransform(points, data.measured));
    const FitOutcome outcome =
        fitSubset(robot, data, used.toVector(), frameIndices(GeometricParameterLayout(robot.dof())), options, 0.0,
                  "fitting the instrument frame");
    used = GeometricParameters::fromVector(outcome.values, robot.dof());
    residual = outcome.solver.residual;
    weights = outcome.solver.block_weight;
    evaluation.loss_scale = outcome.loss_scale;
    evaluation.downweighted_rows = countBelow(weights, 0.999);
    evaluation.outlier_rows = countBelow(weights, 0.5);
  } else {
    CalibrationProblem(robot, data, used.toVector(), {}).evaluateFull(used.toVector(), residual, nullptr);
  }
  evaluation.parameters = used;
  evaluation.error = rowNorms(residual);
  evaluation.weight.assign(weights.data(), weights.data() + weights.size());
  evaluation.statistics = errorStatistics(evaluation.error);
  return evaluation;
}

}  // namespace jointcomp
