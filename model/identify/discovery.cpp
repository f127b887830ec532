#include "model/identify/discovery.hpp"
#include "model/identify/discovery_problem.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <set>

#include "model/common/errors.hpp"
#include "model/common/median.hpp"
#include "model/compensation/metrics.hpp"
#include "model/effects/periodic_table.hpp"
#include "model/effects/registry.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {
namespace {

using namespace discovery_detail;

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
  d.table_knots = options.table_knots;
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
        const bool by_row =
            !candidate.through_compliance && !candidate.joint_error_blocks && candidate.columns.cols() > 0;
        f.sparse.push_back(by_row ? sparseFeatures(candidate.columns) : SparseFeatures());
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
    const Eigen::Vector3d m = KinematicCalibration::predict(model.robot(), parameters, data, i);
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

DiscoveryOptions::DiscoveryOptions() = default;

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
  DiscoveryRun(const JointErrorModel& prior, KinematicCalibration calibration,
               const std::vector<MeasurementCampaign>& heldout, const DiscoveryOptions& options)
      : prior_(prior),
        calibration_(std::move(calibration)),
        heldout_(heldout),
        options_(options),
        names_(calibration_.parameterNames(prior.robot())),
        data_(discoveryData(prior, calibration_.whole(), fittedRows(prior), options)),
        model_(prior),
        cuts_{options.folds, 6, options.min_group_share, options.angle_ranges},
        result_(prior) {
    std::size_t first = 0;
    for (const auto& c : calibration_.fitted()) {
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
    lin_ = linearise(model_, fittedRows(model_), cal_, features_, active_, cuts_, true);
    result_.joint_residual_rms_initial = jointRms(lin_);
    residuals_ = static_cast<double>(lin_.problem.r.size());
    fitBase(false);
    result_.initial = evaluate(base_fit_.cv);
    state_ = result_.initial;
    report(options_.calibration.progress, "discovery: base fit RMS " +
                                              std::to_string(result_.initial.fitted.rms * 1e3) + " mm, " +
                                              std::to_string(features_.candidates.size()) + " candidates");
    result_.stop_reason = "max_steps reached";
    for (int step = 0; step < options_.max_steps; ++step) {
      const std::size_t taken = result_.steps.size();
      if (!takeStep()) break;
      if (result_.steps.size() == taken) continue;  // undone after its refit (undone_ says why)
      const DiscoveryStep& s = result_.steps.back();
      report(options_.calibration.progress, "discovery step " + std::to_string(taken + 1) + ": " + s.type +
                                                (s.joint_name.empty() ? "" : " " + s.joint_name) + s.detail +
                                                ", fitted RMS " + std::to_string(s.after.fitted.rms * 1e3) + " mm");
    }
    if (result_.rejected_at_stop.find(undone_) == std::string::npos)
      result_.rejected_at_stop = joined(undone_, result_.rejected_at_stop);
    report(options_.calibration.progress, "discovery stopped: " + result_.stop_reason);
    finish();
    return std::move(result_);
  }

private:
  // The calibration's free parameters and the accepted effects' coefficients fitted together (CV on whole
  // time blocks); refit() steps the effects by it.
  void fitBase(bool need_inverse) {
    std::vector<const ColumnPiece*> pieces;
    for (const CandidatePiece& a : lin_.active) pieces.push_back(&a.piece);
    const FitSystem system = assembleSystem(lin_.problem, pieces, {lin_.problem.refitGrouping()});
    base_scale_ = system.scale;
    active_first_ = system.piece_first;
    base_fit_ = solveSystem(system, activePenalty(lin_, system, features_, active_), need_inverse);
  }

  // The columns of accepted candidate k's coefficients in the refit system.
  std::vector<int> activeColumns(std::size_t k) const {
    std::vector<int> columns;
    for (int c : lin_.active[k].coefficients) columns.push_back(active_first_[k + 1] + c);
    return columns;
  }

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
    data_.joint_residual = linearise(model_, fittedRows(model_), cal_, Features(), {}, cuts_, true).joint_residual;
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
    double sigma = calibration_.whole().position_noise;
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
    // Discovery's steps are judged on the prior geometry's load torques (its linearisation is); the final
    // files' figures then differ from the reported by the geometry's change of the torques (micrometres).
    cal_options.calibrated_torques = false;
    return cal_options;
  }

  GeometricCalibrationResult calibrate(const JointErrorModel& model) {
    return calibration_.calibrate(model, calibrationOptions());
  }

  // The fitted rows as `model` predicts them: the campaigns' concatenation, each row with its set-up.
  CalibrationData fittedRows(const JointErrorModel& model) const { return calibration_.fittedRows(model); }

