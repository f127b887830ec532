#include "model/identify/transmission_identification.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "model/common/errors.hpp"
#include "model/effects/compliance.hpp"
#include "model/identify/identification_statistics.hpp"
#include "model/identify/identification_support.hpp"
#include "model/io/instrument_noise.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {
namespace {

using namespace identify_detail;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;

void checkOptions(const Robot& robot, const GearTrain& gears, const TransmissionIdentificationOptions& o) {
  if (o.joint < 0 || o.joint >= robot.dof()) {
    throw InvalidArgument("transmission identification: joint " + std::to_string(o.joint + 1) +
                          " does not exist (robot '" + robot.name + "' has " + std::to_string(robot.dof()) + ")");
  }
  const int stages = gears.stageCount(o.joint);
  if (o.stage < 1 || o.stage > stages + 1) {
    throw InvalidArgument("transmission identification: " + robot.joints[o.joint].name + " has stages 1 (motor) to " +
                          std::to_string(stages + 1) + " (output), not " + std::to_string(o.stage));
  }
  if (o.candidate_orders.empty()) throw InvalidArgument("transmission identification: no candidate orders");
  for (std::size_t i = 0; i < o.candidate_orders.size(); ++i) {
    const double order = o.candidate_orders[i];
    if (!(order > 0.0) || !std::isfinite(order)) {
      throw InvalidArgument("transmission identification: candidate order " + formatNumber(order) + " is not positive");
    }
    for (std::size_t k = 0; k < i; ++k) {
      if (o.candidate_orders[k] == order) {
        throw InvalidArgument("transmission identification: candidate order " + formatNumber(order) + " appears twice");
      }
    }
  }
  if (o.baseline_degree < 0 || o.baseline_degree > 12) {
    throw InvalidArgument("transmission identification: baseline_degree must lie in 0 ... 12");
  }
  if (!(o.significance > 0.0 && o.significance < 1.0))
    throw InvalidArgument("transmission identification: significance must lie in (0, 1)");
  if (!(o.confidence > 0.0 && o.confidence < 1.0))
    throw InvalidArgument("transmission identification: confidence must lie in (0, 1)");
  if (!(o.min_periods > 0.0)) throw InvalidArgument("transmission identification: min_periods must be positive");
  if (!(o.spectrum_min_order > 0.0) || !(o.spectrum_max_order > o.spectrum_min_order) || !(o.spectrum_step > 0.0) ||
      (o.spectrum_max_order - o.spectrum_min_order) / o.spectrum_step > 100000.0) {
    throw InvalidArgument(
        "transmission identification: the spectrum needs 0 < min order < max order and a positive step "
        "(at most 100000 orders)");
  }
}

struct Design {
  const std::vector<double>* x;
  const std::vector<double>* theta;
  int degree;
};

Eigen::MatrixXd designMatrix(const Design& d, const std::vector<double>& orders) {
  const int rows = static_cast<int>(d.x->size());
  Eigen::MatrixXd a(rows, d.degree + 1 + 2 * static_cast<int>(orders.size()));
  for (int r = 0; r < rows; ++r) {
    double power = 1.0;
    for (int i = 0; i <= d.degree; ++i) {
      a(r, i) = power;
      power *= (*d.x)[r];
    }
    for (std::size_t h = 0; h < orders.size(); ++h) {
      const double angle = orders[h] * (*d.theta)[r];
      a(r, d.degree + 1 + 2 * static_cast<int>(h)) = std::sin(angle);
      a(r, d.degree + 2 + 2 * static_cast<int>(h)) = std::cos(angle);
    }
  }
  return a;
}

HarmonicEstimate harmonicOf(const LinearFit& fit, int column, double order, double t_factor) {
  HarmonicEstimate h;
  h.order = order;
  const double s = fit.coefficients[column];
  const double c = fit.coefficients[column + 1];
  const Eigen::Matrix2d cov = fit.covariance.block<2, 2>(column, column);
  h.amplitude_rad = std::hypot(s, c);
  h.phase_rad = std::atan2(c, s);
  if (h.amplitude_rad > 0.0) {
    const Eigen::Vector2d g_amplitude(s / h.amplitude_rad, c / h.amplitude_rad);
    const Eigen::Vector2d g_phase(-c / (h.amplitude_rad * h.amplitude_rad), s / (h.amplitude_rad * h.amplitude_rad));
    h.amplitude_se_rad = std::sqrt(std::max(0.0, g_amplitude.dot(cov * g_amplitude)));
    h.phase_se_rad = std::sqrt(std::max(0.0, g_phase.dot(cov * g_phase)));
  } else {
    h.amplitude_se_rad = std::sqrt(0.5 * cov.trace());
    h.phase_se_rad = kPi;
  }
  h.amplitude_low_rad = std::max(0.0, h.amplitude_rad - t_factor * h.amplitude_se_rad);
  h.amplitude_high_rad = h.amplitude_rad + t_factor * h.amplitude_se_rad;
  h.phase_low_rad = h.phase_rad - t_factor * h.phase_se_rad;
  h.phase_high_rad = h.phase_rad + t_factor * h.phase_se_rad;
  h.amplitude_to_se = h.amplitude_se_rad > 0.0 ? h.amplitude_rad / h.amplitude_se_rad : 0.0;
  return h;
}

}  // namespace

