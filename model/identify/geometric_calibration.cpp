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

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Median of a chi distribution with 3 degrees of freedom: |r| of a 3-D normal residual of unit sigma per axis.
constexpr double kChi3Median = 1.5381722;

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return s;
}

Eigen::Matrix3d expRotation(const Eigen::Vector3d& r) {
  const double angle = r.norm();
  if (angle == 0.0) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, r / angle).toRotationMatrix();
}

Eigen::Vector3d logRotation(const Eigen::Matrix3d& rotation) {
  const Eigen::AngleAxisd angle_axis(rotation);
  return angle_axis.angle() * angle_axis.axis();
}

// Right Jacobian of the rotation vector: Exp(r + d) = Exp(r) Exp(Jr(r) d) to first order.
Eigen::Matrix3d rightJacobian(const Eigen::Vector3d& r) {
  const double angle = r.norm();
  const Eigen::Matrix3d k = skew(r);
  if (angle < 1e-5) return Eigen::Matrix3d::Identity() - 0.5 * k + (1.0 / 6.0) * k * k;
  const double a2 = angle * angle;
  return Eigen::Matrix3d::Identity() - (1.0 - std::cos(angle)) / a2 * k +
         (angle - std::sin(angle)) / (a2 * angle) * k * k;
}

Eigen::Matrix3d axisRotation(const Eigen::Vector3d& axis, double angle) {
  return Eigen::AngleAxisd(angle, axis).toRotationMatrix();
}

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

// ---- parameters --------------------------------------------------------------------------------------

GeometricParameters GeometricParameters::zero(int dof) {
  GeometricParameters p;
  p.offset = JointVector::Zero(dof);
  p.compliance = JointVector::Zero(dof);
  p.placement.assign(static_cast<std::size_t>(dof), Vector6::Zero());
  return p;
}

Eigen::Isometry3d GeometricParameters::instrumentFromBase() const {
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  transform.linear() = expRotation(frame_rotation);
  transform.translation() = frame_translation;
  return transform;
}

void GeometricParameters::setInstrumentFromBase(const Eigen::Isometry3d& transform) {
  frame_translation = transform.translation();
  frame_rotation = logRotation(transform.linear());
}

GeometricParameters GeometricParameters::ofSetUp(int setup) const {
  if (setup < 0 || setup >= setUpCount()) {
    throw InvalidArgument("geometric parameters: no instrument set-up " + std::to_string(setup + 1) + " of " +
                          std::to_string(setUpCount()));
  }
  GeometricParameters single = *this;
  single.other_setups.clear();
  if (setup > 0) {
    const SetUp& other = other_setups[static_cast<std::size_t>(setup - 1)];
    single.frame_translation = other.frame_translation;
    single.frame_rotation = other.frame_rotation;
    single.instrument_scale = other.instrument_scale;
  }
  return single;
}

void GeometricParameters::setSetUp(int setup, const GeometricParameters& single) {
  if (setup < 0 || setup >= setUpCount()) {
    throw InvalidArgument("geometric parameters: no instrument set-up " + std::to_string(setup + 1) + " of " +
                          std::to_string(setUpCount()));
  }
  if (setup == 0) {
    frame_translation = single.frame_translation;
    frame_rotation = single.frame_rotation;
    instrument_scale = single.instrument_scale;
    return;
  }
  SetUp& other = other_setups[static_cast<std::size_t>(setup - 1)];
  other.frame_translation = single.frame_translation;
  other.frame_rotation = single.frame_rotation;
  other.instrument_scale = single.instrument_scale;
}

int GeometricParameterLayout::setUpOf(int index) const {
  if (index >= kFrame && index < kFrame + 6) return 0;
  if (index == instrumentScale()) return 0;
  if (index >= 10 + 8 * dof && index < size()) return 1 + (index - 10 - 8 * dof) / 7;
  return -1;
}

bool GeometricParameterLayout::isFrame(int index) const {
  const int setup = setUpOf(index);
  return setup >= 0 && index >= frame(setup) && index < frame(setup) + 6;
}

bool GeometricParameterLayout::isInstrumentScale(int index) const {
  const int setup = setUpOf(index);
  return setup >= 0 && index == instrumentScale(setup);
}

