#include "model/compensation/compensator.hpp"

#include <cmath>
#include <cstdio>

#include "model/common/errors.hpp"

namespace jointcomp {

Compensator::Compensator(const JointErrorModel& model, EffectMask mask, FixedPointOptions options)
    : model_(model), mask_(mask), options_(options), iterate_(false), ws_(model.robot()) {
  if (!(options_.tolerance > 0.0) || options_.max_iterations < 1) {
    throw InvalidArgument("compensator: tolerance must be positive and max_iterations at least 1");
  }
  for (int i = 0; i < model.effectCount(); ++i) {
    if (!((mask >> i) & 1U) || model.effect(i).role() != EffectRole::JointError) continue;
    if (!model.effect(i).dependsOnCommand()) {
      fixed_effects_.push_back(i);
      continue;
    }
    iterate_ = true;
    command_effects_.push_back(i);
  }
}

namespace {
// ctx.motor = G * ctx.command, the same sums as GearTrain::motorAngles (column by column) without
// Eigen's general matrix-vector kernel, whose dispatch costs more than the 6 x 6 product.
void motorAnglesOf(const JointMatrix& g, const JointVector& command, JointVector& motor) {
  const Eigen::Index n = g.rows();
  motor.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    double sum = 0.0;  // in a register: no store-to-load chain through motor
    for (Eigen::Index j = 0; j < g.cols(); ++j) sum += g(i, j) * command[j];
    motor[i] = sum;
  }
}
}  // namespace

FixedPointReport Compensator::compensate(JointContext& ctx, JointVector& reference) {
  const Robot& robot = model_.robot();
  const JointMatrix& g = model_.gears().motorFromJoint();
  checkJointVector(robot, ctx.q, "planned q");
  computeLoadTorque(model_, mask_, ws_, ctx);
  const Eigen::Index n = ctx.q.size();
  // Errors that do not read the command (compliance at ctx.q's load) are the same at every iteration.
  // Summed first, in effect order, as addSelectedJointErrors would when they precede the others.
  fixed_dq_.setZero(n);
  dq_.resize(n);
  for (const int i : fixed_effects_) model_.effect(i).addJointError(robot, ctx, fixed_dq_);
  FixedPointReport report;
  ctx.command = ctx.q;
  reference.resize(n);
  for (report.iterations = 1; report.iterations <= options_.max_iterations; ++report.iterations) {
    motorAnglesOf(g, ctx.command, ctx.motor);
    for (Eigen::Index j = 0; j < n; ++j) dq_[j] = fixed_dq_[j];
    for (const int i : command_effects_) model_.effect(i).addJointError(robot, ctx, dq_);
    double residual = 0.0, non_finite = 0.0;
    bool finite = true;
    for (Eigen::Index j = 0; j < n; ++j) {
      const double next = ctx.q[j] - dq_[j];
      const double change = std::abs(next - ctx.command[j]);
      if (finite && !std::isfinite(change)) non_finite = change;
      finite = finite && std::isfinite(change);
      residual = std::max(residual, change);
      reference[j] = next;
      ctx.command[j] = next;  // element-wise, not a vector copy of just-stored scalars (store forwarding)
    }
    report.residual = finite ? residual : non_finite;
    if (!iterate_ || report.residual <= options_.tolerance) {
      report.converged = finite;
      break;
    }
    if (!finite) break;
  }
  report.iterations = std::min(report.iterations, options_.max_iterations);
  motorAnglesOf(g, ctx.command, ctx.motor);
  if (report.converged) requireWithinLimits(robot, reference);
  return report;
}

void requireWithinLimits(const Robot& robot, const JointVector& reference) {
  for (int j = 0; j < reference.size(); ++j) {
    const Joint& joint = robot.joints[static_cast<std::size_t>(j)];
    if (reference[j] >= joint.lower && reference[j] <= joint.upper) continue;
    char text[320];
    std::snprintf(text, sizeof text,
                  "compensation: the reference of %s would be %.6g rad, outside its limits [%.6g, %.6g] rad: the "
                  "planned pose cannot be reached under its loads",
                  joint.name.c_str(), reference[j], joint.lower, joint.upper);
    throw UnreachableError(text);
  }
}

TrajectoryCompensationReport compensateTrajectory(const JointErrorModel& model, EffectMask mask,
                                                  const std::vector<JointVector>& planned,
                                                  const std::vector<JointVector>& velocities,
                                                  std::vector<JointVector>& references,
                                                  const FixedPointOptions& options) {
  if (!velocities.empty() && velocities.size() != planned.size()) {
    throw InvalidArgument("compensateTrajectory: " + std::to_string(planned.size()) + " positions but " +
                          std::to_string(velocities.size()) + " velocities");
  }
  Compensator compensator(model, mask, options);
  JointContext ctx(model.robot().dof());
  references.resize(planned.size());
  TrajectoryCompensationReport report;
  for (std::size_t k = 0; k < planned.size(); ++k) {
    ctx.q = planned[k];
    if (!velocities.empty()) ctx.velocity = velocities[k];
    const FixedPointReport point = compensator.compensate(ctx, references[k]);
    if (!point.converged) {
      throw SolverError("compensation did not converge at trajectory point " + std::to_string(k) + " (residual " +
                        std::to_string(point.residual) + " rad after " + std::to_string(point.iterations) +
                        " iterations)");
    }
    report.max_iterations = std::max(report.max_iterations, point.iterations);
    report.max_residual = std::max(report.max_residual, point.residual);
    report.max_correction = std::max(report.max_correction, (planned[k] - references[k]).cwiseAbs().maxCoeff());
  }
  return report;
}

}  // namespace jointcomp
