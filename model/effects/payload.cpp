#include "model/effects/payload.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {

PayloadEffect::PayloadEffect(const Robot&, double mass_kg, const Eigen::Vector3d& com_m) : mass_(0.0), com_(Eigen::Vector3d::Zero()) {
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

}  // namespace jointcomp
