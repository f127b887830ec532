#include "model/effects/spring_balancer.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/common/json_fields.hpp"

namespace jointcomp {

SpringBalancerEffect::SpringBalancerEffect(const Robot& robot, int joint, SpringBalancerGeometry geometry)
    : joint_(joint) {
  if (joint < 0 || joint >= robot.dof()) throw ParameterError("spring_balancer: joint index out of range");
  joint_name_ = robot.joints[joint].name;
  setParameters({geometry.anchor_distance_before_m, geometry.anchor_distance_after_m, geometry.angle_at_zero_rad,
                 geometry.stiffness_n_per_m, geometry.free_length_m, geometry.preload_n});
}

std::unique_ptr<Effect> SpringBalancerEffect::fromJson(const nlohmann::json& json, const Robot& robot,
                                                       const std::string& path) {
  JsonFields fields(json, path);
  fields.text("type");
  const int joint = readJoint(fields, robot);
  SpringBalancerGeometry geometry;
  geometry.anchor_distance_before_m = fields.positiveNumber("anchor_distance_before_m");
  geometry.anchor_distance_after_m = fields.positiveNumber("anchor_distance_after_m");
  geometry.angle_at_zero_rad = fields.number("angle_at_zero_rad");
  geometry.stiffness_n_per_m = fields.nonNegativeNumber("stiffness_n_per_m");
  geometry.free_length_m = fields.nonNegativeNumber("free_length_m");
  geometry.preload_n = fields.number("preload_n");
  const std::string note = fields.textOr("estimate", "");
  fields.rejectUnknownKeys();
  auto effect = std::make_unique<SpringBalancerEffect>(robot, joint, geometry);
  effect->estimate_note = note;
  return effect;
}

double SpringBalancerEffect::springLength(double q) const {
  const double a = geometry_.anchor_distance_before_m;
  const double b = geometry_.anchor_distance_after_m;
  return std::sqrt(a * a + b * b - 2.0 * a * b * std::cos(geometry_.angle_at_zero_rad + q));
}

double SpringBalancerEffect::potentialEnergy(double q) const {
  const double length = springLength(q);
  const double stretch = length - geometry_.free_length_m;
  return geometry_.preload_n * length + 0.5 * geometry_.stiffness_n_per_m * stretch * stretch;
}

double SpringBalancerEffect::torque(double q) const {
  const double a = geometry_.anchor_distance_before_m;
  const double b = geometry_.anchor_distance_after_m;
  const double length = springLength(q);
  if (length < 1e-12) return 0.0;  // anchors coincide: the force has no lever arm
  const double force = geometry_.preload_n + geometry_.stiffness_n_per_m * (length - geometry_.free_length_m);
  const double length_rate = a * b * std::sin(geometry_.angle_at_zero_rad + q) / length;
  return force * length_rate;
}

// torque = F(L) L' with L' = a b sin(theta) / L: its slope is k L'^2 + F L'', L'' = (a b cos(theta) - L'^2) / L.
double SpringBalancerEffect::torqueSlope(double q) const {
  const double a = geometry_.anchor_distance_before_m;
  const double b = geometry_.anchor_distance_after_m;
  const double length = springLength(q);
  if (length < 1e-12) return 0.0;  // as torque(): no lever arm
  const double force = geometry_.preload_n + geometry_.stiffness_n_per_m * (length - geometry_.free_length_m);
  const double angle = geometry_.angle_at_zero_rad + q;
  const double length_rate = a * b * std::sin(angle) / length;
  const double length_curvature = (a * b * std::cos(angle) - length_rate * length_rate) / length;
  return geometry_.stiffness_n_per_m * length_rate * length_rate + force * length_curvature;
}

void SpringBalancerEffect::addLoadTorque(const Robot&, const RobotWorkspace&, JointContext& ctx) const {
  ctx.load_torque[joint_] += torque(ctx.q[joint_]);
}

bool SpringBalancerEffect::addLoadTorqueRate(const Robot&, const RobotWorkspace&, const JointContext& ctx,
                                             const JointVector& qd, JointVector& rate) const {
  rate[joint_] += torqueSlope(ctx.q[joint_]) * qd[joint_];
  return true;
}

std::vector<std::string> SpringBalancerEffect::parameterNames() const {
  const std::string p = joint_name_ + ".spring_balancer.";
  return {p + "anchor_distance_before_m", p + "anchor_distance_after_m", p + "angle_at_zero_rad",
          p + "stiffness_n_per_m",        p + "free_length_m",           p + "preload_n"};
}

std::vector<double> SpringBalancerEffect::parameters() const {
  return {geometry_.anchor_distance_before_m, geometry_.anchor_distance_after_m, geometry_.angle_at_zero_rad,
          geometry_.stiffness_n_per_m,        geometry_.free_length_m,           geometry_.preload_n};
}

void SpringBalancerEffect::setParameters(const std::vector<double>& values) {
  const std::vector<std::string> names = parameterNames();
  if (values.size() != names.size()) throw ParameterError("spring_balancer: wrong number of parameters");
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) throw ParameterError("spring_balancer: " + names[i] + " is not finite");
  }
  if (!(values[0] > 0.0) || !(values[1] > 0.0))
    throw ParameterError("spring_balancer: anchor distances must be positive");
  if (values[3] < 0.0 || values[4] < 0.0) {
    throw ParameterError("spring_balancer: stiffness and free length must not be negative");
  }
  geometry_ = {values[0], values[1], values[2], values[3], values[4], values[5]};
}

nlohmann::json SpringBalancerEffect::toJson() const {
  nlohmann::json json = {{"type", kType},
                         {"joint", joint_name_},
                         {"anchor_distance_before_m", geometry_.anchor_distance_before_m},
                         {"anchor_distance_after_m", geometry_.anchor_distance_after_m},
                         {"angle_at_zero_rad", geometry_.angle_at_zero_rad},
                         {"stiffness_n_per_m", geometry_.stiffness_n_per_m},
                         {"free_length_m", geometry_.free_length_m},
                         {"preload_n", geometry_.preload_n}};
  if (!estimate_note.empty()) json["estimate"] = estimate_note;
  return json;
}

}  // namespace jointcomp
