#include "fmu/held_steps.hpp"

#include <cmath>

namespace jointcomp::fmu {

namespace {

// What the FMU extrapolated q_desired of joint j to `time` from the samples before it (Newton's form).
double extrapolated(const InstanceState& s, int j, double time) {
  const double last = s.last_q_desired[j];
  if (!s.has_earlier_step || !(s.last_step_time > s.earlier_step_time)) return last;  // the first step: held
  const double slope = (last - s.earlier_q_desired[j]) / (s.last_step_time - s.earlier_step_time);
  const double line = last + slope * (time - s.last_step_time);
  if (!s.has_earliest_step || !(s.earlier_step_time > s.earliest_step_time)) return line;
  const double earlier_slope =
      (s.earlier_q_desired[j] - s.earliest_q_desired[j]) / (s.earlier_step_time - s.earliest_step_time);
  const double curvature = (slope - earlier_slope) / (s.last_step_time - s.earliest_step_time);
  return line + curvature * (time - s.last_step_time) * (time - s.earlier_step_time);
}

}  // namespace

void holdSteppedJoints(const InstanceState& s, double time, const Robot& robot, const double q[], double velocity[],
                       double acceleration[]) {
  const double interval = time - s.last_step_time;
  for (int j = 0; j < robot.dof(); ++j) {
    const double departure = std::abs(q[j] - extrapolated(s, j, time));
    const bool stepped = departure > kHeldStepTolerance + 0.5 * std::abs(q[j] - s.last_q_desired[j]);
    const double ahead = q[j] + velocity[j] * interval;
    const Joint& joint = robot.joints[j];
    if (stepped || ahead < joint.lower || ahead > joint.upper) {
      velocity[j] = 0.0;
      acceleration[j] = 0.0;
    }
  }
}

}  // namespace jointcomp::fmu
