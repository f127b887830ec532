#include "model/effects/payload.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"
#include "model/effects/joint_error_model.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {

PayloadEffect::PayloadEffect(const Robot&, double mass_kg, const Eigen::Vector3d& com_m)
    : mass_(0.0), com_(Eigen::Vector3d::Zero()) {
  setParameters({mass_kg, com_m.x(), com_m.y(), com_m.z()});
}

std::unique_ptr<Effect> PayloadEffect::fromJson(const nlohmann::json& json, const Robot& robot, const GearTrain&,
                                                const std::string& path) {
  JsonFields fields(json, path);
  fields.text("type");
  const double mass = fields.number("mass_kg");
  const std::vector<double> com = fields.numbers("com_m", 3);
  const std::string note = fields.textOr("estimate", "");
  fields.rejectUnknownKeys();
  auto effect = std::make_unique<PayloadEffect>(robot, mass, Eigen::Vector3d(com[0], com[1], com[2]));
  effect->estimate_note = note;
  return effect;
}

void PayloadEffect::addTorque(const Robot& robot, const RobotWorkspace& ws, double mass, const Eigen::Vector3d& com,
                              JointVector& torque) {
  Jacobian jacobian(6, robot.dof());
  pointJacobian(robot, ws, ws.tool_pose * com, jacobian);
  torque.noalias() -= jacobian.topRows<3>().transpose() * (mass * robot.gravity);
}

void PayloadEffect::addLoadTorque(const Robot& robot, const RobotWorkspace& ws, JointContext& ctx) const {
  if (mass_ == 0.0) return;
  addTorque(robot, ws, mass_, com_, ctx.load_torque);
}

bool PayloadEffect::addLoadTorqueRate(const Robot& robot, const RobotWorkspace& ws, const JointContext&,
                                      const JointVector& qd, JointVector& rate) const {
  if (mass_ != 0.0) {
    addPointForceTorqueRateAtCurrentPose(robot, ws, ws.tool_pose * com_, -mass_ * robot.gravity, qd, rate);
  }
  return true;
}

std::vector<std::string> PayloadEffect::parameterNames() const {
  return {"payload.mass_kg", "payload.com_x_m", "payload.com_y_m", "payload.com_z_m"};
}

std::vector<double> PayloadEffect::parameters() const { return {mass_, com_.x(), com_.y(), com_.z()}; }

void PayloadEffect::setParameters(const std::vector<double>& values) {
  if (values.size() != 4) {
    throw ParameterError("payload: expected 4 parameters (mass_kg and com_m), found " + std::to_string(values.size()));
  }
  const std::vector<std::string> names = parameterNames();
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) throw ParameterError("payload: " + names[i] + " must be finite");
  }
  mass_ = values[0];
  com_ = Eigen::Vector3d(values[1], values[2], values[3]);
}

nlohmann::json PayloadEffect::toJson() const {
  nlohmann::json json = {{"type", kType}, {"mass_kg", mass_}, {"com_m", {com_.x(), com_.y(), com_.z()}}};
  if (!estimate_note.empty()) json["estimate"] = estimate_note;
  return json;
}

void PayloadDiscovery::offer(const DiscoveryData& data, int joint, std::vector<DiscoveryCandidate>& candidates) const {
  if (joint >= 0 || !data.torque_known) return;
  const Robot& robot = *data.robot;
  const int n = robot.dof();
  const int rows = data.rows();
  DiscoveryCandidate candidate;
  candidate.type = name();
  candidate.detail = " (tool)";
  candidate.through_compliance = true;
  candidate.columns.resize(rows, 4 * n);
  RobotWorkspace ws(robot);
  JointVector at_origin(n), at_unit(n);
  for (int i = 0; i < rows; ++i) {
    forwardKinematics(robot, ws, data.command[i]);
    at_origin.setZero();
    PayloadEffect::addTorque(robot, ws, 1.0, Eigen::Vector3d::Zero(), at_origin);
    for (int j = 0; j < n; ++j) candidate.columns(i, j) = at_origin[j];
    for (int k = 0; k < 3; ++k) {
      at_unit.setZero();
      PayloadEffect::addTorque(robot, ws, 1.0, Eigen::Vector3d::Unit(k), at_unit);
      for (int j = 0; j < n; ++j) candidate.columns(i, (k + 1) * n + j) = at_unit[j] - at_origin[j];
    }
  }
  candidates.push_back(std::move(candidate));
}

std::unique_ptr<Effect> PayloadDiscovery::makeEffect(const DiscoveryData& data,
                                                     const std::vector<FittedCandidate>& accepted) const {
  Eigen::Vector4d payload = Eigen::Vector4d::Zero();  // m, m c
  for (const FittedCandidate& a : accepted) payload += a.theta.head<4>();
  // c = (m c) / m; a mass too small to carry a centre is put at the tool origin.
  const Eigen::Vector3d com =
      std::abs(payload[0]) > 1e-9 ? Eigen::Vector3d(payload.tail<3>() / payload[0]) : Eigen::Vector3d::Zero();
  return std::make_unique<PayloadEffect>(*data.robot, payload[0], com);
}

std::vector<NamedEstimate> PayloadDiscovery::describe(const FittedCandidate& fitted,
                                                      const JointErrorModel& model) const {
  const auto& effect = static_cast<const PayloadEffect&>(model.effect(model.findEffect(PayloadEffect::kType)));
  const double m = effect.mass();
  std::vector<NamedEstimate> estimates{{"payload.mass_kg", m, fitted.sigma[0]}};
  const char* axes[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    const double c = effect.centreOfMass()[k];
    const double sigma = std::abs(m) > 1e-9 ? std::hypot(fitted.sigma[k + 1], c * fitted.sigma[0]) / std::abs(m) : 0.0;
    estimates.push_back({std::string("payload.com_") + axes[k] + "_m", c, sigma});
  }
  return estimates;
}

}  // namespace jointcomp
