// Residual discovery: which effect does the nominal model miss? Starting from a base calibration
// (calibrateGeometry: frame and target, optionally the textbook geometry), candidate effects of the
// registry's vocabulary are fitted to the Cartesian residual, one at a time, each jointly with every
// free parameter of the current model (linearised at the current fit: the columns are the derivatives of
// the predicted measurement, joint effects entering through the joint Jacobian dm/dq_j times their
// feature). The candidate that most lowers the time-blocked K-fold cross-validation error (blocks of
// consecutive rows) is accepted when it also lowers an extended BIC,
//   dBIC = N ln(RSS_c / RSS_0) + dk ln N + 2 ln(M)      (N residuals, dk added rank, M candidates tried),
// and when it transfers: predicted from the other folds, it makes no fold more than 1 % worse (a term that
// helps one part of the data and hurts another is rejected, and the report says so). Of the candidates
// statistically tied with the best (within one standard error of the fold-wise differences), the one
// with the fewest parameters is taken. The accepted candidate is
// then added to the model and every free parameter refitted together (Gauss-Newton steps on the effects'
// parameters jointly with the geometry, alternated with calibrateGeometry); repeated until no candidate
// passes or max_steps.
//
// Candidates: every discovery family of the effect registry (model/effects/registry.hpp) offers its own,
// per joint and for the whole robot, with the columns they bring and the calibration parameters they free;
// the family turns the accepted coefficients into its effect and names their estimates. The built-in
// vocabulary is EffectRegistry::builtin().discoveryVocabulary() (`jointcomp help` prints it); each family's
// comment (model/effects) says what its columns are. A user's effect type joins through its own registry
// (DiscoveryOptions::registry).
//
// Ra and Rz on paths: for every fitted or held-out campaign that is a path (isPathCampaign), each state
// gives Ra = mean |z_k| and Rz = max z_k - min z_k (metrics.hpp) of the Z component, in the robot's base
// frame, of the error measured - predicted of its rows (all rows, not robustly weighted), as the paper
// scores its spiral.
//
// Library code: never prints; throws InvalidArgument for unusable inputs, with the campaign's name.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "model/effects/registry.hpp"
#include "model/identify/joint_coverage.hpp"
#include "model/identify/kinematic_calibration.hpp"
#include "model/identify/residual_analysis.hpp"

