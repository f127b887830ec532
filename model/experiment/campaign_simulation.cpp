#include "model/experiment/campaign_simulation.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <memory>

#include <Eigen/QR>
#include <Eigen/SVD>

#include "model/common/errors.hpp"
#include "model/common/random.hpp"
#include "model/compensation/joint_trajectory.hpp"
#include "model/effects/backlash.hpp"
#include "model/experiment/spiral_experiment.hpp"
#include "model/identify/identification_support.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegree = kPi / 180.0;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string formatNumber(double value) {
  char buffer[40];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

void tell(const std::function<void(const std::string&)>& progress, const std::string& what) {
  if (progress) progress(what);
}

using identify_detail::toolWrenchOf;

class Simulator {
public:
  Simulator(const JointErrorModel& truth, const CampaignSimulationSpec& spec)
      : truth_(truth),
        robot_(truth.robot()),
        spec_(spec),
        ws_(robot_),
        random_(spec.seed ^ 0xA5A5A5A55A5A5A5AULL),
        noise_(spec.seed),
        ctx_(robot_.dof()),
        lost_motion_(robot_.dof()) {
    if (!spec.target_in_flange.allFinite()) throw InvalidArgument("simulation: target_in_flange is not finite");
    if (!(spec.tracker.constant_m >= 0.0 && spec.tracker.per_metre >= 0.0 &&
          spec.tracker.tracker_position.allFinite())) {
      throw InvalidArgument("simulation: tracker noise model must be non-negative and finite");
    }
    if (!(spec.level.sigma_rad >= 0.0)) throw InvalidArgument("simulation: level sigma must be non-negative");
    if (spec.temperature.enabled &&
        !(std::isfinite(spec.temperature.start_degc) && std::isfinite(spec.temperature.rise_degc) &&
          spec.temperature.time_constant_s > 0.0 && std::isfinite(spec.temperature.time_constant_s))) {
      throw InvalidArgument(
          "simulation: the temperature profile needs a finite start and rise and a positive time constant");
    }
    campaign_.source = "simulated " + protocolName(spec.protocol) + " campaign";
    campaign_.robot = robot_.name;
    campaign_.frame = MeasurementFrame::Base;
    campaign_.has_target = true;
    campaign_.target_in_flange = spec.target_in_flange;
    campaign_.dof = robot_.dof();
    campaign_.has_position = true;
    stiffness_ = truth.jointStiffness();
  }

  const Robot& robot() const { return robot_; }
  JointErrorWorkspace& ws() { return ws_; }
  // Draws of the protocol (poses) and of the instruments come from two streams, so that switching the
  // noise off leaves the poses as they were.
  DeterministicRandom& random() { return random_; }
  DeterministicRandom& noise() { return noise_; }
  const JointVector& stiffness() const { return stiffness_; }
  MeasurementCampaign& campaign() { return campaign_; }

  // The quasi-static robot at `command` under a wrench at the target and a payload: the link angles.
  // `velocity` is that of the move into `command` (zero for a joint that did not move): the side of each
  // joint's lost motion is the one its last move set, remembered across rows as on a real robot.
  JointVector settle(const JointVector& command, const JointVector& velocity, const Vector6& wrench_at_target,
                     double payload, double t) {
    ctx_.command = command;
    ctx_.time = t;
    ctx_.temperature = spec_.temperature.enabled ? spec_.temperature.at(t) : JointContext().temperature;
    ctx_.velocity = velocity;
    ctx_.approach = lost_motion_.move(velocity);
    ctx_.payload_mass = payload;
    ctx_.payload_com = spec_.target_in_flange;
    forwardKinematics(robot_, ws_.robot, command);
    // Two passes: the moment of the force about the tool point is taken where the target really is.
    const int passes = wrench_at_target.isZero(0.0) ? 1 : 2;
    for (int pass = 0; pass < passes; ++pass) {
      ctx_.tool_wrench = toolWrenchOf(wrench_at_target, ws_.robot, spec_.target_in_flange);
      const FixedPointReport report = settleStatically(truth_, truth_.allEffects(), ws_, ctx_);
      if (!report.converged) {
        throw SolverError("simulation: the quasi-static robot did not settle at row " +
                          std::to_string(campaign_.size()) + " (residual " + formatNumber(report.residual) + " rad)");
      }
      forwardKinematics(robot_, ws_.robot, ctx_.q);
    }
    return ctx_.q;
  }

