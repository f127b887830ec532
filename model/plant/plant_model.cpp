#include "model/plant/plant_model.hpp"

#include <cmath>
#include <cstdio>
#include <string>

#include "model/common/errors.hpp"

namespace jointcomp {

namespace {

// Gains no drive can have would make the integration crawl at micro-second steps (kp 1e12 ran for minutes):
// the position loop's frequency sqrt(kp / J), its damping rate kd / J and the integral's ki / J (a frequency
// cubed) are bounded well above any real servo.
void checkGains(const DriveParameters& d, const std::string& where) {
  const double inertia = d.motor_inertia_kgm2;
  char text[320];
  auto refuse = [&](const char* name, double value, double rate, double limit, const char* unit) {
    std::snprintf(text, sizeof text,
                  "%s = %.6g with motor_inertia_kgm2 = %.6g gives %.3g %s, beyond the %.3g %s of any real drive "
                  "(the plant would need micro-second steps)",
                  name, value, inertia, rate, unit, limit, unit);
    throw InvalidArgument(where + text);
  };
  const double position_loop = std::sqrt(d.kp_nm_per_rad / inertia);
  if (position_loop > kMaxLoopFrequency)
    refuse("kp_nm_per_rad", d.kp_nm_per_rad, position_loop, kMaxLoopFrequency, "rad/s");
  if (d.kd_nms_per_rad / inertia > kMaxLoopFrequency)
    refuse("kd_nms_per_rad", d.kd_nms_per_rad, d.kd_nms_per_rad / inertia, kMaxLoopFrequency, "1/s");
  const double integral_limit = kMaxLoopFrequency * kMaxLoopFrequency * kMaxLoopFrequency;
  if (d.ki_nm_per_rad_s / inertia > integral_limit)
    refuse("ki_nm_per_rad_s", d.ki_nm_per_rad_s, d.ki_nm_per_rad_s / inertia, integral_limit, "rad/s^3");
}

void checkDrive(const DriveParameters& d, const std::string& joint) {
  const std::string where = "plant: drive of " + joint + ": ";
  const double values[] = {d.motor_inertia_kgm2,
                           d.viscous_friction_nms_per_rad,
                           d.coulomb_friction_nm,
                           d.coulomb_velocity_scale_rad_per_s,
                           d.transmission_damping_nms_per_rad,
                           d.kp_nm_per_rad,
                           d.ki_nm_per_rad_s,
                           d.kd_nms_per_rad};
  for (double v : values) {
    if (!std::isfinite(v) || v < 0.0) throw InvalidArgument(where + "every value must be finite and non-negative");
  }
  if (!(d.motor_inertia_kgm2 > 0.0)) throw InvalidArgument(where + "motor_inertia_kgm2 must be positive");
  if (!(d.coulomb_velocity_scale_rad_per_s > 0.0)) {
    throw InvalidArgument(where + "coulomb_velocity_scale_rad_per_s must be positive");
  }
  checkGains(d, where);
}

// A value of the integrator's options within [low, high] (a name and its unit for the message).
template <typename T>
void checkRange(T value, T low, T high, const char* what) {
  if (!(value >= low && value <= high)) {
    throw InvalidArgument(std::string("plant: ") + what + ", not " + std::to_string(value));
  }
}

void checkOptions(const PlantOptions& o) {
  if (!(o.relative_tolerance > 0.0) || !(o.absolute_tolerance > 0.0) || !(o.velocity_tolerance_factor > 0.0) ||
      o.max_step < 0.0 || o.max_steps_per_advance < 1) {
    throw InvalidArgument("plant: tolerances must be positive, max_step non-negative, max_steps_per_advance >= 1");
  }
  if (o.max_order < 1 || o.max_order > 5) throw InvalidArgument("plant: max_order must be 1 to 5");
  checkRange(o.jacobian_reuse_steps, 1L, 100000L, "jacobian_reuse_steps must be 1 to 100000 steps");
  checkRange(o.newton_setup_steps, 1L, 100000L, "newton_setup_steps must be 1 to 100000 steps");
  if (!(o.newton_setup_gamma_change > 0.0 && o.newton_setup_gamma_change <= 10.0)) {
    throw InvalidArgument("plant: newton_setup_gamma_change must be in (0, 10], not " +
                          std::to_string(o.newton_setup_gamma_change));
  }
  checkRange(o.step_past_tolerance_rad, 0.0, 10.0, "step_past_tolerance_rad must be in [0, 10] rad");
  checkRange(o.step_past_updates_s, 0.0, 1.0, "step_past_updates_s must be in [0, 1] s");
}

// Anti-windup by back-calculation: while a drive's torque is clamped, its integral is pulled back by the
// clamped excess over ki Tt, with the tracking time Tt = sqrt(Ti Td) = sqrt(kd / ki) (Astrom and Hagglund),
// Ti = kp / ki for a drive without kd, and the integral's own time scale cbrt(J / ki) for a pure integral drive.
double windupGain(const DriveParameters& d) {
  double tracking_time = 0.0;
  if (d.ki_nm_per_rad_s > 0.0) {
    if (d.kd_nms_per_rad > 0.0) {
      tracking_time = std::sqrt(d.kd_nms_per_rad / d.ki_nm_per_rad_s);
    } else if (d.kp_nm_per_rad > 0.0) {
      tracking_time = d.kp_nm_per_rad / d.ki_nm_per_rad_s;
    } else {
      tracking_time = std::cbrt(d.motor_inertia_kgm2 / d.ki_nm_per_rad_s);
    }
  }
  return tracking_time > 0.0 ? 1.0 / (d.ki_nm_per_rad_s * tracking_time) : 0.0;
}

}  // namespace

PlantModel::PlantModel(const JointErrorModel& truth_model, std::vector<DriveParameters> drive_list,
                       PlantOptions plant_options)
    : truth(truth_model), drives(std::move(drive_list)), options(plant_options), n(truth_model.robot().dof()) {
  const Robot& robot = truth.robot();
  if (!robot.hasInertials()) {
    throw InvalidArgument("plant: link '" + robot.link_without_inertial +
                          "' has no inertial; the plant needs every mass");
  }
  if (static_cast<int>(drives.size()) != n) {
    throw InvalidArgument("plant: " + std::to_string(drives.size()) + " drives for " + std::to_string(n) + " joints");
  }
  for (int j = 0; j < n; ++j) checkDrive(drives[j], robot.joints[j].name);
  springs = truth.jointSprings();
  if (springs < 0) throw InvalidArgument("plant: the joint-error model has no compliance effect (the joint springs)");
  stiffness = truth.jointStiffness();
  for (int j = 0; j < n; ++j) {
    if (!std::isfinite(stiffness[j])) {
      throw InvalidArgument("plant: " + robot.joints[j].name +
                            " is rigid in the compliance effect; the plant needs a "
                            "finite joint stiffness for every joint");
    }
  }
  JointContext ctx(n);
  JointVector probe = JointVector::Zero(n);
  for (int i = 0; i < truth.effectCount(); ++i) {
    const Effect& effect = truth.effect(i);
    if (effect.role() == EffectRole::Load) load_mask |= EffectMask(1) << i;
    if (effect.role() == EffectRole::JointError && i != springs) {
      error_mask |= EffectMask(1) << i;
      if (effect.dependsOnCommand() && !effect.addMotorSlope(robot, ctx, probe)) analytic_slope = false;
    }
  }
  loads_read_kinematics = loadsReadKinematics(truth, load_mask);
  checkOptions(options);
  damping.resize(n);
  windup_gain.resize(n);
  for (int j = 0; j < n; ++j) {
    damping[j] = drives[j].transmission_damping_nms_per_rad;
    windup_gain[j] = windupGain(drives[j]);
  }
}

}  // namespace jointcomp