Eigen::VectorXd GeometricParameters::toVector() const {
  const GeometricParameterLayout layout(dof(), setUpCount());
  Eigen::VectorXd v(layout.size());
  v.segment<3>(0) = frame_translation;
  v.segment<3>(3) = frame_rotation;
  v.segment<3>(GeometricParameterLayout::kTarget) = target;
  for (int j = 0; j < dof(); ++j) {
    v[layout.offset(j)] = offset[j];
    v.segment<6>(layout.placement(j, 0)) = placement[static_cast<std::size_t>(j)];
    v[layout.compliance(j)] = compliance[j];
  }
  v[layout.instrumentScale()] = instrument_scale;
  for (int s = 1; s < setUpCount(); ++s) {
    const SetUp& other = other_setups[static_cast<std::size_t>(s - 1)];
    v.segment<3>(layout.frame(s)) = other.frame_translation;
    v.segment<3>(layout.frame(s) + 3) = other.frame_rotation;
    v[layout.instrumentScale(s)] = other.instrument_scale;
  }
  return v;
}

GeometricParameters GeometricParameters::fromVector(const Eigen::VectorXd& v, int dof, int setups) {
  if (setups < 1) throw InvalidArgument("geometric parameters: " + std::to_string(setups) + " instrument set-ups");
  const GeometricParameterLayout layout(dof, setups);
  if (v.size() != layout.size()) {
    throw InvalidArgument("geometric parameters: expected " + std::to_string(layout.size()) + " values, found " +
                          std::to_string(v.size()));
  }
  GeometricParameters p = zero(dof);
  p.frame_translation = v.segment<3>(0);
  p.frame_rotation = v.segment<3>(3);
  p.target = v.segment<3>(GeometricParameterLayout::kTarget);
  for (int j = 0; j < dof; ++j) {
    p.offset[j] = v[layout.offset(j)];
    p.placement[static_cast<std::size_t>(j)] = v.segment<6>(layout.placement(j, 0));
    p.compliance[j] = v[layout.compliance(j)];
  }
  p.instrument_scale = v[layout.instrumentScale()];
  p.other_setups.resize(static_cast<std::size_t>(setups - 1));
  for (int s = 1; s < setups; ++s) {
    SetUp& other = p.other_setups[static_cast<std::size_t>(s - 1)];
    other.frame_translation = v.segment<3>(layout.frame(s));
    other.frame_rotation = v.segment<3>(layout.frame(s) + 3);
    other.instrument_scale = v[layout.instrumentScale(s)];
  }
  return p;
}

std::vector<std::string> geometricParameterNames(const Robot& robot, int setups) {
  std::vector<std::string> names = {"frame.tx_m",   "frame.ty_m", "frame.tz_m", "frame.rx_rad", "frame.ry_rad",
                                    "frame.rz_rad", "target.x_m", "target.y_m", "target.z_m"};
  for (const Joint& joint : robot.joints) names.push_back(joint.name + ".offset_rad");
  for (const Joint& joint : robot.joints) {
    for (const char* k : {"dx_m", "dy_m", "dz_m", "rx_rad", "ry_rad", "rz_rad"}) {
      names.push_back(joint.name + ".placement_" + k);
    }
  }
  for (const Joint& joint : robot.joints) names.push_back(joint.name + ".compliance_rad_per_nm");
  names.push_back("instrument.scale");
  for (int s = 1; s < setups; ++s) {
    const std::string prefix = "setup" + std::to_string(s + 1) + ".";
    for (int k = 0; k < 6; ++k) names.push_back(prefix + names[static_cast<std::size_t>(k)]);
    names.push_back(prefix + "instrument.scale");
  }
  return names;
}

std::string geometricParameterUnit(const std::string& name) {
  auto ends = [&](const char* suffix) {
    const std::string s = suffix;
    return name.size() >= s.size() && name.compare(name.size() - s.size(), s.size(), s) == 0;
  };
  if (ends("_rad_per_nm")) return "rad/(N m)";
  if (ends("instrument.scale")) return "1";
  if (ends("_rad")) return "rad";
  return "m";
}