  // The tracker's reading of the target with the links at q.
  Eigen::Vector3d measureTarget(const JointVector& q) {
    forwardKinematics(robot_, ws_.robot, q);
    Eigen::Vector3d target = ws_.robot.tool_pose * spec_.target_in_flange;
    const double sigma = spec_.tracker.sigma(target);
    sigma_sum2_ += sigma * sigma;
    ++sigma_count_;
    if (!spec_.noise) return target;
    const double nx = noise_.normal();
    const double ny = noise_.normal();
    const double nz = noise_.normal();
    return target + sigma * Eigen::Vector3d(nx, ny, nz);
  }

  void addRow(double t, const JointVector& command, const JointVector& q, const Vector6& wrench, double payload,
              const JointVector& measured_angles = JointVector()) {
    campaign_.time.push_back(t);
    campaign_.command.push_back(command);
    campaign_.position.push_back(measureTarget(q));
    campaign_.temperature.push_back(spec_.temperature.enabled && !plant_ ? spec_.temperature.at(t) : kNaN);
    campaign_.wrench.push_back(wrench);
    campaign_.payload.push_back(payload);
    if (measured_angles.size() > 0) {
      if (!campaign_.has_measured_angles) {
        campaign_.has_measured_angles = true;
        campaign_.measured_angles.assign(campaign_.time.size() - 1, JointVector::Constant(robot_.dof(), kNaN));
      }
      campaign_.measured_angles.push_back(measured_angles);
    } else if (campaign_.has_measured_angles) {
      campaign_.measured_angles.emplace_back(JointVector::Constant(robot_.dof(), kNaN));
    }
  }

  MeasurementCampaign finish() {
    campaign_.metadata["protocol"] = protocolName(spec_.protocol);
    campaign_.metadata["seed"] = std::to_string(spec_.seed);
    campaign_.metadata["simulated_by"] = "jointcomp simulate (" + simulated_robot_ + ")";
    for (const auto& entry : spec_.metadata) campaign_.metadata[entry.first] = entry.second;
    if (spec_.noise) {
      campaign_.position_noise = sigma_count_ > 0 ? std::sqrt(sigma_sum2_ / sigma_count_) : 0.0;
      writeTrackerNoise(spec_.tracker, campaign_);
      if (campaign_.has_measured_angles) {
        campaign_.angle_noise = std::sqrt(2.0) * spec_.level.sigma_rad;  // difference of two levels
        writeLevelNoise(spec_.level, campaign_);
      }
    } else {
      campaign_.metadata["noise"] = "none (exact measurements)";
    }
    campaign_.validate();
    return std::move(campaign_);
  }

  void setSimulatedRobot(const std::string& what) {
    simulated_robot_ = what;
    plant_ = true;
  }

  // Reading of an electronic level fixed to the body of joint `body` (-1: the base), set up at the
  // commanded pose to read 0 and to sense rotation about `axis`: the rotation of a link-fixed horizontal
  // direction about it. Needs forward kinematics at the commanded pose in `commanded`, at the actual
  // pose in ws().robot.
  static double levelReading(int body, const RobotWorkspace& commanded, const RobotWorkspace& actual,
                             const Eigen::Vector3d& axis, const Eigen::Vector3d& up) {
    if (body < 0) return 0.0;
    const Eigen::Vector3d u = up.cross(axis).normalized();  // horizontal, normal to the axis
    const Eigen::Vector3d w = axis.cross(u);                // = up for a horizontal axis
    const Eigen::Vector3d local = commanded.joint_pose[body].linear().transpose() * u;
    const Eigen::Vector3d now = actual.joint_pose[body].linear() * local;
    return std::atan2(now.dot(w), now.dot(u));
  }

private:
  const JointErrorModel& truth_;
  const Robot& robot_;
  const CampaignSimulationSpec& spec_;
  JointErrorWorkspace ws_;
  DeterministicRandom random_;
  DeterministicRandom noise_;
  JointContext ctx_;
  LostMotionMemory lost_motion_;
  JointVector stiffness_;
  MeasurementCampaign campaign_;
  double sigma_sum2_ = 0.0;
  long sigma_count_ = 0;
  std::string simulated_robot_ = "quasi-static robot";
  bool plant_ = false;  // rows from the plant: no temperature column
};

