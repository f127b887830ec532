#include "fmu/robot/held_steps.hpp"

#include <cmath>

namespace jointcomp::fmu {

void holdSteppedJoints(const RobotState& s, double time, const Robot& robot, const double q[], double velocity[],
                       double acceleration[]) {
  // What the FMU extrapolated q_desired to `time` from the samples before it, in Newton's form
  // last + (last - earlier) * line + ((last - earlier) / (t2 - t1) - (earlier - earliest) / (t1 - t0)) * bend,
  // with the time factors worked out once: held after the first step (both 0), a line after the second
  // (bend 0), the parabola after that. A sample time that does not advance falls back to the lower order.
  const double interval = time - s.last_step_time;
  double line = 0.0, bend = 0.0, over_last = 0.0, over_earlier = 0.0;
  if (s.has_earlier_step && s.last_step_time > s.earlier_step_time) {
    over_last = 1.0 / (s.last_step_time - s.earlier_step_time);
    line = interval * over_last;
    if (s.has_earliest_step && s.earlier_step_time > s.earliest_step_time) {
      over_earlier = 1.0 / (s.earlier_step_time - s.earliest_step_time);
      bend = interval * (time - s.earlier_step_time) / (s.last_step_time - s.earliest_step_time);
    }
  }
  const int n = robot.dof();
  const double* __restrict last_q = s.last_q_desired.data();
  const double* __restrict earlier_q = s.earlier_q_desired.data();
  const double* __restrict earliest_q = s.earliest_q_desired.data();
  for (int j = 0; j < n; ++j) {
    const double last = last_q[j], change = last - earlier_q[j], earlier_change = earlier_q[j] - earliest_q[j];
    const double extrapolated = last + change * line + (change * over_last - earlier_change * over_earlier) * bend;
    const bool stepped = std::abs(q[j] - extrapolated) > kHeldStepTolerance + 0.5 * std::abs(q[j] - last);
    const double ahead = q[j] + velocity[j] * interval;
    const Joint& joint = robot.joints[j];
    if (stepped || ahead < joint.lower || ahead > joint.upper) {
      velocity[j] = 0.0;
      acceleration[j] = 0.0;
    }
  }
}

void estimateDesiredMotion(const RobotState& s, double time, const Robot& robot, const double q[],
                           bool with_acceleration, double velocity[], double acceleration[]) {
  // Joint by joint in scalars: the same arithmetic as the vector expressions it replaces, without their
  // temporaries.
  const double last = time - s.last_step_time;
  if (s.has_earlier_step && s.last_step_time > s.earlier_step_time) {
    // The slope now of the parabola through the last three communication points: the extrapolation
    // then misses the next input by the path's third-order term, where the difference quotient (the
    // velocity half a step ago) misses it by its second-order one; at 10 ms steps the plant's CVODE
    // took about 1.5 times fewer steps on the spiral (bench/fmu_bench). Its curvature is the
    // acceleration the dynamic mode needs.
    const double earlier = s.last_step_time - s.earlier_step_time;
    const double both = last + earlier;
    const double now_weight = (2.0 * last + earlier) / (last * both);
    const double last_weight = both / (last * earlier);
    const double earlier_weight = last / (earlier * both);
    const double curvature = 2.0 / both;
    for (int j = 0; j < robot.dof(); ++j) {
      const double now_q = q[j], last_q = s.last_q_desired[j], earlier_q = s.earlier_q_desired[j];
      velocity[j] = now_q * now_weight - last_q * last_weight + earlier_q * earlier_weight;
    }
    if (with_acceleration) {  // compensation = dynamic, the only reader of the acceleration
      for (int j = 0; j < robot.dof(); ++j) {
        const double now_q = q[j], last_q = s.last_q_desired[j], earlier_q = s.earlier_q_desired[j];
        acceleration[j] = ((now_q - last_q) / last - (last_q - earlier_q) / earlier) * curvature;
      }
    }
  } else {
    for (int j = 0; j < robot.dof(); ++j) velocity[j] = (q[j] - s.last_q_desired[j]) / last;
  }
  // A step of the inputs is held over the coming communication step, not extrapolated.
  holdSteppedJoints(s, time, robot, q, velocity, acceleration);
}

}  // namespace jointcomp::fmu
