// Kinematic ("geometric") calibration from measured target positions: the instrument-to-base transform,
// the target on the flange, the joint offsets, corrections of every joint placement and the joint
// compliances under gravity, solved as one nonlinear least-squares problem over named free parameters
// (in the manner of ROS robot_calibration), on the identifiable subset only.
//
// Measurement model of a row with commanded joints q_c (rad), load torque tau (the joint-error model's
// load torque at q_c: gravity, payload, wrench and load effects) and the joint error e_c of the prior's
// other joint-error effects (not "offset", not "compliance"):
//   q      = q_c + offset - compliance .* tau + e_c                      (link-side joint angles)
//   p_base = FK(q) * target,  joint i placed at  placement_i * Trans(d_i) * Exp(r_i)
//   m      = Exp(frame_r) * p_base + frame_t                              (what the instrument sees)
// with placement_i the nominal Joint::placement, (d_i, r_i) the six corrections of joint i, Exp the
// rotation of a rotation vector. Residual = m - measured, per row 3 values (m).
//
// Parameters (SI, named like the parameter files):
//   frame.tx_m frame.ty_m frame.tz_m frame.rx_rad frame.ry_rad frame.rz_rad   instrument-from-base
//   target.x_m target.y_m target.z_m                                         target in the tool frame
//   <joint>.offset_rad                                                       per joint
//   <joint>.placement_{dx,dy,dz}_m, <joint>.placement_{rx,ry,rz}_rad         per joint
//   <joint>.compliance_rad_per_nm                                            per joint
//
// Campaigns from several instrument set-ups (the tracker moved between them) are calibrated together:
// the robot's parameters are shared, each set-up has its own frame (and scale), named setup<k>.frame.*.
//
// Procedure of calibrateGeometry: rows without a measured position are skipped (and counted); each
// set-up's frame starts from the closed-form rigid fit of the nominal points to its measured ones; the Jacobian
// at that start point decides the identifiable subset (identifiability.hpp, priorities: frame, target,
// offsets, placement translations, placement rotations, compliance); Levenberg-Marquardt fits the subset
// by least squares, then again with the robust loss whose scale comes from the least-squares residuals;
// a compliance fitted outside its physical constraint (ComplianceEffect::implausibility: not positive, too
// soft, deflecting too far) is fixed at its nominal value and the fit repeated; then the fit is repeated with
// the load torques of the calibrated geometry (calibrated_torques), so that the written URDF and parameter
// file give the reported errors; the covariance is sigma^2 (J^T W J)^-1 with sigma^2 the weighted residual
// variance. "Before" is the nominal robot with only its frame fitted (the same robust way; in the base
// frame, no frame), so that before and after differ by the robot alone.
//
// Units inside are SI; the robust loss acts on each row's 3-D error norm (Huber by default, scale 3 robust
// sigma), and the result counts the rows it weighed down. Library code: never prints, throws the typed
// errors of model/common/errors.hpp with the campaign's name in the message.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "model/common/errors.hpp"
#include "model/common/progress.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/identify/identifiability.hpp"
#include "model/identify/levenberg_marquardt.hpp"
#include "model/io/measurement_campaign.hpp"

namespace jointcomp {

struct GeometricParameters {
  Eigen::Vector3d frame_translation = Eigen::Vector3d::Zero();  // m, base origin in the instrument frame
  Eigen::Vector3d frame_rotation = Eigen::Vector3d::Zero();     // rotation vector (rad), instrument from base
  Eigen::Vector3d target = Eigen::Vector3d::Zero();             // m, tool frame
  JointVector offset;                                           // rad
  std::vector<Vector6> placement;                               // per joint: d (m), r (rad)
  JointVector compliance;                                       // rad / (N m)
  // Relative scale error of the instrument (a tracker's distance scale, the set-up's temperature): it
  // measures (1 + instrument_scale) times the true coordinates. Fitted only on request (discovery's
  // instrument_scale candidate); a held-out campaign, another set-up, is evaluated without it.
  double instrument_scale = 0.0;
  // The other instrument set-ups of a calibration on campaigns measured from several (the tracker moved
  // between them): each its own frame and scale; the fields above are the first set-up's. Empty for one.
  struct SetUp {
    Eigen::Vector3d frame_translation = Eigen::Vector3d::Zero();
    Eigen::Vector3d frame_rotation = Eigen::Vector3d::Zero();
    double instrument_scale = 0.0;
  };
  std::vector<SetUp> other_setups;