namespace {

// A sweep moves the identified joint only, and its angle is recovered from the tracker or the levels.
void checkSweep(const Robot& robot, const MeasurementCampaign& campaign, int j,
                TransmissionIdentificationResult& result) {
  const int n = robot.dof();
  for (std::size_t k = 1; k < campaign.size(); ++k) {
    for (int i = 0; i < n; ++i) {
      if (i != j && std::abs(campaign.command[k][i] - campaign.command[0][i]) > 1e-9) {
        throw MeasurementError(campaign.source + ": row " + std::to_string(k + 1) + ": q" + std::to_string(i + 1) +
                               " moves (" + formatNumber(campaign.command[0][i] / kDegree) + " deg to " +
                               formatNumber(campaign.command[k][i] / kDegree) + " deg): a sweep of " +
                               result.joint_name + " moves that joint only");
      }
    }
  }
  const bool by_tracker = campaign.has_position;
  if (!by_tracker && !campaign.has_measured_angles) {
    throw MeasurementError(campaign.source + ": neither positions nor joint angles to recover the joint angle from");
  }
  result.angle_source = by_tracker ? "tracker" : "levels";
  if (by_tracker && campaign.frame != MeasurementFrame::Base) {
    throw MeasurementError(campaign.source +
                           ": the transmission-error identification needs positions in the base frame");
  }
}

// Per measured row: the joint angle measured, the part of it the nominal compliance explains, the
// kinematic error left, the stage angle; returns each row's 1-sigma noise (NaN where unknown).
std::vector<double> sweepSamples(const JointErrorModel& nominal, const MeasurementCampaign& campaign,
                                 const TransmissionIdentificationOptions& options,
                                 TransmissionIdentificationResult& result) {
  const Robot& robot = nominal.robot();
  const GearTrain& gears = nominal.gears();
  const int j = options.joint;
  const int n = robot.dof();
  const bool by_tracker = campaign.has_position;
  const Eigen::Vector3d target = targetOf(campaign);
  const std::vector<double> position_sigma = positionSigmaPerRow(campaign);
  const EffectMask stiffness_mask = nominal.loadsAnd({ComplianceEffect::kType});
  JointErrorWorkspace ws(robot);
  RobotWorkspace predicted(robot);
  JointContext ctx(n);
  std::vector<double> sigma;
  for (std::size_t k = 0; k < campaign.size(); ++k) {
    const JointVector& command = campaign.command[k];
    if (by_tracker ? !campaign.position[k].allFinite() : !std::isfinite(campaign.measured_angles[k][j])) continue;
    // Where the nominal model puts the links under its loads and compliance.
    ctx.command = command;
    ctx.velocity = JointVector::Zero(n);
    ctx.payload_mass = campaign.payload[k];
    ctx.payload_com = target;
    forwardKinematics(robot, ws.robot, command);
    ctx.tool_wrench = toolWrenchOf(campaign.wrench[k], ws.robot, target);
    const FixedPointReport settled = settleStatically(nominal, stiffness_mask, ws, ctx);
    if (!settled.converged) {
      throw SolverError(campaign.source + ": row " + std::to_string(k + 1) + ": the nominal model did not settle");
    }
    double angle = 0.0, stiffness_error = 0.0, row_sigma = std::numeric_limits<double>::quiet_NaN();
    if (by_tracker) {
      forwardKinematics(robot, predicted, ctx.q);
      forwardKinematics(robot, ws.robot, command);
      const Eigen::Vector3d nominal_target = ws.robot.tool_pose * target;
      double lever = 0.0;
      angle = angleAboutAxis(ws.robot.axis[j], ws.robot.origin[j], nominal_target, campaign.position[k], &lever);
      if (lever < 1e-3) {
        throw MeasurementError(campaign.source + ": row " + std::to_string(k + 1) +
                               ": the target is within 1 mm of the axis of " + result.joint_name +
                               ": its angle cannot be recovered");
      }
      stiffness_error =
          angleAboutAxis(ws.robot.axis[j], ws.robot.origin[j], nominal_target, predicted.tool_pose * target);
      row_sigma = position_sigma[k] / lever;
    } else {
      angle = campaign.measured_angles[k][j] - command[j];
      stiffness_error = ctx.q[j] - command[j];
      if (campaign.angle_noise > 0.0) row_sigma = campaign.angle_noise;
    }
    JointVector motor;
    gears.motorAngles(command, motor);
    result.command.push_back(command[j]);
    result.measured.push_back(command[j] + angle);
    result.stiffness_error.push_back(stiffness_error);
    result.kinematic_error.push_back(angle - stiffness_error);
    result.stage_angle.push_back(gears.stageInputAngle(j, options.stage, motor));
    sigma.push_back(row_sigma);
  }
  return sigma;
}

// Which candidates the sweep can tell apart from the baseline: those it turns through min_periods.
std::vector<double> resolvableOrders(const MeasurementCampaign& campaign,
                                     const TransmissionIdentificationOptions& options,
                                     TransmissionIdentificationResult& result) {
  const int samples = result.samples;
  if (samples > 0) {
    const auto range = std::minmax_element(result.stage_angle.begin(), result.stage_angle.end());
    result.stage_revolutions = (*range.second - *range.first) / (2.0 * kPi);
  }
  std::vector<double> orders;
  for (double order : options.candidate_orders) {
    (order * result.stage_revolutions >= options.min_periods ? orders : result.excluded_orders).push_back(order);
  }
  if (orders.empty()) {
    throw MeasurementError(campaign.source + ": the sweep turns " + result.part + " of " + result.joint_name + " by " +
                           formatNumber(result.stage_revolutions) + " revolutions: too short for " +
                           formatNumber(options.min_periods) + " periods of any candidate order");
  }
  return orders;
}

// The full model and the F test of each order (Bonferroni over the candidates); the significant orders.
std::vector<double> significantOrders(const Design& design, const Eigen::Ref<const Eigen::VectorXd>& y,
                                      const Eigen::Ref<const Eigen::VectorXd>& s, const std::vector<double>& orders,
                                      int columns, const MeasurementCampaign& campaign,
                                      const TransmissionIdentificationOptions& options,
                                      TransmissionIdentificationResult& result) {
  const int base_columns = options.baseline_degree + 1;
  const LinearFit full = weightedLeastSquares(designMatrix(design, orders), y, s);
  if (full.rank < columns) {
    throw MeasurementError(campaign.source + ": the sweep of " + result.joint_name +
                           " cannot separate the candidate harmonics from the baseline (degenerate design)");
  }
  const double threshold = options.significance / static_cast<double>(orders.size());
  std::vector<double> significant;
  for (std::size_t h = 0; h < orders.size(); ++h) {
    HarmonicEstimate estimate = harmonicOf(full, base_columns + 2 * static_cast<int>(h), orders[h],
                                           tIntervalFactor(options.confidence, full.dof));
    std::vector<double> others = orders;
    others.erase(others.begin() + static_cast<long>(h));
    const LinearFit reduced = weightedLeastSquares(designMatrix(design, others), y, s);
    estimate.f_statistic = std::max(0.0, (reduced.rss - full.rss) / 2.0 / (full.rss / full.dof));
    estimate.p_value = fTail2(estimate.f_statistic, full.dof);
    estimate.significant = estimate.p_value < threshold;
    if (estimate.significant) significant.push_back(orders[h]);
    result.candidates.push_back(estimate);
  }

  return significant;
}

// The significant orders alone: the harmonics reported, the baseline and the residual.
void fitSignificant(const Design& design, const Eigen::Ref<const Eigen::VectorXd>& y,
                    const Eigen::Ref<const Eigen::VectorXd>& s, const std::vector<double>& significant,
                    bool noise_known, const TransmissionIdentificationOptions& options,
                    TransmissionIdentificationResult& result) {
  const int base_columns = options.baseline_degree + 1;
  const int samples = result.samples;
  const LinearFit final_fit = weightedLeastSquares(designMatrix(design, significant), y, s);
  const double t_factor = tIntervalFactor(options.confidence, final_fit.dof);
  for (std::size_t h = 0; h < significant.size(); ++h) {
    HarmonicEstimate estimate = harmonicOf(final_fit, base_columns + 2 * static_cast<int>(h), significant[h], t_factor);
    for (const HarmonicEstimate& candidate : result.candidates) {
      if (candidate.order == significant[h]) {
        estimate.f_statistic = candidate.f_statistic;
        estimate.p_value = candidate.p_value;
      }
    }
    estimate.significant = true;
    result.harmonics.push_back(estimate);
  }
  result.dof = final_fit.dof;
  result.baseline.assign(final_fit.coefficients.data(), final_fit.coefficients.data() + base_columns);
  const Eigen::VectorXd fitted = y - final_fit.residuals;
  result.fitted.assign(fitted.data(), fitted.data() + samples);
  result.residual_rms_rad = std::sqrt(final_fit.residuals.squaredNorm() / samples);
  result.reduced_chi2 = noise_known ? final_fit.scale2 : 0.0;
}

// The spectrum: one harmonic at a time with the baseline.
void spectrumOf(const Design& design, const Eigen::Ref<const Eigen::VectorXd>& y,
                const Eigen::Ref<const Eigen::VectorXd>& s, const TransmissionIdentificationOptions& options,
                TransmissionIdentificationResult& result) {
  const int base_columns = options.baseline_degree + 1;
  const int steps = static_cast<int>(
      std::floor((options.spectrum_max_order - options.spectrum_min_order) / options.spectrum_step + 1e-9));
  for (int i = 0; i <= steps; ++i) {
    const double order = options.spectrum_min_order + i * options.spectrum_step;
    const LinearFit single = weightedLeastSquares(designMatrix(design, {order}), y, s);
    if (single.rank < base_columns + 2) continue;
    result.spectrum_orders.push_back(order);
    result.spectrum_amplitude_rad.push_back(
        std::hypot(single.coefficients[base_columns], single.coefficients[base_columns + 1]));
  }
}

}  // namespace

