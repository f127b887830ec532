#include <algorithm>
#include <cmath>

#include "model/plant/flexible_joint_dynamics.hpp"
#include "model/robot/dynamics.hpp"

namespace jointcomp {

PlantData::PlantData(const PlantModel& model)
    : reference(JointVector::Zero(model.n)),
      reference_velocity(JointVector::Zero(model.n)),
      reference_acceleration(JointVector::Zero(model.n)),
      feedforward(JointVector::Zero(model.n)),
      feedforward_rate(JointVector::Zero(model.n)),
      blend_offset(JointVector::Zero(model.n)),
      blend_offset_velocity(JointVector::Zero(model.n)),
      blend_offset_acceleration(JointVector::Zero(model.n)),
      feedforward_offset(JointVector::Zero(model.n)),
      feedforward_offset_rate(JointVector::Zero(model.n)),
      ctx(model.n),
      ws(model.truth.robot()) {}

void plantStaticFeedforward(const PlantModel& model, PlantData& data, const JointVector& position,
                            JointVector& torque) {
  data.ctx.q = position;
  if (loadsWithoutKinematics(model.loads_read_kinematics, data.ctx)) {
    double sines[kMaxJoints], cosines[kMaxJoints];
    sinCosBatch(position.data(), model.n, sines, cosines);
    loadTorqueInJointFrames(model.truth, model.load_mask, data.ws, data.ctx, cosines, sines);
  } else {
    computeLoadTorque(model.truth, model.load_mask, data.ws, data.ctx);
  }
  torque = data.ctx.load_torque;
}

// The static-load feed-forward at the last update's reference, and its rate along the update's velocity in
// closed form at the same pose; a difference quotient only when a load effect does not know its rate.
void plantEnsureFeedforward(const PlantModel& model, PlantData& data) {
  if (!data.feedforward_pending) return;
  data.feedforward_pending = false;
  bool rate_known;
  if (loadsWithoutKinematics(model.loads_read_kinematics, data.ctx)) {
    // Gravity and its rate from the sines alone: about 35 % fewer instructions per update than the forward
    // kinematics, the world-frame sum and the chain's rates.
    data.ctx.q = data.reference;
    double sines[kMaxJoints], cosines[kMaxJoints];
    sinCosBatch(data.reference.data(), model.n, sines, cosines);
    rate_known = loadTorqueAndRateInJointFrames(model.truth, model.load_mask, data.ws, data.ctx, cosines, sines,
                                                data.reference_velocity, data.feedforward_rate);
    data.feedforward = data.ctx.load_torque;
  } else {
    plantStaticFeedforward(model, data, data.reference, data.feedforward);
    rate_known = loadTorqueRateAtCurrentPose(model.truth, model.load_mask, data.ws, data.ctx, data.reference_velocity,
                                             data.feedforward_rate);
  }
  if (!rate_known) {
    constexpr double kRateStep = 1e-4;  // s
    JointVector ahead;
    plantStaticFeedforward(model, data, data.reference + data.reference_velocity * kRateStep, ahead);
    data.feedforward_rate = (ahead - data.feedforward) / kRateStep;
  }
}

// The new extrapolation plus (1 - s) times the old one's offset from it, with s = 10 u^3 - 15 u^4 + 6 u^5 of
// u = (t - t_update) / duration: s, s' and s'' vanish at the update (where the offset's Taylor polynomial
// equals the old reference to second order) and s = 1, s' = s'' = 0 from u = 1 on.
PlantReferencePoint plantReferencePoint(const PlantData& data, int j, double t) {
  const double dt = t - data.reference_time;
  PlantReferencePoint point;
  point.value = data.reference[j] + data.reference_velocity[j] * dt + 0.5 * data.reference_acceleration[j] * dt * dt;
  point.velocity = data.reference_velocity[j] + data.reference_acceleration[j] * dt;
  point.acceleration = data.reference_acceleration[j];
  point.feedforward = data.feedforward[j] + data.feedforward_rate[j] * dt;
  point.feedforward_rate = data.feedforward_rate[j];
  point.feedforward_blend = 0.0;
  if (data.blend_duration > 0.0 && dt < data.blend_duration) {
    const double u = std::max(0.0, dt / data.blend_duration);
    const double per_duration = 1.0 / data.blend_duration;
    const double weight = 1.0 - u * u * u * (10.0 + u * (-15.0 + 6.0 * u));
    const double weight_rate = -30.0 * u * u * (1.0 - u) * (1.0 - u) * per_duration;
    const double weight_acceleration = -60.0 * u * (1.0 - u) * (1.0 - 2.0 * u) * per_duration * per_duration;
    const double offset =
        data.blend_offset[j] + data.blend_offset_velocity[j] * dt + 0.5 * data.blend_offset_acceleration[j] * dt * dt;
    const double offset_rate = data.blend_offset_velocity[j] + data.blend_offset_acceleration[j] * dt;
    const double feedforward_offset = data.feedforward_offset[j] + data.feedforward_offset_rate[j] * dt;
    point.value += weight * offset;
    point.velocity += weight_rate * offset + weight * offset_rate;
    point.acceleration +=
        weight_acceleration * offset + 2.0 * weight_rate * offset_rate + weight * data.blend_offset_acceleration[j];
    point.feedforward_blend = weight * feedforward_offset;
    point.feedforward += point.feedforward_blend;
    point.feedforward_rate += weight_rate * feedforward_offset + weight * data.feedforward_offset_rate[j];
  }
  return point;
}

void plantMotorTorques(const PlantModel& model, const PlantData& data, double t, const JointVector& p,
                       const JointVector& pd, const JointVector& integral, JointVector& torque,
                       JointVector* clamped_excess) {
  torque.resize(model.n);
  if (clamped_excess) clamped_excess->setZero(model.n);
  for (int j = 0; j < model.n; ++j) {
    if (!model.options.control) {
      torque[j] = 0.0;
      continue;
    }
    const DriveParameters& d = model.drives[j];
    const double dt = t - data.reference_time;
    // Outside a blend (always without smooth_reference) the extrapolation alone, spelled out: this is
    // every right-hand side's path, and referencePoint() computes much more.
    double wanted, wanted_velocity, feedforward_blend = 0.0;
    if (data.blend_duration > 0.0 && dt < data.blend_duration) {
      const PlantReferencePoint reference = plantReferencePoint(data, j, t);
      wanted = reference.value;
      wanted_velocity = reference.velocity;
      feedforward_blend = reference.feedforward_blend;
    } else {
      wanted = data.reference[j] + data.reference_velocity[j] * dt + 0.5 * data.reference_acceleration[j] * dt * dt;
      wanted_velocity = data.reference_velocity[j] + data.reference_acceleration[j] * dt;
    }
    // Feed-forward of the static load at the reference and of the friction at the reference velocity,
    // as industrial drives do: the feedback then only corrects what the drive does not know.
    const double friction = d.viscous_friction_nms_per_rad * wanted_velocity +
                            d.coulomb_friction_nm * std::tanh(wanted_velocity / d.coulomb_velocity_scale_rad_per_s);
    // The feed-forward as the new extrapolation plus the blend's part (zero without one), in this order so
    // that without smooth_reference the sum is that of the plain extrapolation, bit for bit.
    const double value = d.kp_nm_per_rad * (wanted - p[j]) + d.kd_nms_per_rad * (wanted_velocity - pd[j]) +
                         d.ki_nm_per_rad_s * integral[j] + data.feedforward[j] + data.feedforward_rate[j] * dt +
                         feedforward_blend + friction;
    const double limit = model.truth.robot().joints[j].effort_limit;
    const double clamped = limit > 0.0 ? std::max(-limit, std::min(limit, value)) : value;
    torque[j] = clamped;
    if (clamped_excess) (*clamped_excess)[j] = clamped - value;
  }
}

}  // namespace jointcomp