void checkPose(const Robot& robot, const JointVector& pose, const std::string& what) {
  if (pose.size() != robot.dof() || !pose.allFinite()) {
    throw InvalidArgument(what + ": needs " + std::to_string(robot.dof()) + " finite joint values");
  }
  for (int j = 0; j < robot.dof(); ++j) {
    if (pose[j] < robot.joints[j].lower || pose[j] > robot.joints[j].upper) {
      throw InvalidArgument(what + ": " + robot.joints[j].name + " = " + formatNumber(pose[j] / kDegree) +
                            " deg is outside its limits");
    }
  }
}

// Largest factor by which a load giving joint torques `tau` may be scaled: every joint deflects at most
// max_deflection and carries at most effort_fraction of its effort limit.
double loadScaleLimit(const Robot& robot, const JointVector& stiffness, const JointVector& tau, double max_deflection,
                      double effort_fraction) {
  double scale = std::numeric_limits<double>::infinity();
  for (int i = 0; i < robot.dof(); ++i) {
    const double magnitude = std::abs(tau[i]);
    if (magnitude < 1e-12) continue;
    if (std::isfinite(stiffness[i])) scale = std::min(scale, max_deflection * stiffness[i] / magnitude);
    if (robot.joints[i].effort_limit > 0.0) {
      scale = std::min(scale, effort_fraction * robot.joints[i].effort_limit / magnitude);
    }
  }
  return scale;
}

// The load ladder of one local test: 0 up to +1, down to -1, back to 0.
std::vector<double> loadLadder(int levels) {
  const int half = (levels - 1) / 2;
  std::vector<double> ladder;
  for (int k = 0; k <= half; ++k) ladder.push_back(static_cast<double>(k) / half);
  for (int k = half - 1; k >= -half; --k) ladder.push_back(static_cast<double>(k) / half);
  for (int k = -half + 1; k <= 0; ++k) ladder.push_back(static_cast<double>(k) / half);
  return ladder;
}

double conditioning(const Jacobian& jacobian) {
  const Eigen::MatrixXd matrix = jacobian;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(matrix);
  const Eigen::VectorXd& s = svd.singularValues();
  return s[s.size() - 1] / s[0];
}

JointVector randomPose(const Robot& robot, DeterministicRandom& random, double margin) {
  JointVector q(robot.dof());
  for (int j = 0; j < robot.dof(); ++j) {
    double low = std::isfinite(robot.joints[j].lower) ? robot.joints[j].lower : -kPi;
    double high = std::isfinite(robot.joints[j].upper) ? robot.joints[j].upper : kPi;
    if (high - low > 2.0 * margin) {
      low += margin;
      high -= margin;
    }
    q[j] = random.uniform(low, high);
  }
  return q;
}