TransmissionIdentificationResult identifyTransmissionError(const JointErrorModel& nominal,
                                                           const MeasurementCampaign& campaign,
                                                           const TransmissionIdentificationOptions& options) {
  const Robot& robot = nominal.robot();
  const GearTrain& gears = nominal.gears();
  checkOptions(robot, gears, options);
  checkCampaign(robot, campaign, campaign.has_position, "transmission-error identification");
  const int j = options.joint;
  TransmissionIdentificationResult result;
  result.joint = j;
  result.joint_name = robot.joints[j].name;
  result.stage = options.stage;
  result.part = options.stage == 1                         ? "motor"
                : options.stage == gears.stageCount(j) + 1 ? "output"
                                                           : "stage_" + std::to_string(options.stage);
  result.confidence = options.confidence;
  result.significance = options.significance;
  if (campaign.size() == 0) throw MeasurementError(campaign.source + ": the campaign has no rows");
  checkSweep(robot, campaign, j, result);
  std::vector<double> sigma = sweepSamples(nominal, campaign, options, result);
  const int samples = static_cast<int>(result.command.size());
  result.samples = samples;
  const bool noise_known = fillUnknownSigma(sigma);
  if (noise_known) {
    double sum = 0.0;
    for (double s : sigma) sum += s * s;
    result.noise_rms_rad = samples > 0 ? std::sqrt(sum / samples) : 0.0;
  }
  const std::vector<double> orders = resolvableOrders(campaign, options, result);
  const int base_columns = options.baseline_degree + 1;
  const int columns = base_columns + 2 * static_cast<int>(orders.size());
  if (samples < columns + 2) {
    throw MeasurementError(campaign.source + ": " + std::to_string(samples) + " measured points of " +
                           result.joint_name + " for " + std::to_string(columns) +
                           " unknowns (baseline and harmonics); at least " + std::to_string(columns + 2) +
                           " are needed");
  }
  const auto q_range = std::minmax_element(result.command.begin(), result.command.end());
  result.baseline_centre = 0.5 * (*q_range.first + *q_range.second);
  result.baseline_half_range = std::max(1e-12, 0.5 * (*q_range.second - *q_range.first));
  std::vector<double> x(samples);
  for (int r = 0; r < samples; ++r) x[r] = (result.command[r] - result.baseline_centre) / result.baseline_half_range;
  const Design design{&x, &result.stage_angle, options.baseline_degree};
  const Eigen::Map<const Eigen::VectorXd> y(result.kinematic_error.data(), samples);
  const Eigen::Map<const Eigen::VectorXd> s(sigma.data(), samples);

  const std::vector<double> significant = significantOrders(design, y, s, orders, columns, campaign, options, result);
  fitSignificant(design, y, s, significant, noise_known, options, result);
  spectrumOf(design, y, s, options, result);
  return result;
}