namespace jointcomp {

// The most fitted rows discovery takes, all campaigns together: its candidates' columns and the
// linearised problem grow by about 50 KB a row (20,000 rows: about 1 GB), so 100,000 rows need about 5 GB.
// Beyond it discoverEffects refuses, naming the number.
constexpr std::size_t kMaxDiscoveryRows = 100000;

struct DiscoveryOptions {
  DiscoveryOptions();  // out of line: GCC 12 warns falsely of the inlined defaults of its std::function
  // fit_* flags are set by discovery; loss and solver are used, and progress hears the calibrations' phases
  // and iterations and discovery's own steps.
  GeometricCalibrationOptions calibration;
  // false: the base model frees only the frame and the target; offsets, compliance and joint placements are
  // candidates ("offset", "compliance", "geometric"). true: the textbook base frees them all from the start.
  bool base_geometry = false;
  int folds = 5;
  int max_steps = 8;
  int max_harmonic_order = 4;
  double min_cv_gain = 0.02;       // relative drop of the CV error a candidate must bring
  double noise_floor = 0.0;        // m, 3-D RMS; 0: sqrt(3) times the campaigns' position_noise
  int refit_iterations = 1;        // joint refits after each accepted step
  double velocity_scale = 1e-3;    // rad/s, backlash smooth sign
  std::vector<std::string> types;  // candidate types to try; empty: all
  // The largest weight of a candidate's prior (a periodic table's roughness), relative to the data of one
  // column; cross-validation on the fitted data chooses among 0 and five decades up to it. 0: no prior.
  double max_prior_weight = 10.0;
  // The same for the ridge toward zero that every candidate with a prior also gets (knots the data barely
  // reach stay near zero); chosen together with the roughness weight.
  double max_ridge_weight = 1.0;
  // Knots per revolution of the periodic tables offered (each part of each joint, every count).
  std::vector<int> table_knots = {16, 32, 64, 128};
  // Pairs: the best candidate of one family on each of two joints, fitted together, compete when they lower
  // the CV error by more than their members alone summed (effects that only help together are found).
  bool pairs = true;
  // The transfer check. A candidate is rejected when, predicted from the other groups, it makes a group of
  // rows (a time block, a part of the joint space, a range of one of its joints' angles) worse by more than
  // 1 % and by more than transfer_significance standard errors of that group's change (its sub-blocks'
  // spread). Joint-space parts smaller than min_group_share of the rows join the nearest larger part.
  double transfer_significance = 3.0;
  double min_group_share = 0.05;
  int angle_ranges = 5;  // ranges of a joint's angle, equally filled, for leave-one-range-out CV
  // The held-out campaigns were measured with the fitted campaigns' instrument (the same tracker, not moved):
  // an instrument scale discovery finds applies to them too. false: each is another set-up.
  bool heldout_same_instrument = false;
  const EffectRegistry* registry = nullptr;  // whose discovery families compete; null: the built-in one
};

// The built-in vocabulary of discovered effect types (the built-in registry's families, in order).
const std::vector<std::string>& discoveryEffectTypes();

using DiscoveredParameter = NamedEstimate;  // e.g. "shoulder_lift_joint.backlash_width_rad"

struct PathRoughness {
  bool held_out = false;
  int campaign = 0;  // index among the fitted (held_out false) or held-out campaigns
  int rows = 0;
  double ra = 0.0, rz = 0.0;  // m, of the Z error
};

// A campaign is a path when its metadata says "protocol: spiral" (jointcomp simulate) or its rows were
// taken while moving: at least 20 rows, the median time step between consecutive rows at most 0.1 s
// (a tracker sampling at 10 Hz or faster), as opposed to poses settled one by one.
bool isPathCampaign(const MeasurementCampaign& campaign);

struct DiscoveryState {
  ErrorStatistics fitted;                // on the fitted rows (calibration's "after")
  std::vector<ErrorStatistics> heldout;  // one per held-out campaign, frame re-fitted
  double cv_rms = 0.0;                   // m per axis, time-blocked CV of the linearised model
  std::vector<PathRoughness> paths;      // fitted paths first, then held-out ones; empty: no path
};

struct DiscoveryStep {
  std::string type;
  int joint = -1;                        // -1 for payload (the whole robot); of a pair, its first
  std::vector<int> joints;               // every candidate's joint (two for a pair of candidates)
  std::string joint_name;                // "" for payload; of a pair, its first (detail names the second)
  int stage = 0;                         // harmonic: 1 = motor ... stageCount + 1 = output
  std::string part;                      // harmonic: "motor", "stage_k", "output"; thermal: "temperature" or "time"
  double cycles = 0.0;                   // harmonic order (cycles per revolution of the part)
  std::string detail;                    // the candidate's label detail, e.g. " motor order 2" or " (time)"
  nlohmann::ordered_json report_fields;  // what the family reports beside type and joint
  std::vector<DiscoveredParameter> parameters;
  double cv_rms_before = 0.0, cv_rms_after = 0.0;  // m per axis
  double delta_bic = 0.0;
  int candidates_tried = 0;
  std::string runner_up;  // best rejected / next candidate, for the evidence
  std::string rejected;   // the best candidate that lowered the CV error but hurt a part of the data, and why
  DiscoveryState before, after;
};

// How far a held-out campaign goes beyond the joint angles the fit visited (DiscoveryResult::coverage).
struct HeldoutCoverage {
  std::vector<double> fraction_outside;  // per joint, of its rows
  bool flagged = false;                  // some joint has more than kCoverageFlagFraction of its rows outside
  double median_pose_distance = 0.0;     // rad, median distance of its poses to the nearest fitted pose
};
constexpr double kCoverageHalfWidth = 0.0872664626;  // rad (5 deg) around every fitted row's angle
constexpr double kCoverageFlagFraction = 0.05;

struct DiscoveryResult {
  JointErrorModel model;                   // prior + discovered effects, offsets and compliance as fitted
  GeometricCalibrationResult calibration;  // the final base fit (geometry, frame, target)
  std::vector<DiscoveryStep> steps;
  DiscoveryState initial, final_state;
  std::vector<double> joint_residual_rms_initial, joint_residual_rms_final;  // rad, residual mapped to joints
  double noise_floor = 0.0;                                                  // m, 3-D RMS
  std::string stop_reason;
  std::string rejected_at_stop;  // as DiscoveryStep::rejected, for the step that was not taken
  int fitted_rows = 0;
  int candidates = 0;
  JointCoverage coverage;                         // of the fitted rows
  std::vector<HeldoutCoverage> heldout_coverage;  // one per held-out campaign
  UnexplainedResidual unexplained;                // where the final fit's residual lies
  explicit DiscoveryResult(JointErrorModel m) : model(std::move(m)) {}
};

// Fitted campaigns from different instrument set-ups (instrumentSetUps) are fitted together, each set-up
// with its own frame (and scale, once the instrument_scale candidate is accepted). Throws InvalidArgument
// for no fitted campaign, campaigns of another robot or in different frames (base and instrument).
DiscoveryResult discoverEffects(const JointErrorModel& prior, const std::vector<MeasurementCampaign>& fitted,
                                const std::vector<MeasurementCampaign>& heldout, const DiscoveryOptions& options = {});

}  // namespace jointcomp