// The stiffness protocol's settings and the joints it tests; throws InvalidArgument naming what is wrong.
std::vector<int> checkedStiffnessJoints(const Simulator& sim, const CampaignSimulationSpec& spec, JointVector& pose) {
  const Robot& robot = sim.robot();
  const StiffnessProtocolSpec& p = spec.stiffness;
  const int n = robot.dof();
  if (!sim.stiffness().allFinite()) {
    throw InvalidArgument("stiffness protocol: the truth has no compliance effect (nothing would deflect)");
  }
  if (p.load_levels < 3 || p.load_levels % 2 == 0) {
    throw InvalidArgument("stiffness protocol: load_levels must be odd and at least 3");
  }
  if (!(p.max_deflection_rad > 0.0) || !(p.effort_fraction > 0.0) || !(p.row_period_s > 0.0)) {
    throw InvalidArgument("stiffness protocol: max_deflection_rad, effort_fraction and row_period_s must be positive");
  }
  if (p.global_poses < 0) throw InvalidArgument("stiffness protocol: global_poses must not be negative");
  pose = p.pose.size() > 0 ? p.pose : defaultStiffnessPose(robot);
  checkPose(robot, pose, "stiffness protocol pose");
  std::vector<int> joints = p.joints;
  if (joints.empty()) {
    for (int j = 0; j < n; ++j) joints.push_back(j);
  }
  for (int j : joints) {
    if (j < 0 || j >= n)
      throw InvalidArgument("stiffness protocol: tested joint " + std::to_string(j + 1) + " does not exist");
  }
  if (p.level_joint >= n)
    throw InvalidArgument("stiffness protocol: level_joint " + std::to_string(p.level_joint + 1) + " does not exist");
  return joints;
}

// The local tests: per joint, a ladder of loads at the test pose that turns that joint alone (or, for the
// level joint, 1 N upwards, read by two levels). Returns the time after the last row.
double localStiffnessTests(Simulator& sim, const CampaignSimulationSpec& spec, const JointVector& pose,
                           const std::vector<int>& joints, const std::function<void(const std::string&)>& progress) {
  const Robot& robot = sim.robot();
  const StiffnessProtocolSpec& p = spec.stiffness;
  const int n = robot.dof();
  const Eigen::Vector3d up = -robot.gravity.normalized();
  const std::vector<double> ladder = loadLadder(p.load_levels);
  JointErrorWorkspace& ws = sim.ws();
  RobotWorkspace commanded(robot);
  Jacobian jacobian(6, n);
  const JointVector rest = JointVector::Zero(n);
  double t = 0.0;
  for (int j : joints) {
    tell(progress, "local stiffness test of " + robot.joints[j].name);
    forwardKinematics(robot, commanded, pose);
    const Eigen::Vector3d target = commanded.tool_pose * spec.target_in_flange;
    pointJacobian(robot, commanded, target, jacobian);
    const bool by_levels = j == p.level_joint;
    Vector6 unit_wrench = Vector6::Zero();
    if (by_levels) {
      if (std::abs(commanded.axis[j].dot(up)) > 0.9) {
        throw InvalidArgument("stiffness protocol: " + robot.joints[j].name +
                              " has a vertical axis at the test pose; levels cannot see its rotation");
      }
      unit_wrench[2] = 1.0;  // 1 N upwards at the target
    } else {
      // A wrench at the target with J^T w = e_j: it loads joint j alone.
      const Eigen::MatrixXd jt = Eigen::MatrixXd(jacobian).transpose();
      const Eigen::VectorXd unit = Eigen::VectorXd::Unit(n, j);
      unit_wrench = Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(jt).solve(unit);
      // Round-off dust (and negative zeros) out of the file.
      const double largest = unit_wrench.cwiseAbs().maxCoeff();
      for (int i = 0; i < 6; ++i) unit_wrench[i] = std::abs(unit_wrench[i]) < 1e-12 * largest ? 0.0 : unit_wrench[i];
    }
    const JointVector tau = jacobian.transpose() * unit_wrench;
    if (std::abs(tau[j]) < 1e-9) {
      throw InvalidArgument("stiffness protocol: no load at the target turns " + robot.joints[j].name +
                            " at the test pose (singular pose)");
    }
    const double scale = loadScaleLimit(robot, sim.stiffness(), tau, p.max_deflection_rad, p.effort_fraction);
    for (double level : ladder) {
      const Vector6 wrench = (unit_wrench * (scale * level)).array() + 0.0;  // + 0.0: no negative zeros
      const JointVector q = sim.settle(pose, rest, wrench, 0.0, t);
      JointVector measured;
      if (by_levels) {
        // Two levels: on the link before the joint and on the link after it; each reading has its noise.
        const Eigen::Vector3d axis = commanded.axis[j];
        const double before = Simulator::levelReading(j - 1, commanded, ws.robot, axis, up);
        const double after = Simulator::levelReading(j, commanded, ws.robot, axis, up);
        double noise_before = 0.0;
        double noise_after = 0.0;
        if (spec.noise) {
          noise_before = spec.level.sigma_rad * sim.noise().normal();
          noise_after = spec.level.sigma_rad * sim.noise().normal();
        }
        measured = JointVector::Constant(n, kNaN);
        measured[j] = pose[j] + (after + noise_after) - (before + noise_before);
      }
      sim.addRow(t, pose, q, wrench, 0.0, measured);
      t += p.row_period_s;
    }
  }

  return t;
}

