// Joint-error prediction, compensation and the paper's spiral experiment.
#include "api_support.hpp"
#include "model/experiment/spiral_experiment.hpp"
#include "spiral_outputs.hpp"

using namespace jointcomp;
using namespace jointcomp::capi;

namespace {

// A joint context carrying the handle's payload and tool wrench.
JointContext contextWithConditions(const jc_robot& handle) {
  JointContext ctx(handle.robot->dof());
  ctx.payload_mass = handle.payload_mass;
  ctx.payload_com = handle.payload_com;
  ctx.tool_wrench = handle.tool_wrench;
  return ctx;
}

// The joint trajectory runSpiralExperiment plans for the default spec.
JointTrajectory planDefaultSpiral(const Robot& robot) {
  const SpiralExperimentSpec spec;
  return planSpiralTrajectory(robot, spec.spiral, spec.feed_rate, spec.seed_posture);
}

// m points of n joints from a flat array of planned_len values.
std::int64_t pointCount(std::int32_t length, int dof, const char* name) {
  if (length <= 0 || length % dof != 0) {
    invalid(std::string(name) + "_len is " + std::to_string(length) + ", must be a positive multiple of " +
            std::to_string(dof) + " (points x the robot's number of joints)");
  }
  return length / dof;
}

std::int32_t sampleCount(std::size_t samples) {
  if (samples > static_cast<std::size_t>(INT32_MAX / 16))
    invalid("the spiral has too many samples for int32_t lengths");
  return static_cast<std::int32_t>(samples);
}

}  // namespace