JointErrorModel withIdentifiedHarmonics(const JointErrorModel& nominal, const TransmissionIdentificationResult& result,
                                        const std::string& source_note) {
  const Robot& robot = nominal.robot();
  if (result.joint < 0 || result.joint >= robot.dof() || robot.joints[result.joint].name != result.joint_name) {
    throw InvalidArgument("harmonic update: the result is for another robot");
  }
  std::vector<Harmonic> harmonics;
  std::string old_note;
  const int index = nominal.findEffect(TransmissionErrorEffect::kType);
  if (index >= 0) {
    const auto& effect = static_cast<const TransmissionErrorEffect&>(nominal.effect(index));
    old_note = effect.estimate_note;
    for (const Harmonic& h : effect.harmonics()) {
      if (h.joint != result.joint || h.stage != result.stage) harmonics.push_back(h);
    }
  }
  for (const HarmonicEstimate& e : result.harmonics) {
    Harmonic h;
    h.joint = result.joint;
    h.stage = result.stage;
    h.cycles_per_revolution = e.order;
    h.amplitude_rad = e.amplitude_rad;
    h.phase_rad = e.phase_rad;
    harmonics.push_back(h);
  }
  auto updated_effect = std::make_unique<TransmissionErrorEffect>(robot, nominal.gears(), harmonics);
  std::string note = result.joint_name + " " + result.part + " harmonics identified from " + source_note;
  if (!old_note.empty()) note += "; the others: " + old_note;
  updated_effect->estimate_note = note;
  std::vector<std::unique_ptr<Effect>> effects;
  for (int i = 0; i < nominal.effectCount(); ++i) {
    if (i == index) {
      effects.push_back(std::move(updated_effect));
    } else {
      effects.push_back(nominal.effect(i).clone());
    }
  }
  if (index < 0) effects.push_back(std::move(updated_effect));
  JointErrorModel updated(nominal.sharedRobot(), nominal.gears(), std::move(effects));
  updated.notes = nominal.notes + (nominal.notes.empty() ? "" : " ") + "Transmission error of " + result.joint_name +
                  " identified from " + source_note + ".";
  return updated;
}

}  // namespace jointcomp
