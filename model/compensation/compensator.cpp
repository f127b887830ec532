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
    if (((mask >> i) & 1U) && model.effect(i).dependsOnCommand()) iterate_ = true;
  }
}

FixedPointReport Compensator::compensate(JointContext& ctx, JointVector& reference) {
  checkJointVector(model_.robot(), ctx.q, "planned q");
  computeLoadTorque(model_, mask_, ws_, ctx);
  JointVector dq;
  FixedPointReport report;
  ctx.command = ctx.q;
  for (report.iterations = 1; report.iterations <= options_.max_iterations; ++report.iterations) {
    updateMotorAngles(model_, ctx);
    dq.setZero(ctx.q.size());
    addSelectedJointErrors(model_, mask_, ctx, dq);
    reference = ctx.q - dq;
    report.residual = (reference - ctx.command).cwiseAbs().maxCoeff();
    ctx.command = reference;
    if (!iterate_ || report.residual <= options_.tolerance) {
      report.converged = std::isfinite(report.residual);
      break;
    }
    if (!std::isfinite(report.residual)) break;
  }
  report.iterations = std::min(report.iterations, options_.max_iterations);
  updateMotorAngles(model_, ctx);
  if (report.converged) requireWithinLimits(model_.robot(), reference);
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