// The global poses: random well-conditioned poses, each unloaded and under a force or moment along every
// axis in both directions.
void globalStiffnessPoses(Simulator& sim, const CampaignSimulationSpec& spec, double t,
                          const std::function<void(const std::string&)>& progress) {
  const Robot& robot = sim.robot();
  const StiffnessProtocolSpec& p = spec.stiffness;
  const int n = robot.dof();
  RobotWorkspace commanded(robot);
  Jacobian jacobian(6, n);
  const JointVector rest = JointVector::Zero(n);
  if (p.global_poses > 0) tell(progress, "global stiffness poses");
  int accepted = 0;
  for (int attempt = 0; accepted < p.global_poses; ++attempt) {
    if (attempt > 2000 * p.global_poses) {
      throw SolverError("stiffness protocol: found only " + std::to_string(accepted) + " of " +
                        std::to_string(p.global_poses) + " well-conditioned global poses");
    }
    const JointVector q_pose = randomPose(robot, sim.random(), p.global_limit_margin_rad);
    forwardKinematics(robot, commanded, q_pose);
    const Eigen::Vector3d target = commanded.tool_pose * spec.target_in_flange;
    if (target.z() < 0.1) continue;
    pointJacobian(robot, commanded, target, jacobian);
    if (conditioning(jacobian) < p.min_conditioning) continue;
    ++accepted;
    std::vector<Vector6> wrenches{Vector6::Zero()};
    for (int axis = 0; axis < 6; ++axis) {
      for (double sign : {1.0, -1.0}) {
        Vector6 w = Vector6::Zero();
        w[axis] = sign * (axis < 3 ? p.global_force_n : p.global_moment_nm);
        const JointVector tau = jacobian.transpose() * w;
        w *= std::min(1.0, loadScaleLimit(robot, sim.stiffness(), tau, p.max_deflection_rad, p.effort_fraction));
        wrenches.emplace_back((w.array() + 0.0).matrix());
      }
    }
    for (const Vector6& wrench : wrenches) {
      const JointVector q = sim.settle(q_pose, rest, wrench, 0.0, t);
      sim.addRow(t, q_pose, q, wrench, 0.0);
      t += p.row_period_s;
    }
  }
}

void simulateStiffness(Simulator& sim, const CampaignSimulationSpec& spec,
                       const std::function<void(const std::string&)>& progress) {
  JointVector pose;
  const std::vector<int> joints = checkedStiffnessJoints(sim, spec, pose);
  const double t = localStiffnessTests(sim, spec, pose, joints, progress);
  globalStiffnessPoses(sim, spec, t, progress);
}