Robot correctedRobot(const Robot& nominal, const GeometricParameters& parameters) {
  if (parameters.dof() != nominal.dof())
    throw InvalidArgument("correctedRobot: parameters and robot differ in joint count");
  Robot robot = nominal;
  for (int j = 0; j < robot.dof(); ++j) {
    const Vector6& c = parameters.placement[static_cast<std::size_t>(j)];
    Eigen::Isometry3d correction = Eigen::Isometry3d::Identity();
    correction.translation() = c.head<3>();
    correction.linear() = expRotation(c.tail<3>());
    robot.joints[static_cast<std::size_t>(j)].placement =
        nominal.joints[static_cast<std::size_t>(j)].placement * correction;
  }
  return robot;
}

// ---- data and model -------------------------------------------------------------------------------------

CalibrationData prepareCalibrationData(const JointErrorModel& prior, const MeasurementCampaign& campaign) {
  const Robot& robot = prior.robot();
  if (!campaign.has_position) {
    throw MeasurementError(campaign.source +
                           ": the campaign has no measured positions (columns x, y, z); the "
                           "kinematic calibration needs them");
  }
  if (campaign.dof != robot.dof()) {
    throw MeasurementError(campaign.source + ": the campaign has " + std::to_string(campaign.dof) +
                           " joint columns, robot '" + robot.name + "' has " + std::to_string(robot.dof()) + " joints");
  }
  if (!campaign.robot.empty() && campaign.robot != robot.name) {  // as parameter files are checked
    throw MeasurementError(campaign.source + ": the campaign is of robot '" + campaign.robot + "', the model of '" +
                           robot.name + "'; a campaign calibrates only the robot it was measured on");
  }
  const std::size_t rows = campaign.command.size();
  if (campaign.position.size() != rows) {
    throw MeasurementError(campaign.source + ": " + std::to_string(campaign.position.size()) + " positions for " +
                           std::to_string(rows) + " commands");
  }
  CalibrationData data;
  data.source = campaign.source;
  data.torque_known = robot.hasInertials();
  // The prior's other joint-error effects (offset and compliance are what is fitted) and all its loads.
  EffectMask loads = 0, others = 0;
  for (int i = 0; i < prior.effectCount(); ++i) {
    const Effect& effect = prior.effect(i);
    if (effect.role() == EffectRole::Load)
      loads |= EffectMask(1) << i;
    else if (!effect.calibrationParameter())
      others |= EffectMask(1) << i;
  }
  JointErrorWorkspace ws(robot);
  JointContext ctx(robot.dof());
  // The robot rests at each row: the side of each joint's lost motion is the one its last move set,
  // remembered along every row with a finite command (used or not), not known before the first move.
  LostMotionMemory memory(robot.dof());
  const JointVector* previous = nullptr;
  for (std::size_t k = 0; k < rows; ++k) {
    const JointVector& command = campaign.command[k];
    const bool command_known = command.size() == robot.dof() && command.allFinite();
    if (command_known) {
      if (previous) memory.move(command - *previous);
      previous = &command;
    }
    const Eigen::Vector3d& position = campaign.position[k];
    if (!command_known || !position.allFinite()) {
      ++data.skipped_rows;
      continue;
    }
    ctx.q = command;
    ctx.command = command;
    ctx.velocity.setZero();
    ctx.approach = memory.sides();
    ctx.time = k < campaign.time.size() ? campaign.time[k] : 0.0;
    const double temperature = k < campaign.temperature.size() ? campaign.temperature[k] : kNaN;
    ctx.temperature = std::isfinite(temperature) ? temperature : 20.0;
    ctx.tool_wrench =
        k < campaign.wrench.size() && campaign.wrench[k].allFinite() ? campaign.wrench[k] : Vector6::Zero();
    ctx.payload_mass = k < campaign.payload.size() && std::isfinite(campaign.payload[k]) ? campaign.payload[k] : 0.0;
    ctx.payload_com = campaign.target_in_flange;
    updateMotorAngles(prior, ctx);
    if (data.torque_known) {
      computeLoadTorque(prior, loads, ws, ctx);
    } else {
      ctx.load_torque.setZero();
    }
    JointVector other = JointVector::Zero(robot.dof());
    if (others != 0) addSelectedJointErrors(prior, others, ctx, other);
    data.row.push_back(static_cast<int>(k));
    data.command.push_back(command);
    data.load_torque.push_back(ctx.load_torque);
    data.approach.push_back(ctx.approach);
    data.other_error.push_back(other);
    data.measured.push_back(position);
    data.setup.push_back(0);
    data.campaign.push_back(0);
  }
  return data;
}

