#include <algorithm>
#include <cmath>
#include <limits>

#include "model/common/errors.hpp"
#include "model/plant/flexible_joint_dynamics.hpp"
#include "model/robot/dynamics.hpp"
#include "model/robot/kinematics.hpp"

namespace jointcomp {

namespace {

// M qdd + c(q, qd) = tau_s - loads(q), c the bias torques without gravity and the loads with it: at fixed
// tau_s, M d qdd = -(d(M qdd + c) + d loads), the first from the tangent passes of inverse dynamics, the second
// from the loads' own rates along each e_j. False (and nothing usable) when a load does not know its rate.
bool analyticLinkDerivatives(const PlantModel& model, PlantData& data, const JointVector& qd, const JointVector& qdd) {
  PlantJacobianScratch& w = data.jacobian;
  const Robot& robot = model.truth.robot();
  w.torque_by_q.resize(model.n, model.n);
  for (int j = 0; j < model.n; ++j) {
    if (!loadTorqueRateAtCurrentPose(model.truth, model.load_mask, data.ws, data.ctx, JointVector::Unit(model.n, j),
                                     w.load_rate))
      return false;
    w.torque_by_q.col(j) = w.load_rate;
  }
  inverseDynamicsDerivativesAtCurrentPose(robot, data.ws.robot, qd, qdd, false, w.link_by_q, w.link_by_qd);
  w.torque_by_q += w.link_by_q;
  w.link_by_q.noalias() = -w.inverse_mass * w.torque_by_q;
  w.torque_by_q.noalias() = -w.inverse_mass * w.link_by_qd;
  w.link_by_qd = w.torque_by_q;
  return true;
}

// The same by forward differences of the link dynamics alone at the fixed transmitted torque (2 n forward
// dynamics); kept to compare against and for loads that do not know their rates.
void linkDerivativesByDifferences(const PlantModel& model, PlantData& data, const JointVector& q, const JointVector& qd,
                                  const JointVector& spring_torque, const JointVector& qdd) {
  PlantJacobianScratch& w = data.jacobian;
  // data.ctx.load_torque holds the loads at q (linkAcceleration's; the loads' rates leave it alone).
  const Robot& robot = model.truth.robot();
  const JointVector link_torque = spring_torque - data.ctx.load_torque;
  const double step = std::sqrt(std::numeric_limits<double>::epsilon());
  JointVector shifted = qd;
  for (int k = 0; k < model.n; ++k) {  // same pose, same loads: only the bias torques change
    const double h = step * std::max(1.0, std::abs(qd[k]));
    shifted[k] = qd[k] + h;
    forwardDynamicsAtCurrentPose(robot, data.ws.robot, shifted, link_torque, w.shifted_qdd);
    shifted[k] = qd[k];
    w.link_by_qd.col(k) = (w.shifted_qdd - qdd) / h;
  }
  shifted = q;
  for (int k = 0; k < model.n; ++k) {
    const double h = step * std::max(1.0, std::abs(q[k]));
    shifted[k] = q[k] + h;
    plantLinkAcceleration(model, data, shifted, qd, spring_torque, w.shifted_qdd);
    shifted[k] = q[k];
    w.link_by_q.col(k) = (w.shifted_qdd - qdd) / h;
  }
}

// Transmission: tau_s = K (p + e(p) - q) + D (S pd - qd), the motors feel S^T tau_s, S = I + diag(s) G with
// s the slopes de_j/dm_j at the motor angles m = G p and s' their curvatures (a central difference of the
// effects' own slopes). Into w.output_by_motor (S), w.spring_by_motor, w.reaction_by_motor(_rate); data.ctx
// left at command p.
void transmissionBlocks(const PlantModel& model, PlantData& data, const PlantStateParts& x,
                        JointVector& spring_torque) {
  const int n = model.n;
  PlantJacobianScratch& w = data.jacobian;
  JointVector motor_reaction;
  plantTransmissionTorques(model, data, x.p, x.pd, x.q, x.qd, spring_torque, motor_reaction);
  const JointMatrix& gears = model.truth.gears().motorFromJoint();
  w.slope.setZero(n);
  w.curvature.setZero(n);
  if (model.error_mask != 0) {
    plantAddMotorSlopes(model, data, w.slope);
    constexpr double kMotorStep = 1e-6;  // rad of motor angle; every motor at once (e_j depends on m_j only)
    const JointVector motor = data.ctx.motor;
    w.ahead.setZero(n);
    w.behind.setZero(n);
    data.ctx.motor.array() += kMotorStep;
    plantAddMotorSlopes(model, data, w.ahead);
    data.ctx.motor.array() = motor.array() - kMotorStep;
    plantAddMotorSlopes(model, data, w.behind);
    data.ctx.motor = motor;
    w.curvature = (w.ahead - w.behind) / (2.0 * kMotorStep);
  }
  const JointVector& damping = model.damping;
  w.output_by_motor = w.slope.asDiagonal() * gears;  // S
  w.output_by_motor.diagonal().array() += 1.0;
  const JointVector motor_rate = gears * x.pd;
  // d tau_s/dp = K S + diag(D s' (G pd)) G, d tau_s/dpd = D S, d tau_s/dq = -K, d tau_s/dqd = -D.
  w.spring_by_motor.noalias() = model.stiffness.asDiagonal() * w.output_by_motor;
  w.spring_by_motor.noalias() += damping.cwiseProduct(w.curvature).cwiseProduct(motor_rate).asDiagonal() * gears;
  // d(S^T tau_s)/dp = S^T d tau_s/dp + G^T diag(s' tau_s) G (S moves with p), and S^T D S for pd.
  w.reaction_by_motor.noalias() = w.output_by_motor.transpose() * w.spring_by_motor;
  w.reaction_by_motor.noalias() += gears.transpose() * (w.curvature.cwiseProduct(spring_torque).asDiagonal() * gears);
  w.reaction_by_motor_rate.noalias() = w.output_by_motor.transpose() * (damping.asDiagonal() * w.output_by_motor);
}

// Link side: qdd = M(q)^-1 (tau_s - loads(q) - bias(q, qd)), its rows of J.
void linkRows(const PlantModel& model, PlantData& data, const PlantStateParts& x, const JointVector& spring_torque,
              Eigen::Map<Eigen::MatrixXd>& J) {
  const int n = model.n;
  PlantJacobianScratch& w = data.jacobian;
  JointVector qdd;
  plantLinkAcceleration(model, data, x.q, x.qd, spring_torque, qdd);
  w.link_by_q.resize(n, n);
  w.link_by_qd.resize(n, n);
  // Eigen's LLT here (a Jacobian is rare): its solve for a matrix groups the sums unlike the vector solves.
  w.mass_llt.compute(data.ws.robot.mass_matrix);
  w.inverse_mass = w.mass_llt.solve(JointMatrix::Identity(n, n));
  if (!model.options.analytic_link_derivatives || !analyticLinkDerivatives(model, data, x.qd, qdd)) {
    linkDerivativesByDifferences(model, data, x.q, x.qd, spring_torque, qdd);
  }
  const JointVector& damping = model.damping;
  for (int j = 0; j < n; ++j) J(j, n + j) = 1.0;
  J.block(n, 0, n, n) = w.link_by_q - w.inverse_mass * model.stiffness.asDiagonal();
  J.block(n, n, n, n) = w.link_by_qd - w.inverse_mass * damping.asDiagonal();
  J.block(n, 2 * n, n, n).noalias() = w.inverse_mass * w.spring_by_motor;
  J.block(n, 3 * n, n, n).noalias() = w.inverse_mass * (damping.asDiagonal() * w.output_by_motor);
}

// Motor side: B pdd = tau_m - S^T tau_s - friction(pd); tau_m = kp (r - p) + kd (rd - pd) + ki z + ..., whose
// slopes vanish while the drive saturates, when the anti-windup takes them over in the integral's rate.
void motorRows(const PlantModel& model, PlantData& data, double t, const PlantStateParts& x,
               Eigen::Map<Eigen::MatrixXd>& J) {
  const int n = model.n;
  const PlantJacobianScratch& w = data.jacobian;
  JointVector motor_torque, clamped_excess;
  plantMotorTorques(model, data, t, x.p, x.pd, x.integral, motor_torque, &clamped_excess);
  for (int j = 0; j < n; ++j) {
    const DriveParameters& d = model.drives[j];
    const bool free = model.options.control && clamped_excess[j] == 0.0;
    const bool saturated = model.options.control && clamped_excess[j] != 0.0;
    if (!model.options.motors_locked) {
      const double per_inertia = 1.0 / d.motor_inertia_kgm2;
      const double scale = d.coulomb_velocity_scale_rad_per_s;
      const double coulomb = std::tanh(x.pd[j] / scale);
      const double friction_slope =
          d.viscous_friction_nms_per_rad + d.coulomb_friction_nm * (1.0 - coulomb * coulomb) / scale;
      J(2 * n + j, 3 * n + j) = 1.0;
      for (int k = 0; k < n; ++k) {
        J(3 * n + j, k) = w.output_by_motor(k, j) * model.stiffness[k] * per_inertia;  // -d(S^T tau_s)/dq
        J(3 * n + j, n + k) = w.output_by_motor(k, j) * model.damping[k] * per_inertia;
        J(3 * n + j, 2 * n + k) = -w.reaction_by_motor(j, k) * per_inertia;
        J(3 * n + j, 3 * n + k) = -w.reaction_by_motor_rate(j, k) * per_inertia;
      }
      J(3 * n + j, 3 * n + j) -= friction_slope * per_inertia;
      if (free) {
        J(3 * n + j, 2 * n + j) -= d.kp_nm_per_rad * per_inertia;
        J(3 * n + j, 3 * n + j) -= d.kd_nms_per_rad * per_inertia;
        J(3 * n + j, 4 * n + j) = d.ki_nm_per_rad_s * per_inertia;
      }
    }
    if (model.options.control) {  // dz/dt = r - p + (clamped - unclamped torque) / (ki Tt)
      J(4 * n + j, 2 * n + j) = -1.0;
      if (saturated) {
        J(4 * n + j, 2 * n + j) += model.windup_gain[j] * d.kp_nm_per_rad;
        J(4 * n + j, 3 * n + j) = model.windup_gain[j] * d.kd_nms_per_rad;
        J(4 * n + j, 4 * n + j) = -model.windup_gain[j] * d.ki_nm_per_rad_s;
      }
    }
  }
}

}  // namespace

// Closed form (the link accelerations' q and qd columns by tangent passes of inverse dynamics) except the
// transmission error's curvature, a central difference of the effects' own slopes.
void plantJacobian(const PlantModel& model, PlantData& data, double t, const double* y, double* jacobian) {
  plantEnsureFeedforward(model, data);
  if (!model.analytic_slope) {
    throw InvalidArgument("plant: no analytic Jacobian: an effect of the transmission error does not give its slope");
  }
  const PlantStateParts x(y, model.n);
  Eigen::Map<Eigen::MatrixXd> J(jacobian, model.stateSize(), model.stateSize());
  J.setZero();
  JointVector spring_torque;
  transmissionBlocks(model, data, x, spring_torque);
  linkRows(model, data, x, spring_torque, J);
  motorRows(model, data, t, x, J);
  if (!J.allFinite()) throw SolverError("plant: the Jacobian has an entry that is not finite");
}

}  // namespace jointcomp
