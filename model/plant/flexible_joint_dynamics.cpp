#include <cmath>

#include "model/plant/flexible_joint_dynamics.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {

namespace {

// transmissionError and, with analytic_slope, the effects' motor slopes at the motor angles of p, in one
// pass (Effect::addJointErrorAndMotorSlope): the same bits as the two. Leaves data.ctx at command p.
void transmissionErrorAndMotorSlopes(const PlantModel& model, PlantData& data, const JointVector& p,
                                     const JointVector& q, JointVector& error, JointVector& motor_slope) {
  data.ctx.q = q;
  data.ctx.command = p;
  updateMotorAngles(model.truth, data.ctx);
  error.setZero(model.n);
  motor_slope.setZero(model.n);
  // Effect by effect in index order, as addSelectedJointErrors and addMotorSlopes sum them: the same bits.
  const Robot& robot = model.truth.robot();
  for (int i = 0; i < model.truth.effectCount(); ++i) {
    if ((model.error_mask >> i & 1) == 0) continue;
    const Effect& effect = model.truth.effect(i);
    if (effect.dependsOnCommand()) {
      effect.addJointErrorAndMotorSlope(robot, data.ctx, error, motor_slope);
    } else {
      effect.addJointError(robot, data.ctx, error);
    }
  }
}

}  // namespace

void plantTransmissionError(const PlantModel& model, PlantData& data, const JointVector& p, const JointVector& q,
                            JointVector& error) {
  data.ctx.q = q;
  data.ctx.command = p;
  updateMotorAngles(model.truth, data.ctx);
  error.setZero(model.n);
  addSelectedJointErrors(model.truth, model.error_mask, data.ctx, error);
}

void plantTransmissionTorques(const PlantModel& model, PlantData& data, const JointVector& p, const JointVector& pd,
                              const JointVector& q, const JointVector& qd, JointVector& link_torque,
                              JointVector& motor_reaction) {
  // The gear output turns by p + e(p): the spring stretches by p + e - q and the damper by its rate
  // (I + E) pd - qd with E = de/dp. The motors feel (I + E)^T times the transmitted torque, which keeps
  // the spring conservative and the damper dissipative. E = diag(de_j/dm_j) G from the effects' own
  // slopes (the error of joint j depends on its motor angle m = G p), or by central differences when an
  // effect does not give its slope.
  JointVector error;
  if (model.error_mask != 0 && model.analytic_slope) {
    // E = diag(s) G applied without forming it (the rhs's path; the same bits as the matrix form below).
    JointVector motor_slope, output_rate;
    transmissionErrorAndMotorSlopes(model, data, p, q, error,
                                    motor_slope);  // leaves data.ctx at command p, its motor angles set
    const JointMatrix& gears = model.truth.gears().motorFromJoint();
    transmissionOutputRate(motor_slope, gears, pd, output_rate);
    link_torque = model.stiffness.cwiseProduct(p + error - q);
    for (int j = 0; j < model.n; ++j)
      link_torque[j] += model.drives[j].transmission_damping_nms_per_rad * (output_rate[j] - qd[j]);
    transmissionReaction(motor_slope, gears, link_torque, motor_reaction);
    return;
  }
  JointMatrix slope = JointMatrix::Zero(model.n, model.n);
  if (model.error_mask != 0) {
    plantTransmissionError(model, data, p, q, error);
    JointVector shifted = p;
    JointVector ahead, behind;
    constexpr double kStep = 1e-6;  // rad of joint-side motor angle
    for (int k = 0; k < model.n; ++k) {
      shifted[k] = p[k] + kStep;
      plantTransmissionError(model, data, shifted, q, ahead);
      shifted[k] = p[k] - kStep;
      plantTransmissionError(model, data, shifted, q, behind);
      shifted[k] = p[k];
      slope.col(k) = (ahead - behind) / (2.0 * kStep);
    }
  } else {
    plantTransmissionError(model, data, p, q, error);
  }
  const JointVector output_rate = pd + slope * pd;
  link_torque = model.stiffness.cwiseProduct(p + error - q);
  for (int j = 0; j < model.n; ++j)
    link_torque[j] += model.drives[j].transmission_damping_nms_per_rad * (output_rate[j] - qd[j]);
  motor_reaction = link_torque + slope.transpose() * link_torque;
}