Eigen::Vector3d predictMeasurement(const Robot& robot, const GeometricParameters& p, const JointVector& command,
                                   const JointVector& load_torque, const JointVector& other_error,
                                   Eigen::MatrixXd* jacobian, int setup) {
  const int n = robot.dof();
  const GeometricParameterLayout layout(n, p.setUpCount());
  if (setup < 0 || setup >= p.setUpCount()) {
    throw InvalidArgument("predictMeasurement: no instrument set-up " + std::to_string(setup + 1) + " of " +
                          std::to_string(p.setUpCount()));
  }
  const GeometricParameters::SetUp* other = setup > 0 ? &p.other_setups[static_cast<std::size_t>(setup - 1)] : nullptr;
  const Eigen::Vector3d& frame_r = other ? other->frame_rotation : p.frame_rotation;
  const Eigen::Vector3d& frame_t = other ? other->frame_translation : p.frame_translation;
  // Forward kinematics with the corrections, keeping what the derivatives need.
  std::array<Eigen::Matrix3d, kMaxJoints> rotation_before;     // frame in which d_j is given
  std::array<Eigen::Matrix3d, kMaxJoints> rotation_corrected;  // frame in which r_j acts (and the joint turns)
  std::array<Eigen::Vector3d, kMaxJoints> origin;              // joint origins, base frame
  std::array<Eigen::Vector3d, kMaxJoints> axis;                // joint axes, base frame
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  for (int j = 0; j < n; ++j) {
    const Joint& joint = robot.joints[static_cast<std::size_t>(j)];
    const Vector6& c = p.placement[static_cast<std::size_t>(j)];
    position += rotation * joint.placement.translation();
    rotation = rotation * joint.placement.linear();
    rotation_before[j] = rotation;
    position += rotation * c.head<3>();
    rotation = rotation * expRotation(c.tail<3>());
    rotation_corrected[j] = rotation;
    origin[j] = position;
    axis[j] = rotation * joint.axis;
    const double q = command[j] + p.offset[j] - p.compliance[j] * load_torque[j] + other_error[j];
    rotation = rotation * axisRotation(joint.axis, q);
  }
  const Eigen::Matrix3d tool_rotation = rotation * robot.tool.linear();
  const Eigen::Vector3d point = position + rotation * robot.tool.translation() + tool_rotation * p.target;
  const Eigen::Matrix3d frame_rotation = expRotation(frame_r);
  const Eigen::Vector3d true_position = frame_rotation * point + frame_t;
  const double scale = 1.0 + (other ? other->instrument_scale : p.instrument_scale);
  if (!jacobian) return scale * true_position;

  Eigen::MatrixXd& jac = *jacobian;
  jac.setZero(3, layout.size());
  jac.block<3, 3>(0, layout.frame(setup)).setIdentity();
  jac.block<3, 3>(0, layout.frame(setup) + 3) = -frame_rotation * skew(point) * rightJacobian(frame_r);
  jac.block<3, 3>(0, GeometricParameterLayout::kTarget) = frame_rotation * tool_rotation;
  for (int j = 0; j < n; ++j) {
    const Eigen::Vector3d lever = point - origin[j];
    const Eigen::Vector3d turn = frame_rotation * axis[j].cross(lever);
    jac.col(layout.offset(j)) = turn;
    jac.col(layout.compliance(j)) = -load_torque[j] * turn;
    jac.block<3, 3>(0, layout.placement(j, 0)) = frame_rotation * rotation_before[j];
    jac.block<3, 3>(0, layout.placement(j, 3)) = -frame_rotation * skew(lever) * rotation_corrected[j] *
                                                 rightJacobian(p.placement[static_cast<std::size_t>(j)].tail<3>());
  }
  jac *= scale;  // every column above is of the true position
  jac.col(layout.instrumentScale(setup)) = true_position;
  return scale * true_position;
}