  // Errors on the fitted rows, on every held-out campaign (frame re-fitted) and the paths' Ra and Rz, as
  // `model` with the calibration's parameters `p` predicts them (the step's model and estimate by default).
  DiscoveryState evaluate(double cv_sse) const { return evaluate(cv_sse, model_, cal_.estimate); }
  DiscoveryState evaluate(double cv_sse, const JointErrorModel& model, const GeometricParameters& p) const {
    DiscoveryState state;
    state.fitted = cal_.after;
    if (fitted_path_) {
      const CalibrationData data = fittedRows(model);
      const std::vector<double> z = zErrors(model, p, data);
      for (std::size_t c = 0; c < calibration_.fitted().size(); ++c) {
        if (!isPathCampaign(calibration_.fitted()[c])) continue;
        std::vector<double> part;
        for (std::size_t i = 0; i < z.size(); ++i) {
          const std::size_t row = static_cast<std::size_t>(data.row[i]);
          if (row >= first_row_[c] && row < first_row_[c + 1]) part.push_back(z[i]);
        }
        state.paths.push_back(roughness(part, false, static_cast<int>(c)));
      }
    }
    GeometricCalibrationOptions cal_options = calibrationOptions();
    cal_options.same_instrument = options_.heldout_same_instrument;
    for (std::size_t k = 0; k < heldout_.size(); ++k) {
      const HoldoutEvaluation e = KinematicCalibration::evaluate(model, p, heldout_[k], cal_options);
      state.heldout.push_back(e.statistics);
      if (isPathCampaign(heldout_[k])) {
        state.paths.push_back(roughness(zErrors(model, e.parameters, KinematicCalibration::rows(model, heldout_[k])),
                                        true, static_cast<int>(k)));
      }
    }
    state.cv_rms = std::sqrt(cv_sse / std::max(1.0, residuals_));
    return state;
  }

  // The candidate (or pair) to accept: chooseCandidate (discovery_selection.cpp).
  Choice choose() const {
    const Fit base = solveSystem(baseSystem(lin_.problem), Penalty(), false);
    const Selection selection{lin_, data_, features_, offered_, cal_, base, options_, cuts_};
    return chooseCandidate(selection);
  }

  // Adds the step's solution to the accepted candidates' coefficients and appends the chosen ones (the freed
  // geometry is refitted by the calibration).
  void acceptCoefficients(const Evaluation& chosen) {
    for (std::size_t m = 0; m < chosen.candidates.size(); ++m) {
      const int c = chosen.candidates[m];
      if (features_.candidates[static_cast<std::size_t>(c)].coefficients(prior_.robot().dof()) == 0) continue;
      Active fresh{c, chosen.member_step[m], Eigen::VectorXd::Zero(chosen.member_step[m].size()),
                   chosen.roughness_weight[m], chosen.ridge_weight[m]};
      active_.push_back(fresh);
    }
  }

  // Refits everything together: calibrates the base with the effects fixed, then a joint Gauss-Newton step
  // of the effects' coefficients with the base; then the final model of the step and its uncertainties.
  // A step that freed no calibration parameter starts from the calibration it was chosen at: its coefficients
  // were fitted together with that calibration's free parameters.
  void refit(bool released) {
    for (int it = 0; it < options_.refit_iterations; ++it) {
      if (!rebuildModel()) return;
      if (it > 0 || released || active_.empty()) cal_ = calibrate(model_);
      if (active_.empty()) break;
      lin_ = linearise(model_, fittedRows(model_), cal_, features_, active_, cuts_, false);
      fitBase(false);
      for (std::size_t k = 0; k < active_.size(); ++k) {
        const std::vector<int> columns = activeColumns(k);
        for (std::size_t c = 0; c < columns.size(); ++c)
          active_[k].theta[static_cast<Eigen::Index>(c)] += base_fit_.d[columns[c]] / base_scale_[columns[c]];
      }
    }
    if (!rebuildModel()) return;
    cal_ = calibrate(model_);
    lin_ = linearise(model_, fittedRows(model_), cal_, features_, active_, cuts_, false);
    fitBase(true);
    // Uncertainties of the effects' parameters: sigma^2 (X^T X + P)^-1, unscaled.
    const double sigma2 = base_fit_.rss / std::max(1.0, residuals_ - base_fit_.dof);
    for (std::size_t k = 0; k < active_.size(); ++k) {
      const std::vector<int> columns = activeColumns(k);
      for (std::size_t c = 0; c < columns.size(); ++c) {
        const double variance = sigma2 * base_fit_.inverse(columns[c], columns[c]);
        active_[k].sigma[static_cast<Eigen::Index>(c)] = std::sqrt(std::max(0.0, variance)) / base_scale_[columns[c]];
      }
    }
  }

