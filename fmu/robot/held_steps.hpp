// A step of the q_desired inputs is a step (issue 39): with use_velocity_inputs = false the FMU extrapolates
// q_desired between communication points with the slope and curvature of the parabola through the last
// three of them, which follows a smooth path to third order but carried a step onward to about 3.25 times
// its size (a 0.07 rad step tripped the 0.2 rad tracking watchdog; a 1.5 rad step asked for 4.87 rad, beyond
// the joint limit). This decides, joint by joint, where the inputs have stepped, and holds those joints
// over the coming communication step instead.
#pragma once

#include "fmu/robot/robot_state.hpp"
#include "model/robot/robot.hpp"

namespace jointcomp::fmu {

// Departures from the path the earlier samples describe of less than this are never taken for a step
// (20 um at the RX170's reach): a smooth path misses the parabola by its third-order term only.
inline constexpr double kHeldStepTolerance = 1e-5;  // rad

// Zeroes velocity[j] and acceleration[j] (the extrapolation of joint j over the coming communication step)
// for every joint j whose input q[j] at `time`
// - departs from the path through the samples before it (the parabola through the last three communication
//   points, the line through the last two, or the last value: what the FMU extrapolated from them) by more
//   than kHeldStepTolerance plus half its change since the last communication point: a step, and the two
//   communication points after it while the step is among the three samples the parabola goes through;
// - or would leave the joint's limits when extrapolated over a step as long as the last one.
// `s` holds the samples of the communication points before `time` (has_last_step at least).
void holdSteppedJoints(const RobotState& s, double time, const Robot& robot, const double q[], double velocity[],
                       double acceleration[]);

// The velocity and acceleration of q_desired at `time` that the FMU extrapolates with when
// use_velocity_inputs is false (instance.hpp, step 1): the slope (and, with_acceleration, the curvature)
// of the parabola through q at `time` and the last two samples of `s`, the difference quotient after the
// first step, then holdSteppedJoints. `s` has a last step before `time`; velocity and acceleration come in
// zeroed.
void estimateDesiredMotion(const RobotState& s, double time, const Robot& robot, const double q[],
                           bool with_acceleration, double velocity[], double acceleration[]);

}  // namespace jointcomp::fmu