ErrorStatistics errorStatistics(const std::vector<double>& errors) {
  ErrorStatistics s;
  s.rows = static_cast<int>(errors.size());
  if (errors.empty()) return s;
  double sum = 0.0, squares = 0.0;
  for (double e : errors) {
    sum += e;
    squares += e * e;
    s.max = std::max(s.max, e);
  }
  s.mean = sum / static_cast<double>(errors.size());
  s.rms = std::sqrt(squares / static_cast<double>(errors.size()));
  return s;
}

Eigen::Isometry3d fitRigidTransform(const std::vector<Eigen::Vector3d>& from, const std::vector<Eigen::Vector3d>& to) {
  if (from.size() != to.size() || from.size() < 3) {
    throw InvalidArgument("fitRigidTransform: needs at least 3 point pairs, has " + std::to_string(from.size()));
  }
  Eigen::Vector3d mean_from = Eigen::Vector3d::Zero(), mean_to = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < from.size(); ++k) {
    mean_from += from[k];
    mean_to += to[k];
  }
  mean_from /= static_cast<double>(from.size());
  mean_to /= static_cast<double>(to.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < from.size(); ++k) covariance += (to[k] - mean_to) * (from[k] - mean_from).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  if (svd.singularValues()[1] <= 1e-12 * std::max(1.0, svd.singularValues()[0])) {
    throw InvalidArgument("fitRigidTransform: the points lie on a line; the rotation is not determined");
  }
  Eigen::Matrix3d correction = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0) correction(2, 2) = -1.0;
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  transform.linear() = svd.matrixU() * correction * svd.matrixV().transpose();
  transform.translation() = mean_to - transform.linear() * mean_from;
  return transform;
}

namespace {

int findCalibrationEffect(const JointErrorModel& model, CalibrationParameter parameter) {
  for (int i = 0; i < model.effectCount(); ++i) {
    if (model.effect(i).calibrationParameter() == parameter) return i;
  }
  return -1;
}

}  // namespace

