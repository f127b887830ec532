// The FMU's built-in demo move (reference = demo, or auto with no input set): what a plain run in any
// importer shows. Every joint swings from the middle of its range (zero where the range allows) towards
// the side with more room and back, shaped sin^4(pi t / T), one cycle per kDemoPeriod: smooth (every
// derivative continuous), within the joint limits of any robot, and with gravity loads that change along
// the way, so that the joints' deflection and its compensation show. At t = 0 it starts from rest with its
// velocity, acceleration and jerk all zero, so that it continues the robot at rest before it without a
// jump in any of them (a (1 - cos) shape starts with a jump of its acceleration, issue 39).
#pragma once

#include <algorithm>
#include <cmath>

#include "model/robot/robot.hpp"

namespace jointcomp::fmu {

inline constexpr double kDemoPeriod = 10.0;     // s
inline constexpr double kDemoAmplitude = 0.35;  // rad, at most

// q(t) and q'(t) of the demo move, from the start time.
inline void demoMove(const Robot& robot, double t, JointVector& q, JointVector& qd) {
  const int n = robot.dof();
  q.resize(n);
  qd.resize(n);
  const double pi = 3.14159265358979323846;
  const double omega = 2.0 * pi / kDemoPeriod;
  for (int j = 0; j < n; ++j) {
    const Joint& joint = robot.joints[j];
    double centre = 0.0, amplitude = kDemoAmplitude;
    if (std::isfinite(joint.lower) && std::isfinite(joint.upper)) {
      const double margin = 0.1 * (joint.upper - joint.lower);
      centre = std::clamp(0.0, joint.lower + margin, joint.upper - margin);
      const double room_up = joint.upper - margin - centre, room_down = centre - (joint.lower + margin);
      amplitude = std::min(kDemoAmplitude, std::max(room_up, room_down));
      if (room_down > room_up) amplitude = -amplitude;
    }
    // s = sin^4(x) with x = omega t / 2: s' = 2 omega sin^3(x) cos(x).
    const double sine = std::sin(0.5 * omega * t), cosine = std::cos(0.5 * omega * t);
    const double sine2 = sine * sine;
    q[j] = centre + amplitude * sine2 * sine2;
    qd[j] = amplitude * 2.0 * omega * sine2 * sine * cosine;
  }
}

}  // namespace jointcomp::fmu
