// The measurement model of the kinematic calibration (geometric_calibration.hpp): the named parameters,
// their flat layout, the corrected robot and the predicted instrument reading with its Jacobian.
#include "model/identify/geometric_calibration.hpp"

#include <cmath>
#include <cstdio>

#include <Eigen/SVD>

#include "model/common/errors.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {
namespace {

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

std::string geometryBeyondLimits(const Robot& robot, const GeometricParameters& p, const GeometryLimits& limits) {
  if (p.dof() != robot.dof()) throw InvalidArgument("geometryBeyondLimits: parameters and robot differ in joint count");
  std::string out;
  const auto beyond = [&](const std::string& what, double size, double limit, const char* unit, double shown) {
    if (size <= limit) return;  // false for NaN: a NaN is beyond
    char text[240];
    std::snprintf(text, sizeof(text), "%s %.4g %s beyond the plausible %.4g %s", what.c_str(), size * shown, unit,
                  limit * shown, unit);
    out += (out.empty() ? "" : "; ") + std::string(text);
  };
  constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;
  for (int j = 0; j < robot.dof(); ++j) {
    const std::string& name = robot.joints[static_cast<std::size_t>(j)].name;
    const Vector6& c = p.placement[static_cast<std::size_t>(j)];
    beyond(name + ".offset_rad: the joint's zero moves by", std::abs(p.offset[j]), limits.offset, "deg",
           kDegreesPerRadian);
    beyond(name + ".placement_d*_m: the joint's axis moves in its link by", c.head<3>().norm(), limits.placement_shift,
           "mm", 1e3);
    beyond(name + ".placement_r*_rad: the joint's axis turns in its link by", c.tail<3>().norm(), limits.placement_turn,
           "deg", kDegreesPerRadian);
  }
  return out;
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

}  // namespace jointcomp