GeometricParameters nominalParameters(const JointErrorModel& prior, const MeasurementCampaign& campaign) {
  const int n = prior.robot().dof();
  GeometricParameters p = GeometricParameters::zero(n);
  if (campaign.has_target) p.target = campaign.target_in_flange;
  // The first effect holding each of the calibration's own per-joint parameters is where it starts.
  const int offset = findCalibrationEffect(prior, CalibrationParameter::Offset);
  if (offset >= 0) {
    for (int j = 0; j < n; ++j) p.offset[j] = prior.effect(offset).calibrationValue(j);
  }
  const int compliance = findCalibrationEffect(prior, CalibrationParameter::Compliance);
  if (compliance >= 0) {
    for (int j = 0; j < n; ++j) p.compliance[j] = prior.effect(compliance).calibrationValue(j);
  }
  return p;
}

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
    if (!fit_frame) continue;
    GeometricParameters single = start.ofSetUp(s);
    single.setInstrumentFromBase(fitRigidTransform(points, own.measured));
    start.setSetUp(s, single);
  }

  // "Before": the nominal robot with only its frames fitted (robustly, like the calibration).
  if (fit_frame) {
    const FitOutcome frame_fit =
        fitSubset(robot, data, start.toVector(), frameIndices(GeometricParameterLayout(n, data.setups)), options, 0.0,
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
      reason[static_cast<std::size_t>(i)] = "fixed by request";
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
      if (std::find(free.begin(), free.end(), i) != free.end()) continue;
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

// The fit; a compliance that comes out not positive is held at its nominal value and the fit repeated.
FitOutcome fitKeepingCompliancePositive(const Robot& robot, const CalibrationData& data,
                                        const Eigen::VectorXd& nominal_values,
                                        const GeometricCalibrationOptions& options, ParameterChoice& choice) {
  const int n = robot.dof();
  const GeometricParameterLayout layout(n);
  std::vector<int>& free = choice.free;
  std::vector<std::string>& reason = choice.reason;
  FitOutcome fit = fitSubset(robot, data, nominal_values, free, options, 0.0, "calibrating");
  for (int round = 0; round < n; ++round) {
    std::vector<int> dropped;
    for (int j = 0; j < n; ++j) {
      const int i = layout.compliance(j);
      if (std::find(free.begin(), free.end(), i) != free.end() && !(fit.values[i] > 0.0)) dropped.push_back(i);
    }
    if (dropped.empty()) break;
    for (int i : dropped) {
      reason[static_cast<std::size_t>(i)] = "fitted " + fmt("%.3g", fit.values[i]) +
                                            " rad/(N m), not positive: held at nominal " +
                                            fmt("%.3g", nominal_values[i]);
      free.erase(std::find(free.begin(), free.end(), i));
      fit.values[i] = nominal_values[i];
    }
    fit = fitSubset(robot, data, fit.values, free, options, fit.loss_scale, "calibrating");
  }
  return fit;
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
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(weighted);
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

}  // namespace

void checkCampaignsAgree(const std::vector<MeasurementCampaign>& campaigns) {
  if (campaigns.empty()) throw InvalidArgument("no campaign given");
  const MeasurementCampaign& first = campaigns.front();
  for (const MeasurementCampaign& m : campaigns) {
    if (m.dof != first.dof || m.frame != first.frame || m.has_position != first.has_position) {
      throw InvalidArgument("campaign '" + m.source + "' differs from '" + first.source +
                            "' in joints, frame (base or instrument) or positions; campaigns used together must "
                            "agree in all three");
    }
    if (!m.robot.empty() && !first.robot.empty() && m.robot != first.robot) {
      throw InvalidArgument("campaign '" + m.source + "' is of robot '" + m.robot + "', '" + first.source +
                            "' of robot '" + first.robot + "'; campaigns used together must be of one robot");
    }
  }
}

MeasurementCampaign concatenateCampaigns(const std::vector<MeasurementCampaign>& campaigns) {
  checkCampaignsAgree(campaigns);
  MeasurementCampaign all = campaigns.front();
  for (std::size_t c = 1; c < campaigns.size(); ++c) {
    const MeasurementCampaign& m = campaigns[c];
    const double shift = (all.time.empty() ? 0.0 : all.time.back() + 1.0) - (m.time.empty() ? 0.0 : m.time.front());
    for (std::size_t k = 0; k < m.size(); ++k) {
      all.time.push_back(m.time[k] + shift);
      all.command.push_back(m.command[k]);
      all.position.push_back(m.position[k]);
      all.temperature.push_back(k < m.temperature.size() ? m.temperature[k] : kNaN);
      all.wrench.push_back(k < m.wrench.size() ? m.wrench[k] : Vector6::Zero());
      all.payload.push_back(k < m.payload.size() ? m.payload[k] : 0.0);
      if (all.has_measured_angles) {
        all.measured_angles.push_back(k < m.measured_angles.size() ? m.measured_angles[k]
                                                                   : JointVector::Constant(all.dof, kNaN));
      }
    }
    all.source += "+" + m.source;
  }
  return all;
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

void assignCampaigns(CalibrationData& data, const std::vector<MeasurementCampaign>& campaigns,
                     const std::vector<int>& setup_of_campaign) {
  if (campaigns.empty() || setup_of_campaign.size() != campaigns.size()) {
    throw InvalidArgument(data.source + ": " + std::to_string(setup_of_campaign.size()) + " set-ups given for " +
                          std::to_string(campaigns.size()) + " campaigns");
  }
  std::vector<bool> used(campaigns.size(), false);
  for (int s : setup_of_campaign) {
    if (s < 0 || s >= static_cast<int>(campaigns.size())) {
      throw InvalidArgument(data.source + ": instrument set-up " + std::to_string(s) + " of " +
                            std::to_string(campaigns.size()) + " campaigns");
    }
    used[static_cast<std::size_t>(s)] = true;
  }
  data.setups = 1 + *std::max_element(setup_of_campaign.begin(), setup_of_campaign.end());
  if (std::find(used.begin(), used.begin() + data.setups, false) != used.begin() + data.setups) {
    throw InvalidArgument(data.source + ": instrument set-ups must be numbered 0, 1, ... without gaps");
  }
  std::size_t campaign = 0, end = campaigns.front().size();
  for (std::size_t k = 0; k < data.size(); ++k) {
    while (static_cast<std::size_t>(data.row[k]) >= end) {
      if (++campaign == campaigns.size()) throw InvalidArgument(data.source + ": a row beyond the campaigns given");
      end += campaigns[campaign].size();
    }
    data.setup[k] = setup_of_campaign[campaign];
    data.campaign[k] = static_cast<int>(campaign);
  }
}

CalibrationData prepareCalibrationData(const JointErrorModel& prior, const std::vector<MeasurementCampaign>& campaigns,
                                       const std::vector<int>& setup_of_campaign) {
  CalibrationData data = prepareCalibrationData(prior, concatenateCampaigns(campaigns));
  assignCampaigns(data, campaigns, setup_of_campaign);
  return data;
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
  const MeasurementCampaign whole = concatenateCampaigns(campaigns);
  const std::string& source = whole.source;
  for (const MeasurementCampaign& c : campaigns) {
    if (c.has_target != whole.has_target || (c.has_target && c.target_in_flange != whole.target_in_flange)) {
      throw InvalidArgument("campaign '" + c.source + "' names another target in the flange than '" +
                            campaigns.front().source + "'; one calibration fits one target");
    }
  }
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
  const FitOutcome fit = fitKeepingCompliancePositive(robot, data, nominal_values, options, choice);
  result.estimate = GeometricParameters::fromVector(fit.values, n, setups);
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

namespace {

// Each prepared row's residual in its set-up's frame, and mapped to the joints.
std::vector<RowResidual> residualsOf(const Robot& robot, const GeometricParameters& used, const CalibrationData& data) {
  const int n = robot.dof();
  const GeometricParameterLayout layout(n, used.setUpCount());
  std::vector<RowResidual> out(data.size());
  constexpr double kDamping = 1e-3;  // m per rad
  Eigen::MatrixXd jacobian;
  Eigen::Matrix<double, 3, Eigen::Dynamic> joint_columns(3, n);
  for (std::size_t k = 0; k < data.size(); ++k) {
    const Eigen::Vector3d predicted = predictMeasurement(robot, used, data.command[k], data.load_torque[k],
                                                         data.other_error[k], &jacobian, data.setup[k]);
    RowResidual& r = out[k];
    r.row = data.row[k];
    r.error = data.measured[k] - predicted;
    for (int j = 0; j < n; ++j) joint_columns.col(j) = jacobian.col(layout.offset(j));
    // Damped least squares (minimum norm, damping 1 mm per rad): near a singular pose the plain
    // pseudo-inverse would blow the mapping up; away from one the damping changes it by ~1e-6.
    const Eigen::Matrix3d gram =
        joint_columns * joint_columns.transpose() + kDamping * kDamping * Eigen::Matrix3d::Identity();
    r.joint_error = joint_columns.transpose() * gram.ldlt().solve(r.error);
  }
  return out;
}

// In the base frame there is no frame: whatever the parameters hold, the rows are predicted without one.
GeometricParameters withoutFrames(GeometricParameters used) {
  used.frame_translation.setZero();
  used.frame_rotation.setZero();
  for (GeometricParameters::SetUp& other : used.other_setups) {
    other.frame_translation.setZero();
    other.frame_rotation.setZero();
  }
  return used;
}

}  // namespace

std::vector<RowResidual> rowResiduals(const JointErrorModel& model, const GeometricParameters& parameters,
                                      const MeasurementCampaign& campaign) {
  const CalibrationData data = prepareCalibrationData(model, campaign);
  const GeometricParameters used = parameters.ofSetUp(0);
  return residualsOf(model.robot(), campaign.frame == MeasurementFrame::Base ? withoutFrames(used) : used, data);
}

std::vector<RowResidual> rowResiduals(const JointErrorModel& model, const GeometricParameters& parameters,
                                      const std::vector<MeasurementCampaign>& campaigns,
                                      const std::vector<int>& setup_of_campaign) {
  const CalibrationData data = prepareCalibrationData(model, campaigns, setup_of_campaign);
  if (parameters.setUpCount() < data.setups) {
    throw InvalidArgument(data.source + ": parameters of " + std::to_string(parameters.setUpCount()) +
                          " instrument set-ups for campaigns from " + std::to_string(data.setups));
  }
  const bool base = campaigns.front().frame == MeasurementFrame::Base;
  return residualsOf(model.robot(), base ? withoutFrames(parameters) : parameters, data);
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
  const bool fit = refit_frame && campaign.frame == MeasurementFrame::Instrument;
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

JointErrorModel calibratedJointErrorModel(const JointErrorModel& prior, std::shared_ptr<const Robot> calibrated_robot,
                                          const GeometricCalibrationResult& result,
                                          std::vector<std::string>& left_out) {
  const Robot& robot = *calibrated_robot;
  const int n = robot.dof();
  if (n != prior.robot().dof()) throw InvalidArgument("calibratedJointErrorModel: robots differ in joint count");
  left_out.clear();
  std::vector<std::unique_ptr<Effect>> effects;
  for (int i = 0; i < prior.effectCount(); ++i) {
    if (prior.effect(i).calibrationParameter()) continue;  // replaced by the calibration's values below
    effects.push_back(prior.effect(i).clone());
  }
  std::vector<double> offsets(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) offsets[static_cast<std::size_t>(j)] = result.estimate.offset[j];
  auto offset = std::make_unique<JointOffsetEffect>(robot, offsets);
  offset->estimate_note = "kinematic calibration on " + std::to_string(result.used_rows) + " rows";
  effects.push_back(std::move(offset));

  const GeometricParameterLayout layout(n);
  const int prior_compliance = findCalibrationEffect(prior, CalibrationParameter::Compliance);
  std::vector<double> stiffness(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) {
    const ParameterEstimate& c = result.parameters[static_cast<std::size_t>(layout.compliance(j))];
    const std::string& joint = robot.joints[static_cast<std::size_t>(j)].name;
    if (!c.identified && prior_compliance >= 0 && c.value == c.nominal) {
      stiffness[static_cast<std::size_t>(j)] = prior.effect(prior_compliance).parameters()[static_cast<std::size_t>(j)];
    } else if (c.value > 0.0) {
      stiffness[static_cast<std::size_t>(j)] = 1.0 / c.value;
    } else {
      // Rigid in the file: nothing known to compensate on this joint.
      stiffness[static_cast<std::size_t>(j)] = std::numeric_limits<double>::infinity();
      left_out.push_back(joint + ": " + (c.identified ? "fitted compliance not positive" : c.fixed_because) +
                         (c.value == 0.0 ? " (no prior stiffness; written as rigid)" : " (written as rigid)"));
    }
  }
  {
    auto compliance = std::make_unique<ComplianceEffect>(robot, stiffness);
    compliance->estimate_note = "kinematic calibration: 1 / fitted compliance under the load torque";
    effects.push_back(std::move(compliance));
  }
  JointErrorModel model(std::move(calibrated_robot), prior.gears(), std::move(effects));
  model.notes = prior.notes;
  return model;
}

MeasurementCampaign simulateGeometricCampaign(const JointErrorModel& prior, const GeometricParameters& truth,
                                              const std::vector<JointVector>& commands, double noise,
                                              std::uint64_t seed, const Eigen::Vector3d& nominal_target) {
  const Robot& robot = prior.robot();
  MeasurementCampaign campaign;
  campaign.source = "simulated campaign (seed " + std::to_string(seed) + ")";
  campaign.robot = robot.name;
  campaign.frame = MeasurementFrame::Instrument;
  campaign.has_target = true;
  campaign.target_in_flange = nominal_target;
  campaign.position_noise = noise;
  campaign.dof = robot.dof();
  campaign.has_position = true;
  for (std::size_t k = 0; k < commands.size(); ++k) {
    campaign.time.push_back(static_cast<double>(k));
    campaign.command.push_back(commands[k]);
    campaign.position.emplace_back(Eigen::Vector3d::Zero());
    campaign.temperature.push_back(kNaN);
    campaign.wrench.emplace_back(Vector6::Zero());
    campaign.payload.push_back(0.0);
  }
  const CalibrationData data = prepareCalibrationData(prior, campaign);
  DeterministicRandom random(seed);
  for (std::size_t k = 0; k < data.size(); ++k) {
    Eigen::Vector3d p = predictMeasurement(robot, truth, data.command[k], data.load_torque[k], data.other_error[k]);
    for (int a = 0; a < 3; ++a) p[a] += noise * random.normal();
    campaign.position[static_cast<std::size_t>(data.row[k])] = p;
  }
  campaign.validate();
  return campaign;
}

}  // namespace jointcomp
