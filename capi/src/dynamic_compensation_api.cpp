// jc_compensate_trajectory_dynamic: the dynamic compensation (model/dynamic_compensation/dynamic_compensation.hpp) of a
// trajectory with time, with the handle's payload and tool wrench.
#include "api_support.hpp"
#include "model/dynamic_compensation/dynamic_compensation.hpp"

using namespace jointcomp;
using namespace jointcomp::capi;

extern "C" {

jc_status jc_compensate_trajectory_dynamic(jc_robot* robot, const double* times, int32_t times_len,
                                           const double* planned, int32_t planned_len, const double* velocities,
                                           int32_t velocities_len, double* references, int32_t references_len,
                                           double* reference_velocities, int32_t reference_velocities_len,
                                           int32_t* runs, double* max_link_error) {
  return CAPI_ENTRY({
    jc_robot& handle = robotHandle(robot);
    const int n = handle.robot->dof();
    if (handle.drives.empty()) {
      invalid(
          "the robot's parameters have no \"plant\" object (drives and controller gains): the dynamic "
          "compensation inverts them");
    }
    requirePointer(times, "times");
    requirePointer(planned, "planned");
    requirePointer(velocities, "velocities");
    if (times_len < 3)
      invalid("times_len is " + std::to_string(times_len) + "; the trajectory needs at least 3 samples");
    const std::int64_t m = times_len;
    requireLength(planned_len, m * n, "planned", "times_len x the robot's joints");
    requireLength(velocities_len, m * n, "velocities", "times_len x the robot's joints");
    requireFinite(times, times_len, "times");
    requireFinite(planned, planned_len, "planned");
    requireFinite(velocities, velocities_len, "velocities");
    requireOutput(references, references_len, m * n, "references", "times_len x the robot's joints");
    const bool want_velocities = optionalOutput(reference_velocities, reference_velocities_len, m * n,
                                                "reference_velocities", "times_len x the robot's joints");
    JointTrajectory trajectory;
    for (std::int64_t k = 0; k < m; ++k) {
      trajectory.time.push_back(times[k]);
      trajectory.q.push_back(Eigen::Map<const Eigen::VectorXd>(planned + k * n, n));
      trajectory.qd.push_back(Eigen::Map<const Eigen::VectorXd>(velocities + k * n, n));
    }
    DynamicCompensationOptions options;
    {
      const std::lock_guard<std::mutex> lock(handle.mutex);  // the conditions only; the model is immutable
      options.payload_mass = handle.payload_mass;
      options.payload_com = handle.payload_com;
      options.tool_wrench = handle.tool_wrench;
    }
    std::vector<JointVector> reference, reference_velocity;
    const DynamicCompensationReport report =
        compensateDynamically(handle.model, handle.drives, trajectory, reference, reference_velocity, options);
    for (std::int64_t k = 0; k < m; ++k) {
      copyJoints(reference[k], references + k * n);
      if (want_velocities) copyJoints(reference_velocity[k], reference_velocities + k * n);
    }
    if (runs) *runs = report.iterations;
    if (max_link_error) *max_link_error = report.max_error_rad;
  });
}

}  // extern "C"
