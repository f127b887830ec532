// The flexible-joint plant's workspace (Pinocchio's Data beside plant_model.hpp's Model): the controller's
// reference as the last update left it, and the scratch of the right-hand side and its Jacobian, so that
// neither allocates. One per plant; the functions of flexible_joint_dynamics.hpp read the model and write this.
#pragma once

#include <Eigen/Cholesky>

#include "model/plant/plant_model.hpp"

namespace jointcomp {

// The Jacobian's scratch.
struct PlantJacobianScratch {
  JointMatrix inverse_mass, spring_by_motor, reaction_by_motor, reaction_by_motor_rate, link_by_q, link_by_qd,
      torque_by_q, output_by_motor;
  JointVector curvature, ahead, behind, load_rate, shifted_qdd, slope;
  Eigen::LLT<JointMatrix> mass_llt;
};

struct PlantData {
  explicit PlantData(const PlantModel& model);

  // The reference of the last update (position, velocity, the acceleration seen between the last two
  // updates), its time, and the static feed-forward there with its rate.
  JointVector reference, reference_velocity, reference_acceleration, feedforward, feedforward_rate;
  double reference_time = 0.0;
  // The blend from the previous extrapolation (PlantOptions::smooth_reference): its offset from the new one
  // at the update (value, rate, acceleration; feed-forward value and rate) and the blend's duration (0: none).
  JointVector blend_offset, blend_offset_velocity, blend_offset_acceleration, feedforward_offset,
      feedforward_offset_rate;
  double blend_duration = 0.0;
  // The static feed-forward of the last update and its rate are computed when first needed (the right-hand
  // side, the Jacobian, the motor torques, a saved state): with step_past_updates_s most updates are replaced
  // by the next one before CVODE takes a step. The same values as when computed at the update: what they read
  // (the reference and the loads) is set before, and a change of the loads first computes the pending ones.
  bool feedforward_pending = false;
  // The context of the effects: the loads (tool wrench, payload) set by the plant's user, the rest scratch.
  JointContext ctx;
  JointErrorWorkspace ws;
  PlantJacobianScratch jacobian;
};

}  // namespace jointcomp