  // Everything zero for a robot of `dof` joints.
  static GeometricParameters zero(int dof);
  int dof() const { return static_cast<int>(offset.size()); }
  int setUpCount() const { return 1 + static_cast<int>(other_setups.size()); }
  Eigen::Isometry3d instrumentFromBase() const;
  void setInstrumentFromBase(const Eigen::Isometry3d& transform);
  // The robot's parameters with set-up `setup`'s frame and scale as the only set-up: what one campaign of
  // that set-up is predicted with.
  GeometricParameters ofSetUp(int setup) const;
  // Set-up `setup`'s frame and scale taken from single-set-up parameters (the others unchanged).
  void setSetUp(int setup, const GeometricParameters& single);

  // The flat vector in the order of geometricParameterNames, and back.
  Eigen::VectorXd toVector() const;
  static GeometricParameters fromVector(const Eigen::VectorXd& values, int dof, int setups = 1);
};

// Index of the first parameter of each group in the flat vector. The first set-up's frame and scale come
// first and last of the robot's parameters (as for one set-up); each further set-up appends its frame
// (6) and scale (1).
struct GeometricParameterLayout {
  explicit GeometricParameterLayout(int dof_, int setups_ = 1) : dof(dof_), setups(setups_) {}
  int dof;
  int setups;
  static constexpr int kFrame = 0;   // 6
  static constexpr int kTarget = 6;  // 3
  int offset(int joint) const { return 9 + joint; }
  int placement(int joint, int k) const { return 9 + dof + 6 * joint + k; }  // k: dx dy dz rx ry rz
  int compliance(int joint) const { return 9 + 7 * dof + joint; }
  int instrumentScale() const { return 9 + 8 * dof; }
  int frame(int setup) const { return setup == 0 ? kFrame : 10 + 8 * dof + 7 * (setup - 1); }
  int instrumentScale(int setup) const { return setup == 0 ? instrumentScale() : frame(setup) + 6; }
  // The set-up whose frame or scale parameter `index` is, or -1 for a parameter of the robot or target.
  int setUpOf(int index) const;
  bool isFrame(int index) const;
  bool isInstrumentScale(int index) const;
  int size() const { return 10 + 8 * dof + 7 * (setups - 1); }
};

// Set-up k > 0's parameters are named "setup<k+1>.frame.tx_m" ... "setup<k+1>.instrument.scale".
std::vector<std::string> geometricParameterNames(const Robot& robot, int setups = 1);
// The unit in the name: "m", "rad" or "rad/(N m)".
std::string geometricParameterUnit(const std::string& name);

// The robot with its joint placements corrected: placement_i * Trans(d_i) * Exp(r_i). Offsets and
// compliance are joint errors (the "offset" and "compliance" effects), not geometry.
Robot correctedRobot(const Robot& nominal, const GeometricParameters& parameters);

// How far a real robot's geometry can be from its URDF: a joint's zero (a mastering error; 0.1 rad, 5.7 deg,
// is a whole motor turn slipped on a gear of 63:1 or more) and where its axis sits in its link (machining
// and assembly, tenths of a millimetre and of a degree on real arms; the UR10 of ../shared/data moves by at
// most 0.8 mm and 1.3 mrad). A calibration that needs more is describing its URDF or its data, not the
// robot, and is refused (ImplausibleGeometry).
struct GeometryLimits {
  double offset = 0.1;            // rad, |offset| of each joint
  double placement_shift = 0.02;  // m, |(dx, dy, dz)| of each joint's placement
  double placement_turn = 0.05;   // rad, |(rx, ry, rz)|, the angle the axis is turned by (2.9 deg)
};

// A calibration whose fitted geometry lies beyond its GeometryLimits.
class ImplausibleGeometry : public InvalidArgument {
public:
  using InvalidArgument::InvalidArgument;
};

// Empty when every joint's offset and placement of `p` lies within `limits`; else each one beyond them,
// named, with its size and its limit ("joint_3.offset_rad 0.2 rad (11.5 deg) beyond the plausible ...").
// NaN limits or parameters are beyond.
std::string geometryBeyondLimits(const Robot& robot, const GeometricParameters& p, const GeometryLimits& limits);

// The rows of a campaign in the form the measurement model needs.
struct CalibrationData {
  std::string source;
  std::vector<int> row;                   // campaign row (0-based) of each used row
  std::vector<JointVector> command;       // rad
  std::vector<JointVector> load_torque;   // N m
  std::vector<JointVector> approach;      // side of each joint's lost motion, remembered along all rows
  std::vector<JointVector> other_error;   // rad, the prior's other joint-error effects
  std::vector<Eigen::Vector3d> measured;  // m, in the campaign's frame
  std::vector<int> setup;                 // instrument set-up of each used row (0 for one campaign)
  std::vector<int> campaign;              // campaign of each used row (0 for one campaign)
  int setups = 1;
  int skipped_rows = 0;      // rows without a measured position (NaN / empty cells)
  bool torque_known = true;  // false when the robot has no inertials (no compliance then)
  std::size_t size() const { return row.size(); }
};

// Throws MeasurementError when the campaign has no position columns or its joint count differs from the
// robot's; never fails for a row with a NaN position (skipped and counted) or a NaN command (the same).
CalibrationData prepareCalibrationData(const JointErrorModel& prior, const MeasurementCampaign& campaign);
// Several campaigns as one: the rows of their concatenation (concatenateCampaigns; `row` indexes it, and
// the lost motion's memory runs on across campaigns, as for one campaign), each row with the set-up of
// its campaign (setup_of_campaign, one per campaign, 0-based and without gaps).
CalibrationData prepareCalibrationData(const JointErrorModel& prior, const std::vector<MeasurementCampaign>& campaigns,
                                       const std::vector<int>& setup_of_campaign);
// The same for rows already prepared from the campaigns' concatenation (without copying the campaigns again):
// each row's campaign and set-up. Throws InvalidArgument for set-ups not numbered 0, 1, ... or rows beyond
// the campaigns.
void assignCampaigns(CalibrationData& data, const std::vector<MeasurementCampaign>& campaigns,
                     const std::vector<int>& setup_of_campaign);

// The predicted instrument reading of a row measured from set-up `setup` and, when `jacobian` is not
// null, its derivative by every parameter (3 x GeometricParameterLayout(dof, setUpCount()).size()).
Eigen::Vector3d predictMeasurement(const Robot& nominal, const GeometricParameters& parameters,
                                   const JointVector& command, const JointVector& load_torque,
                                   const JointVector& other_error, Eigen::MatrixXd* jacobian = nullptr, int setup = 0);

// The residual of one used row, measured - predicted, in the campaign's frame, and the same mapped to the
// joints: the smallest joint errors dq that explain it to first order (damped least squares on the joint
// columns of the measurement's Jacobian), for users who analyse what a model leaves.
struct RowResidual {
  int row = 0;  // campaign row (0-based)
  Eigen::Vector3d error = Eigen::Vector3d::Zero();
  JointVector joint_error;  // rad
};
// The campaign is predicted with the first set-up's frame: pass parameters.ofSetUp(s) for set-up s.
std::vector<RowResidual> rowResiduals(const JointErrorModel& model, const GeometricParameters& parameters,
                                      const MeasurementCampaign& campaign);
// The rows of several campaigns as one calibration saw them (prepareCalibrationData's concatenation: `row`
// indexes it), each in its set-up's frame.
std::vector<RowResidual> rowResiduals(const JointErrorModel& model, const GeometricParameters& parameters,
                                      const std::vector<MeasurementCampaign>& campaigns,
                                      const std::vector<int>& setup_of_campaign);

// Mean, RMS and max of the 3-D error norms (m).
struct ErrorStatistics {
  int rows = 0;
  double mean = 0.0;
  double rms = 0.0;
  double max = 0.0;
};
ErrorStatistics errorStatistics(const std::vector<double>& errors);

struct GeometricCalibrationOptions {
  // Which groups are free (the frame only when the campaign is in the instrument frame: a campaign in the
  // base frame has none to fit).
  bool fit_frame = true;
  bool fit_target = true;
  bool fit_offsets = true;
  bool fit_placements = true;
  bool fit_compliance = true;
  bool fit_instrument_scale = false;  // a property of the set-up, not the robot: only when asked
  // evaluateOnCampaign: the held-out campaign was measured with the fitted campaigns' (first) instrument set-up,
  // so its instrument scale applies; false: another set-up, evaluated without it
  bool same_instrument = false;
  std::vector<std::string> fixed;  // parameter names held at nominal whatever the data say
  // What the fitted offsets and placements may come to: a fit beyond is refused (ImplausibleGeometry).
  GeometryLimits limits;
  IdentifiabilityOptions identifiability;
  RobustLoss loss = RobustLoss::Huber;
  // Scale k of the robust loss (m); 0: loss_scale_sigmas times the robust per-axis sigma of the
  // least-squares residuals (median of the 3-D error norms / 1.538, the median of a chi with 3 dof).
  double loss_scale = 0.0;
  double loss_scale_sigmas = 3.0;
  int minimum_rows = 10;
  // Refit with the load torques of the calibrated geometry (the written URDF's) and report the rows' errors
  // with them, so that the written files give the reported figures; false: the prior's torques throughout.
  bool calibrated_torques = true;
  LevenbergMarquardtOptions solver;  // loss and block size are set by the calibration
  Progress progress;                 // told the phases and each accepted step (may be empty)
};

// Whether the first set-up's frame is kept: all six frame.* names are fixed (`--fix base`). A campaign with
// a known base frame (MeasurementCampaign::base_frame) is then predicted in it and fitted like a campaign
// in the base frame (nothing re-fitted, held-out campaigns in their own base frames); otherwise the
// given frame is where the fit of the first set-up's frame starts.
bool baseFrameKept(const GeometricCalibrationOptions& options);

struct ParameterEstimate {
  std::string name;
  std::string unit;
  double nominal = 0.0;
  double value = 0.0;
  double sigma = 0.0;                                          // 1 sigma; 0 for a fixed parameter
  bool identified = false;                                     // free in the final fit
  double pivot = 0.0;                                          // relative pivot of its column at the start point
  std::string fixed_because;                                   // empty when identified
  std::vector<std::pair<std::string, double>> redundant_with;  // name, ratio (see Redundancy)
};

struct GeometricCalibrationResult {
  std::vector<std::string> names;
  GeometricParameters nominal;  // the start: prior offsets and compliance, campaign target, frame fitted
  GeometricParameters estimate;
  std::vector<ParameterEstimate> parameters;
  std::vector<int> free;                   // indices into names of the parameters of the final fit
  Eigen::MatrixXd covariance;              // of the free parameters, in the order of `free`
  double condition_number_at_start = 0.0;  // kept columns, unit-scaled, at the start point
  double condition_number = 0.0;           // the same at the solution, weighted
  double residual_sigma = 0.0;             // m per axis, sqrt(sum w r^2 / (residuals - free))
  RobustLoss loss = RobustLoss::None;
  double loss_scale = 0.0;  // m
  int used_rows = 0;
  int skipped_rows = 0;
  int downweighted_rows = 0;         // weight below 0.999 in the final fit
  int outlier_rows = 0;              // weight below 0.5 (Huber: error above twice the scale)
  std::vector<int> row;              // campaign row of each used row
  std::vector<double> error_before;  // m per used row: nominal robot, frame fitted
  std::vector<double> error_after;   // m per used row: calibrated
  std::vector<double> weight;        // final IRLS weight per used row
  ErrorStatistics before, after;
  GeometricParameters nominal_frame_fit;         // the nominal robot with its frame fitted ("before")
  bool frame_fitted = true;                      // false: campaigns in the base frame, no frame to fit
  std::vector<std::string> compliance_left_out;  // "<joint>: reason" for the compliances not written
  int iterations = 0;
  std::string stop_reason;
  // Several campaigns: `row` is each used row's row in its own campaign, `campaign_of_row` which campaign
  // (index into the campaigns given), `setup_of_campaign` the instrument set-up each was measured from.
  std::vector<std::string> sources;
  std::vector<int> campaign_of_row;
  std::vector<int> setup_of_campaign;
};

// Throws InvalidArgument for too few rows (fewer than options.minimum_rows usable, or fewer residuals
// than twice the identifiable parameters) or degenerate poses (all rows at one pose, collinear points,
// an instrument frame the poses cannot determine), MeasurementError for a campaign without positions or
// of another robot, SolverError when Levenberg-Marquardt does not converge. Messages name the campaign.
GeometricCalibrationResult calibrateGeometry(const JointErrorModel& prior, const MeasurementCampaign& campaign,
                                             const GeometricCalibrationOptions& options = {});

// The most rows a calibration takes, all campaigns together: its memory grows by about 3.4 KB a row (100,000
// rows of a six-joint arm: 335 MB; the Jacobian by every candidate parameter and its Gram-Schmidt copy in the
// identifiability analysis, docs/performance.md), 1e6 rows about 3.4 GB.
// Beyond it calibrateGeometry refuses, naming the number.
constexpr std::size_t kMaxCalibrationRows = 1000000;

// Campaigns in the instrument frame whose frames, each fitted alone on the prior, lie further apart than
// this are from different set-ups (a nominal robot's frame fit moves by millimetres between campaigns of one).
constexpr double kSameSetUpDistance = 0.05;       // m
constexpr double kSameSetUpAngle = 0.0349065850;  // rad (2 deg)

// The instrument set-up of each campaign (0, 1, ...; the first campaign's is 0): a campaign joins the first
// set-up whose first campaign's frame, fitted on the prior, is within kSameSetUpDistance and
// kSameSetUpAngle of its own, else starts a new one. Campaigns in the base frame are one set-up without a
// frame. Throws InvalidArgument for campaigns in different frames (base and instrument) or of other joint
// counts, naming them.
struct InstrumentSetUps {
  std::vector<int> setup_of_campaign;
  std::vector<Eigen::Isometry3d> frame_of_campaign;  // instrument from base, fitted on the prior (identity: base)
  int count() const;
};
InstrumentSetUps instrumentSetUps(const JointErrorModel& prior, const std::vector<MeasurementCampaign>& campaigns,
                                  const GeometricCalibrationOptions& options = {});

// One calibration of the robot on campaigns measured from one or several instrument set-ups: the robot's
// parameters are shared, each set-up has its own frame (and scale, when fitted). With one campaign it is
// calibrateGeometry above. The set-ups are instrumentSetUps' unless given. Messages name the campaign (or
// "A+B" for the whole).
GeometricCalibrationResult calibrateGeometry(const JointErrorModel& prior,
                                             const std::vector<MeasurementCampaign>& campaigns,
                                             const GeometricCalibrationOptions& options = {});
GeometricCalibrationResult calibrateGeometry(const JointErrorModel& prior,
                                             const std::vector<MeasurementCampaign>& campaigns,
                                             const std::vector<int>& setup_of_campaign,
                                             const GeometricCalibrationOptions& options);

// The campaigns as one (rows appended in order, times shifted to stay non-decreasing, sources joined by
// '+'). Throws InvalidArgument (checkCampaignsAgree) for campaigns of other joint counts, frames or without
// positions.
MeasurementCampaign concatenateCampaigns(const std::vector<MeasurementCampaign>& campaigns);
void checkCampaignsAgree(const std::vector<MeasurementCampaign>& campaigns);

// The nominal parameters a calibration starts from: offsets and compliance (1 / stiffness) of the prior's
// "offset" and "compliance" effects (zero without them), the campaign's target (zero without one),
// identity frame.
GeometricParameters nominalParameters(const JointErrorModel& prior, const MeasurementCampaign& campaign);

// The rigid transform minimising sum |R p_i + t - m_i|^2 (Kabsch / Horn, by SVD). Throws InvalidArgument
// for fewer than 3 points or points on a line.
Eigen::Isometry3d fitRigidTransform(const std::vector<Eigen::Vector3d>& from, const std::vector<Eigen::Vector3d>& to);

// A held-out campaign checked with given robot parameters: only the six frame parameters are re-fitted
// (each instrument set-up has its own), robustly as in the calibration; with refit_frame false the
// frame of `parameters` is used as it is (the first set-up's, when it has several).
struct HoldoutEvaluation {
  std::string source;
  GeometricParameters parameters;  // with the frame used
  std::vector<int> row;
  std::vector<double> error;  // m per used row
  std::vector<double> weight;
  ErrorStatistics statistics;
  int skipped_rows = 0;
  int downweighted_rows = 0;  // weight below 0.999
  int outlier_rows = 0;       // weight below 0.5
  double loss_scale = 0.0;
};
HoldoutEvaluation evaluateOnCampaign(const JointErrorModel& prior, const GeometricParameters& parameters,
                                     const MeasurementCampaign& campaign, bool refit_frame,
                                     const GeometricCalibrationOptions& options = {});

// The calibrated joint-error model: the prior's effects with the "offset" effect (fitted offsets) in place
// of any prior one and the "compliance" effect with stiffness 1 / compliance (fitted, or the prior's where
// it was not fitted); a joint with neither a positive fitted compliance nor a prior is written as rigid
// and `left_out` says why. The robot is `calibrated_robot`.
JointErrorModel calibratedJointErrorModel(const JointErrorModel& prior, std::shared_ptr<const Robot> calibrated_robot,
                                          const GeometricCalibrationResult& result, std::vector<std::string>& left_out);

// What the written files describe: the prior's effects on the corrected robot (correctedRobot), and the
// parameters with their placement corrections moved into that robot (zero). Predicted with these, a row's
// load torques are those of the calibrated geometry, as compensation with the written URDF computes them.
struct CalibratedView {
  JointErrorModel model;
  GeometricParameters parameters;
};
CalibratedView asWritten(const JointErrorModel& prior, const GeometricParameters& estimate);

// Simulated measurements for tests and planning: the instrument reading of every command under the given
// true parameters, plus normal noise of `noise` (m, per axis), seeded. frame = instrument, target = the
// nominal target given (what the file would say), no temperature.
MeasurementCampaign simulateGeometricCampaign(const JointErrorModel& prior, const GeometricParameters& truth,
                                              const std::vector<JointVector>& commands, double noise,
                                              std::uint64_t seed, const Eigen::Vector3d& nominal_target);

}  // namespace jointcomp