// The command sequence of a sweep: from -> to (and back, for back-and-forth) in steps.
std::vector<double> sweepValues(const JointSweepSpec& s, bool back_and_forth) {
  if (!std::isfinite(s.from_rad) || !std::isfinite(s.to_rad) || !(s.step_rad > 0.0) || s.to_rad == s.from_rad) {
    throw InvalidArgument("joint sweep: from and to must differ and step must be positive");
  }
  const double span = s.to_rad - s.from_rad;
  const double ratio = std::abs(span) / s.step_rad;
  if (!(ratio <= static_cast<double>(kMaxSweepRows))) {
    throw InvalidArgument("joint sweep: " + formatNumber(ratio) + " steps are more than " +
                          std::to_string(kMaxSweepRows) + " rows");
  }
  const long steps = std::lround(ratio);
  if (steps < 1) throw InvalidArgument("joint sweep: the step does not fit the range");
  std::vector<double> one_way;
  for (long k = 0; k <= steps; ++k) one_way.push_back(s.from_rad + span * static_cast<double>(k) / steps);
  if (!back_and_forth) return one_way;
  if (s.cycles < 1) throw InvalidArgument("back-and-forth: cycles must be at least 1");
  if (s.cycles > kMaxSweepRows / (2 * steps)) {
    throw InvalidArgument("back-and-forth: " + std::to_string(s.cycles) + " cycles of " + std::to_string(2 * steps) +
                          " steps are more than " + std::to_string(kMaxSweepRows) + " rows");
  }
  std::vector<double> values{one_way.front()};
  for (int c = 0; c < s.cycles; ++c) {
    values.insert(values.end(), one_way.begin() + 1, one_way.end());
    values.insert(values.end(), one_way.rbegin() + 1, one_way.rend());
  }
  return values;
}

void simulateSweep(Simulator& sim, const CampaignSimulationSpec& spec, bool back_and_forth,
                   const JointErrorModel& truth, const std::function<void(const std::string&)>& progress) {
  const Robot& robot = sim.robot();
  const JointSweepSpec& s = spec.sweep;
  const int n = robot.dof();
  if (s.joint < 0 || s.joint >= n)
    throw InvalidArgument("joint sweep: joint " + std::to_string(s.joint + 1) + " does not exist");
  if (!(s.settle_s > 0.0) || !(s.move_speed_rad_s > 0.0)) {
    throw InvalidArgument("joint sweep: settle_s and move_speed_rad_s must be positive");
  }
  JointVector pose = s.pose.size() > 0 ? s.pose : defaultStiffnessPose(robot);
  const std::vector<double> values = sweepValues(s, back_and_forth);
  for (double value : {s.from_rad, s.to_rad}) {
    pose[s.joint] = value;
    checkPose(robot, pose, "joint sweep");
  }
  tell(progress, "sweeping " + robot.joints[s.joint].name + " over " + std::to_string(values.size()) + " steps");
  const double move_time = s.step_rad / s.move_speed_rad_s;
  const JointVector rest = JointVector::Zero(n);
  std::unique_ptr<FlexibleJointPlant> plant;
  if (!spec.drives.empty()) {
    plant = std::make_unique<FlexibleJointPlant>(truth, spec.drives, spec.plant);
    sim.setSimulatedRobot("flexible-joint plant, " + formatNumber(s.settle_s) + " s settling per step");
  }
  double t = 0.0;
  double direction = values.size() > 1 && values[1] < values[0] ? -1.0 : 1.0;
  for (std::size_t k = 0; k < values.size(); ++k) {
    JointVector command = pose;
    command[s.joint] = values[k];
    if (k > 0) direction = values[k] > values[k - 1] ? 1.0 : -1.0;
    JointVector velocity = rest;
    velocity[s.joint] = direction * s.move_speed_rad_s;
    if (plant) {
      if (k == 0) {
        plant->reset(command, 0.0);
        plant->advance(s.settle_s);
      } else {
        JointVector previous = pose;
        previous[s.joint] = values[k - 1];
        // A ramp at the move speed, then the new position held for the settling time. Each reference is
        // set twice so that the controller sees no acceleration between two updates.
        plant->setReference(previous, velocity);
        plant->setReference(previous, velocity);
        plant->advance(plant->time() + move_time);
        plant->setReference(command, rest);
        plant->setReference(command, rest);
        plant->advance(plant->time() + s.settle_s);
      }
      t = plant->time();
      sim.addRow(t, command, plant->linkPositions(), Vector6::Zero(), 0.0);
      if (progress && k % 500 == 499)
        tell(progress, "  step " + std::to_string(k + 1) + " of " + std::to_string(values.size()));
    } else {
      // The settled robot is at rest; it is given the velocity of its last move so that effects which
      // depend on the direction of approach see it.
      const JointVector q = sim.settle(command, velocity, Vector6::Zero(), 0.0, t);
      sim.addRow(t, command, q, Vector6::Zero(), 0.0);
      t += move_time + s.settle_s;
    }
  }
  sim.campaign().metadata["swept_joint"] = robot.joints[s.joint].name;
}