// Eigen's column-major matrix-vector kernel sums each row over the columns in order, from zero, and adds
// the sum to the vector it is added to.
void transmissionOutputRate(const JointVector& motor_slope, const JointMatrix& gears, const JointVector& pd,
                            JointVector& output_rate) {
  const Eigen::Index n = pd.size();
  output_rate.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    double sum = 0.0;
    for (Eigen::Index k = 0; k < n; ++k) sum += (motor_slope[i] * gears(i, k)) * pd[k];
    output_rate[i] = pd[i] + sum;
  }
}

// Eigen's row-major kernel (E^T of a column-major E) sums each row in two lanes, even and odd columns, from
// zero, adds the lanes, then the last column of an odd count (SSE2's two doubles per packet).
void transmissionReaction(const JointVector& motor_slope, const JointMatrix& gears, const JointVector& torque,
                          JointVector& reaction) {
  const Eigen::Index n = torque.size();
  const Eigen::Index paired = n - n % 2;
  reaction.resize(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    double even = 0.0, odd = 0.0;
    for (Eigen::Index k = 0; k < paired; k += 2) {
      even += (motor_slope[k] * gears(k, j)) * torque[k];
      odd += (motor_slope[k + 1] * gears(k + 1, j)) * torque[k + 1];
    }
    double sum = even + odd;
    if (paired < n) sum += (motor_slope[n - 1] * gears(n - 1, j)) * torque[n - 1];
    reaction[j] = torque[j] + sum;
  }
}

void plantAddMotorSlopes(const PlantModel& model, const PlantData& data, JointVector& slope) {
  for (int i = 0; i < model.truth.effectCount(); ++i) {
    const Effect& effect = model.truth.effect(i);
    if ((model.error_mask >> i & 1) != 0 && effect.dependsOnCommand())
      effect.addMotorSlope(model.truth.robot(), data.ctx, slope);
  }
}

void plantLinkAcceleration(const PlantModel& model, PlantData& data, const JointVector& q, const JointVector& qd,
                           const JointVector& spring_torque, JointVector& qdd) {
  const Robot& robot = model.truth.robot();
  forwardKinematics(robot, data.ws.robot, q);
  data.ctx.q = q;
  data.ctx.load_torque.setZero(model.n);
  addNonGravityLoadsAtCurrentPose(model.truth, model.load_mask, data.ws, data.ctx);
  const JointVector link_torque = spring_torque - data.ctx.load_torque;
  forwardDynamicsAtCurrentPose(robot, data.ws.robot, qd, link_torque, qdd);  // at the pose computed above
}

void plantDerivative(const PlantModel& model, PlantData& data, double t, const double* y, double* ydot) {
  plantEnsureFeedforward(model, data);
  const PlantStateParts parts(y, model.n);
  const JointVector &q = parts.q, &qd = parts.qd, &p = parts.p, &pd = parts.pd, &integral = parts.integral;

  JointVector spring_torque, motor_reaction;
  plantTransmissionTorques(model, data, p, pd, q, qd, spring_torque, motor_reaction);

  JointVector qdd;
  plantLinkAcceleration(model, data, q, qd, spring_torque, qdd);

  // Motor side and controller.
  JointVector motor_torque, clamped_excess;
  plantMotorTorques(model, data, t, p, pd, integral, motor_torque, &clamped_excess);
  for (int j = 0; j < model.n; ++j) {
    const DriveParameters& d = model.drives[j];
    const double friction = d.viscous_friction_nms_per_rad * pd[j] +
                            d.coulomb_friction_nm * std::tanh(pd[j] / d.coulomb_velocity_scale_rad_per_s);
    ydot[j] = qd[j];
    ydot[model.n + j] = qdd[j];
    if (model.options.motors_locked) {
      ydot[2 * model.n + j] = 0.0;
      ydot[3 * model.n + j] = 0.0;
    } else {
      ydot[2 * model.n + j] = pd[j];
      ydot[3 * model.n + j] = (motor_torque[j] - motor_reaction[j] - friction) / d.motor_inertia_kgm2;
    }
    ydot[4 * model.n + j] =
        model.options.control ? plantReferenceAt(data, j, t) - p[j] + model.windup_gain[j] * clamped_excess[j] : 0.0;
  }
}

}  // namespace jointcomp
