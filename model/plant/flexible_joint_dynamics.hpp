// The flexible-joint plant's equations as free functions of its constant model (plant_model.hpp) and its
// workspace (plant_data.hpp), as Pinocchio writes algorithms: the controller, the transmission, the
// right-hand side and its Jacobian. FlexibleJointPlant (flexible_joint_plant.hpp) integrates them with CVODE
// (plant_integrator.hpp). The state y = [q, qd, p, pd, integral of the position error], 5 n values.
#pragma once

#include "model/plant/plant_data.hpp"
#include "model/plant/plant_model.hpp"

namespace jointcomp {

// The state y in its parts, as the right-hand side and its Jacobian read it.
struct PlantStateParts {
  PlantStateParts(const double* y, int n) {
    const Eigen::Map<const Eigen::VectorXd> state(y, 5 * n);
    q = state.segment(0, n);
    qd = state.segment(n, n);
    p = state.segment(2 * n, n);
    pd = state.segment(3 * n, n);
    integral = state.segment(4 * n, n);
  }
  JointVector q, qd, p, pd, integral;
};

// The controller's reference of `joint` at t: value, rate and acceleration, and its static feed-forward
// torque and that torque's rate (the rates feed the blend of the next update); feedforward_blend is the
// blend's part of the feed-forward.
struct PlantReferencePoint {
  double value, velocity, acceleration, feedforward, feedforward_rate, feedforward_blend;
};
PlantReferencePoint plantReferencePoint(const PlantData& data, int joint, double t);
// Its value alone. Inline: an update's departure check reads it at three times for every joint, and the
// watchdog for every joint, at every update.
inline double plantReferenceAt(const PlantData& data, int joint, double t) {
  const double dt = t - data.reference_time;
  if (data.blend_duration > 0.0 && dt < data.blend_duration) return plantReferencePoint(data, joint, t).value;
  return data.reference[joint] + data.reference_velocity[joint] * dt +
         0.5 * data.reference_acceleration[joint] * dt * dt;
}
// The controller's torques; `clamped_excess` (optional) receives, per joint, the clamped torque minus the
// unclamped one (zero unless the drive saturates), which the anti-windup feeds back.
void plantMotorTorques(const PlantModel& model, const PlantData& data, double t, const JointVector& p,
                       const JointVector& pd, const JointVector& integral, JointVector& torque,
                       JointVector* clamped_excess = nullptr);
// The static load torque at `position` (the loads of data.ctx), the controller's feed-forward.
void plantStaticFeedforward(const PlantModel& model, PlantData& data, const JointVector& position, JointVector& torque);
// The pending feed-forward of the last update and its rate (PlantData::feedforward_pending), if pending.
void plantEnsureFeedforward(const PlantModel& model, PlantData& data);

// The transmission error e(p) of the effects other than the springs, at link positions q.
void plantTransmissionError(const PlantModel& model, PlantData& data, const JointVector& p, const JointVector& q,
                            JointVector& error);
// The torque the transmission carries to the link, tau_s = K (p + e - q) + D ((I + E) pd - qd), and the
// motors' reaction (I + E)^T tau_s, E = de/dp.
void plantTransmissionTorques(const PlantModel& model, PlantData& data, const JointVector& p, const JointVector& pd,
                              const JointVector& q, const JointVector& qd, JointVector& link_torque,
                              JointVector& motor_reaction);
// Sum of the command-dependent effects' motor slopes at the motor angles in data.ctx.
void plantAddMotorSlopes(const PlantModel& model, const PlantData& data, JointVector& slope);
// Link accelerations for the transmitted torque `spring_torque`: loads, then forward dynamics at q.
void plantLinkAcceleration(const PlantModel& model, PlantData& data, const JointVector& q, const JointVector& qd,
                           const JointVector& spring_torque, JointVector& qdd);

// The right-hand side dy/dt at (t, y), both of model.stateSize().
void plantDerivative(const PlantModel& model, PlantData& data, double t, const double* y, double* ydot);
// d(dy/dt)/dy at (t, y), stateSize() x stateSize() column-major. Throws InvalidArgument without
// model.analytic_slope, SolverError for an entry that is not finite.
void plantJacobian(const PlantModel& model, PlantData& data, double t, const double* y, double* jacobian);

// The transmission's rates through E = diag(motor_slope) G (de/dp from the effects' motor slopes and the gear
// matrix) without forming E: output_rate = pd + E pd and reaction = torque + E^T torque, with the arithmetic
// of Eigen's matrix-vector products (the same bits as those matrix expressions, which tests compare).
void transmissionOutputRate(const JointVector& motor_slope, const JointMatrix& gears, const JointVector& pd,
                            JointVector& output_rate);
void transmissionReaction(const JointVector& motor_slope, const JointMatrix& gears, const JointVector& torque,
                          JointVector& reaction);

}  // namespace jointcomp