void simulateRandom(Simulator& sim, const CampaignSimulationSpec& spec,
                    const std::function<void(const std::string&)>& progress) {
  const Robot& robot = sim.robot();
  const RandomPosesSpec& r = spec.random;
  if (r.count < 1 || r.count > kMaxRandomPoses) {
    throw InvalidArgument("random poses: count is " + std::to_string(r.count) + ", must be from 1 to " +
                          std::to_string(kMaxRandomPoses));
  }
  if (!(r.row_period_s > 0.0)) throw InvalidArgument("random poses: row_period_s must be positive");
  tell(progress, "measuring " + std::to_string(r.count) + " random poses");
  RobotWorkspace commanded(robot);
  Jacobian jacobian(6, robot.dof());
  const JointVector rest = JointVector::Zero(robot.dof());
  double t = 0.0;
  int accepted = 0;
  JointVector previous;
  for (long attempt = 0; accepted < r.count; ++attempt) {
    if (attempt > 1000L * r.count) {
      throw SolverError("random poses: found only " + std::to_string(accepted) +
                        " poses meeting the height and conditioning limits");
    }
    const JointVector q_pose = randomPose(robot, sim.random(), r.limit_margin_rad);
    forwardKinematics(robot, commanded, q_pose);
    const Eigen::Vector3d target = commanded.tool_pose * spec.target_in_flange;
    if (target.z() < r.min_target_height_m) continue;
    pointJacobian(robot, commanded, target, jacobian);
    if (conditioning(jacobian) < r.min_conditioning) continue;
    ++accepted;
    // The robot arrives from the previous pose: its velocity (the mean of the move) gives each joint's
    // direction of approach, which direction-dependent effects (backlash) need; the first pose: at rest.
    const JointVector velocity =
        previous.size() == q_pose.size() ? JointVector((q_pose - previous) / r.row_period_s) : rest;
    sim.addRow(t, q_pose, sim.settle(q_pose, velocity, Vector6::Zero(), 0.0, t), Vector6::Zero(), 0.0);
    previous = q_pose;
    t += r.row_period_s;
  }
}

void simulateSpiral(Simulator& sim, const CampaignSimulationSpec& spec, const JointErrorModel& truth,
                    const std::function<void(const std::string&)>& progress) {
  const Robot& robot = sim.robot();
  const SpiralCampaignSpec& s = spec.spiral;
  if (!(s.sample_period_s > 0.0)) throw InvalidArgument("spiral: sample_period_s must be positive");
  tell(progress, "planning the spiral");
  const JointTrajectory planned = planSpiralTrajectory(robot, s.spiral, s.feed_rate, s.seed_posture);
  const long every = std::max(1L, std::lround(s.sample_period_s / s.feed_rate.controller_period));
  tell(progress, "following the spiral (" + std::to_string(planned.size()) + " controller samples)");
  if (!spec.drives.empty()) {
    sim.setSimulatedRobot("flexible-joint plant");
    FlexibleJointPlant plant(truth, spec.drives, spec.plant);
    plant.reset(planned.q[0], planned.time[0]);
    for (std::size_t k = 0; k < planned.size(); ++k) {
      plant.setReference(planned.q[k], planned.qd[k]);
      if (static_cast<long>(k) % every == 0) {
        sim.addRow(planned.time[k], planned.q[k], plant.linkPositions(), Vector6::Zero(), 0.0);
      }
      if (k + 1 < planned.size()) plant.advance(planned.time[k + 1]);
    }
  } else {
    for (std::size_t k = 0; k < planned.size(); k += static_cast<std::size_t>(every)) {
      sim.addRow(planned.time[k], planned.q[k],
                 sim.settle(planned.q[k], planned.qd[k], Vector6::Zero(), 0.0, planned.time[k]), Vector6::Zero(), 0.0);
    }
  }
}

}  // namespace