  // model_ from the active coefficients; false, model_ kept, when a refit carried one beyond what its effect
  // accepts and its family calls that not physical (the caller then undoes the step).
  bool rebuildModel() {
    try {
      model_ = buildModel(prior_, active_, features_, data_, options_);
      return true;
    } catch (const ParameterError&) {
      if (unphysicalActive().empty()) throw;
      return false;
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
    if (!choice.found) {
      result_.stop_reason =
          "no candidate lowers the cross-validated error and the BIC without making a part of the "
          "data significantly worse";
      result_.rejected_at_stop = joined(undone_, choice.rejected);
      return false;
    }
    const Evaluation& chosen = choice.chosen;
    DiscoveryStep record = describeChoice(choice);
    record.before = state_;
    std::vector<int> newly_released;  // calibration parameters this step frees
    const std::set<int> free_before(cal_.free.begin(), cal_.free.end());
    const std::set<int> released_before = released_;
    for (int c : chosen.candidates) {
      offered_[static_cast<std::size_t>(c)] = false;
      for (int idx : features_.releases[static_cast<std::size_t>(c)]) {
        if (!free_before.count(idx)) newly_released.push_back(idx);
        released_.insert(idx);
      }
    }
    const std::size_t first_new = active_.size();
    const std::vector<Active> active_before = active_;
    acceptCoefficients(chosen);
    std::string unphysical;
    try {
      refit(!newly_released.empty());
      unphysical = unphysicalActive();
    } catch (const ImplausibleGeometry& e) {
      unphysical = std::string("not physical: ") + e.what();  // a freed offset or placement beyond its limit
    }
    if (!unphysical.empty()) {
      // The joint refit carried an effect or the geometry beyond what is physical: the step is undone and not
      // offered again.
      active_ = active_before;
      released_ = released_before;
      refit(true);
      undone_ += (undone_.empty() ? "" : "; ") + record.type + " " + record.joint_name + record.detail +
                 " undone after its refit, " + unphysical;
      return true;
    }
    state_ = evaluate(base_fit_.cv);
    record.after = state_;
    std::size_t next = first_new;
    for (int c : chosen.candidates) {
      const DiscoveryCandidate& candidate = features_.candidates[static_cast<std::size_t>(c)];
      if (candidate.columns.cols() == 0) {
        appendCalibrationEstimates(features_.releases[static_cast<std::size_t>(c)], record.parameters);
        continue;
      }
      const Active& a = active_[next++];
      for (const NamedEstimate& e :
           features_.family[static_cast<std::size_t>(c)]->describe({&candidate, a.theta, a.sigma}, model_))
        record.parameters.push_back(e);
    }
    if (next > first_new) appendCalibrationEstimates(newly_released, record.parameters);
    result_.steps.push_back(record);
    return true;
  }

  // Empty when every accepted effect is physical at its current coefficients; else the first problem.
  std::string unphysicalActive() const {
    for (const Active& a : active_) {
      const std::size_t c = static_cast<std::size_t>(a.candidate);
      const std::string problem =
          features_.family[c]->physicalProblem(data_, features_.candidates[c], a.theta, cal_.estimate.compliance);
      if (!problem.empty()) return problem;
    }
    return {};
  }

  static std::string joined(const std::string& a, const std::string& b) {
    return a.empty() ? b : b.empty() ? a : a + "; " + b;
  }

  // The step's record before it is taken: what was chosen (one candidate, or two together), and the evidence.
  DiscoveryStep describeChoice(const Choice& choice) const {
    const Evaluation& chosen = choice.chosen;
    const DiscoveryCandidate& first = features_.candidates[static_cast<std::size_t>(chosen.candidates[0])];
    DiscoveryStep record;
    record.type = first.type;
    record.joint = first.joint;
    record.stage = first.stage;
    record.part = first.part;
    record.cycles = first.cycles;
    record.detail = first.detail;
    record.report_fields = first.report_fields;
    for (std::size_t m = 0; m < chosen.candidates.size(); ++m) {
      const DiscoveryCandidate& c = features_.candidates[static_cast<std::size_t>(chosen.candidates[m])];
      const std::string name = c.joint >= 0 ? prior_.robot().joints[static_cast<std::size_t>(c.joint)].name : "";
      if (m == 0) record.joint_name = name;
      record.joints.push_back(c.joint);
      if (m > 0) record.detail += " + " + (name.empty() ? c.type : name) + c.detail;
      if (c.prior.size() > 0) {
        const std::string suffix = chosen.candidates.size() > 1 ? "_" + std::to_string(m + 1) : "";
        record.report_fields["roughness_weight" + suffix] = chosen.roughness_weight[m];
        record.report_fields["ridge_weight" + suffix] = chosen.ridge_weight[m];
      }
    }
    record.cv_rms_before = std::sqrt(base_fit_.cv / residuals_);
    record.cv_rms_after = std::sqrt(chosen.fit.cv / residuals_);
    record.delta_bic = chosen.delta_bic;
    record.candidates_tried = choice.tried;
    record.runner_up = choice.runner_up;
    record.rejected = joined(undone_, choice.rejected);
    return record;
  }

  // The joint-space residual and the calibrated model. The steps were judged on the prior geometry's load
  // torques; the written files are the final geometry's: the calibration is refitted on those (the effects
  // as accepted) and the final figures are what the written URDF and parameter file give.
  void finish() {
    GeometricCalibrationOptions written_options = calibrationOptions();
    written_options.calibrated_torques = true;
    cal_ = calibration_.calibrate(model_, written_options);
    const CalibratedView written = KinematicCalibration::written(model_, cal_.estimate);
    state_ = evaluate(base_fit_.cv, written.model, written.parameters);
    lin_ = linearise(model_, fittedRows(model_), cal_, features_, active_, cuts_, true);
    result_.joint_residual_rms_final = jointRms(lin_);
    // Where what is left lies (reported when it is well above the noise floor).
    const ResidualRows rows{lin_.joint_residual, lin_.joint_lever, lin_.joint_share, data_.command, data_.motor,
                            lin_.residual_norm,  lin_.time_block,  lin_.residual,    data_.time};
    result_.unexplained = analyseUnexplained(prior_.robot(), rows, cal_.after.rms, result_.noise_floor);
    result_.final_state = state_;
    result_.fitted_rows = cal_.used_rows;
    std::vector<std::string> left_out;
    result_.model = KinematicCalibration::calibratedModel(model_, cal_, left_out);
    result_.calibration = cal_;
  }

  const JointErrorModel& prior_;
  const KinematicCalibration calibration_;  // the fitted campaigns with their instrument set-ups
  const std::vector<MeasurementCampaign>& heldout_;
  const DiscoveryOptions& options_;
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
  double residuals_ = 0.0;
  Fit base_fit_;
  Eigen::VectorXd base_scale_;
  std::vector<int> active_first_;  // first column of each piece in the refit system
  std::string undone_;             // steps undone because their refit was not physical, and why
  const Cuts cuts_;
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
  if (!std::isfinite(options.max_ridge_weight) || options.max_ridge_weight < 0.0) {
    throw InvalidArgument("discover: max_ridge_weight is " + std::to_string(options.max_ridge_weight) +
                          "; it must be finite and >= 0 (0: no ridge)");
  }
  for (int knots : options.table_knots) {
    if (knots < PeriodicTableEffect::kMinKnots || knots > PeriodicTableEffect::kMaxKnots) {
      throw InvalidArgument("discover: a table of " + std::to_string(knots) + " knots; tables have " +
                            std::to_string(PeriodicTableEffect::kMinKnots) + " to " +
                            std::to_string(PeriodicTableEffect::kMaxKnots) + " knots per revolution");
    }
  }
  if (!(options.transfer_significance >= 0.0) || !std::isfinite(options.transfer_significance))
    throw InvalidArgument("discover: transfer_significance must be finite and >= 0");
  if (!(options.min_group_share >= 0.0 && options.min_group_share < 0.5))
    throw InvalidArgument("discover: min_group_share must lie in [0, 0.5)");
  if (options.angle_ranges < 2 || options.angle_ranges > 50)
    throw InvalidArgument("discover: angle_ranges must lie in 2 .. 50");
  if (fitted.empty()) throw InvalidArgument("discover: no fitted campaign");
  std::size_t rows = 0;
  for (const MeasurementCampaign& c : fitted) rows += c.size();
  if (rows > kMaxDiscoveryRows) {
    throw InvalidArgument("discover: the fitted campaigns have " + std::to_string(rows) +
                          " rows, more than discovery takes (" + std::to_string(kMaxDiscoveryRows) +
                          " rows, about 50 KB of memory each)");
  }
  return DiscoveryRun(prior, KinematicCalibration(prior, fitted, options.calibration), heldout, options).run();
}

}  // namespace jointcomp