extern "C" {

jc_status jc_predict_joint_errors(jc_robot* robot, const char* effects, const double* command, int32_t command_len,
                                  const double* velocity, int32_t velocity_len, double* errors, int32_t errors_len) {
  return CAPI_ENTRY({
    jc_robot& handle = robotHandle(robot);
    const int n = handle.robot->dof();
    const EffectMask mask = effectSelection(handle.model, effects);
    const JointVector commanded = jointInput(command, command_len, n, "command");
    const JointVector moving = optionalJointInput(velocity, velocity_len, n, "velocity");
    requireOutput(errors, errors_len, n, "errors", "the robot's number of joints");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    JointContext ctx = contextWithConditions(handle);
    ctx.command = commanded;
    ctx.velocity = moving;
    const FixedPointReport settled = settleStatically(handle.model, mask, handle.workspace, ctx);
    if (!settled.converged) {
      throw SolverError("the links did not settle (residual " + std::to_string(settled.residual) + " rad after " +
                        std::to_string(settled.iterations) + " iterations)");
    }
    copyJoints(ctx.q - ctx.command, errors);
  });
}

jc_status jc_compensate_point(jc_robot* robot, const char* effects, const double* planned, int32_t planned_len,
                              const double* velocity, int32_t velocity_len, double* reference, int32_t reference_len,
                              int32_t* iterations) {
  return CAPI_ENTRY({
    jc_robot& handle = robotHandle(robot);
    const int n = handle.robot->dof();
    const EffectMask mask = effectSelection(handle.model, effects);
    const JointVector target = jointInput(planned, planned_len, n, "planned");
    const JointVector moving = optionalJointInput(velocity, velocity_len, n, "velocity");
    requireOutput(reference, reference_len, n, "reference", "the robot's number of joints");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    Compensator compensator(handle.model, mask);
    JointContext ctx = contextWithConditions(handle);
    ctx.q = target;
    ctx.velocity = moving;
    JointVector result;
    const FixedPointReport report = compensator.compensate(ctx, result);
    if (!report.converged) {
      throw SolverError("compensation did not converge (residual " + std::to_string(report.residual) + " rad after " +
                        std::to_string(report.iterations) + " iterations)");
    }
    copyJoints(result, reference);
    if (iterations) *iterations = report.iterations;
  });
}

jc_status jc_compensate_trajectory(jc_robot* robot, const char* effects, const double* planned, int32_t planned_len,
                                   const double* velocities, int32_t velocities_len, double* references,
                                   int32_t references_len, int32_t* max_iterations, double* max_correction) {
  return CAPI_ENTRY({
    jc_robot& handle = robotHandle(robot);
    const int n = handle.robot->dof();
    const EffectMask mask = effectSelection(handle.model, effects);
    requirePointer(planned, "planned");
    const std::int64_t m = pointCount(planned_len, n, "planned");
    requireFinite(planned, planned_len, "planned");
    if (velocities) {
      requireLength(velocities_len, planned_len, "velocities", "the same as planned_len");
      requireFinite(velocities, velocities_len, "velocities");
    } else {
      requireLength(velocities_len, 0, "velocities", "NULL, so no values");
    }
    requireOutput(references, references_len, planned_len, "references", "the same as planned_len");
    const std::lock_guard<std::mutex> lock(handle.mutex);
    // compensateTrajectory (model/compensation/compensator.cpp) point by point, with the handle's payload
    // and wrench, which compensateTrajectory has no argument for.
    Compensator compensator(handle.model, mask);
    JointContext ctx = contextWithConditions(handle);
    std::vector<JointVector> result(static_cast<std::size_t>(m));
    TrajectoryCompensationReport report;
    for (std::int64_t k = 0; k < m; ++k) {
      ctx.q = Eigen::Map<const Eigen::VectorXd>(planned + k * n, n);
      if (velocities) ctx.velocity = Eigen::Map<const Eigen::VectorXd>(velocities + k * n, n);
      const FixedPointReport point = compensator.compensate(ctx, result[k]);
      if (!point.converged) {
        throw SolverError("compensation did not converge at trajectory point " + std::to_string(k) + " (residual " +
                          std::to_string(point.residual) + " rad after " + std::to_string(point.iterations) +
                          " iterations)");
      }
      const Eigen::Map<const Eigen::VectorXd> target(planned + k * n, n);
      report.max_iterations = std::max(report.max_iterations, point.iterations);
      report.max_correction = std::max(report.max_correction, (target - result[k]).cwiseAbs().maxCoeff());
    }
    for (std::int64_t k = 0; k < m; ++k) copyJoints(result[k], references + k * n);
    if (max_iterations) *max_iterations = report.max_iterations;
    if (max_correction) *max_correction = report.max_correction;
  });
}

jc_status jc_spiral_sample_count(jc_robot* robot, int32_t* count) {
  return CAPI_ENTRY({
    const jc_robot& handle = robotHandle(robot);
    requirePointer(count, "count");
    *count = sampleCount(planDefaultSpiral(*handle.robot).size());
  });
}

jc_status jc_spiral_plan(jc_robot* robot, double* time, int32_t time_len, double* tool_positions,
                         int32_t tool_positions_len, double* q, int32_t q_len, double* qd, int32_t qd_len) {
  return CAPI_ENTRY({
    const jc_robot& handle = robotHandle(robot);
    const int n = handle.robot->dof();
    const JointTrajectory plan = planDefaultSpiral(*handle.robot);
    const std::int64_t m = sampleCount(plan.size());
    const bool want_time = optionalOutput(time, time_len, m, "time", "the spiral's sample count");
    const bool want_positions =
        optionalOutput(tool_positions, tool_positions_len, 3 * m, "tool_positions", "3 x the spiral's sample count");
    const bool want_q = optionalOutput(q, q_len, m * n, "q", "the spiral's sample count x the number of joints");
    const bool want_qd = optionalOutput(qd, qd_len, m * n, "qd", "the spiral's sample count x the number of joints");
    for (std::int64_t k = 0; k < m; ++k) {
      if (want_time) time[k] = plan.time[k];
      if (want_positions) {
        for (int i = 0; i < 3; ++i) tool_positions[3 * k + i] = plan.tool_position[k][i];
      }
      if (want_q) copyJoints(plan.q[k], q + k * n);
      if (want_qd) copyJoints(plan.qd[k], qd + k * n);
    }
  });
}

jc_status jc_spiral_experiment(jc_robot* robot, int32_t use_plant, double* metrics, int32_t metrics_len, double* errors,
                               int32_t errors_len) {
  return CAPI_ENTRY({
    const jc_robot& handle = robotHandle(robot);
    if (use_plant != 0 && use_plant != 1) invalid("use_plant is " + std::to_string(use_plant) + ", must be 0 or 1");
    if (use_plant && handle.drives.empty()) {
      invalid("use_plant is 1 but the parameters have no \"plant\" object (drives and controller gains)");
    }
    requireOutput(metrics, metrics_len, 15, "metrics", "3 runs x Ra, Rz, RMS, max, mean");
    SpiralExperimentSpec spec;
    if (use_plant) spec.drives = handle.drives;
    // The expected size of `errors` is known only once the spiral is planned; it is checked before the
    // (longer) simulation by planning first.
    const std::int64_t m = sampleCount(planDefaultSpiral(*handle.robot).size());
    const bool want_errors = optionalOutput(errors, errors_len, 9 * m, "errors", "3 runs x the spiral's samples x 3");
    const SpiralExperimentResult result = runSpiralExperiment(handle.model, spec);
    if (static_cast<std::int64_t>(result.planned.size()) != m) {
      throw std::logic_error("the experiment planned " + std::to_string(result.planned.size()) +
                             " samples, jc_spiral_plan " + std::to_string(m));
    }
    writeSpiralRuns(result, m, metrics, want_errors ? errors : nullptr);
  });
}

}  // extern "C"