double TemperatureProfile::at(double t) const {
  return start_degc + rise_degc * (1.0 - std::exp(-t / time_constant_s));
}

SpiralCampaignSpec::SpiralCampaignSpec() : spiral(SpiralExperimentSpec::defaultSpiral()) {}

CampaignSimulationSpec defaultCampaignSpec(CampaignProtocol protocol) {
  CampaignSimulationSpec spec;
  spec.protocol = protocol;
  if (protocol == CampaignProtocol::BackAndForth) {
    spec.sweep.from_rad = -20.0 * kDegree;
    spec.sweep.to_rad = 20.0 * kDegree;
    spec.sweep.step_rad = 0.5 * kDegree;
    spec.sweep.cycles = 2;
  }
  return spec;
}

CampaignProtocol protocolFromName(const std::string& name) {
  if (name == "stiffness") return CampaignProtocol::Stiffness;
  if (name == "joint-sweep" || name == "joint2-sweep" || name == "sweep") return CampaignProtocol::JointSweep;
  if (name == "spiral") return CampaignProtocol::Spiral;
  if (name == "random") return CampaignProtocol::RandomPoses;
  if (name == "back-and-forth") return CampaignProtocol::BackAndForth;
  throw InvalidArgument("unknown protocol '" + name + "' (stiffness, joint2-sweep, spiral, random, back-and-forth)");
}

std::string protocolName(CampaignProtocol protocol) {
  switch (protocol) {
    case CampaignProtocol::Stiffness: return "stiffness";
    case CampaignProtocol::JointSweep: return "joint-sweep";
    case CampaignProtocol::Spiral: return "spiral";
    case CampaignProtocol::RandomPoses: return "random";
    case CampaignProtocol::BackAndForth: return "back-and-forth";
  }
  return "unknown";
}

JointVector defaultStiffnessPose(const Robot& robot) {
  JointVector pose = JointVector::Zero(robot.dof());
  const double wanted[3][2] = {{1, 40.0}, {2, 50.0}, {4, 50.0}};
  for (const auto& entry : wanted) {
    const int j = static_cast<int>(entry[0]);
    if (j < robot.dof()) pose[j] = entry[1] * kDegree;
  }
  for (int j = 0; j < robot.dof(); ++j) {
    const Joint& joint = robot.joints[j];
    if (pose[j] < joint.lower || pose[j] > joint.upper) {
      pose[j] = std::isfinite(joint.lower) && std::isfinite(joint.upper)
                    ? 0.5 * (joint.lower + joint.upper)
                    : std::clamp(pose[j], joint.lower, joint.upper);
    }
  }
  return pose;
}

MeasurementCampaign simulateCampaign(const JointErrorModel& truth, const CampaignSimulationSpec& spec,
                                     const std::function<void(const std::string&)>& progress) {
  Simulator sim(truth, spec);
  switch (spec.protocol) {
    case CampaignProtocol::Stiffness: simulateStiffness(sim, spec, progress); break;
    case CampaignProtocol::JointSweep: simulateSweep(sim, spec, false, truth, progress); break;
    case CampaignProtocol::BackAndForth: simulateSweep(sim, spec, true, truth, progress); break;
    case CampaignProtocol::RandomPoses: simulateRandom(sim, spec, progress); break;
    case CampaignProtocol::Spiral: simulateSpiral(sim, spec, truth, progress); break;
  }
  return sim.finish();
}

}  // namespace jointcomp
