// Feed-rate planning along a path: a jerk-limited (7-segment S-curve) rest-to-rest motion law s(t),
// sampled at the controller period into tool-point positions, velocities and accelerations.
// Planning allocates; it is not a hot path.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "model/compensation/path.hpp"

namespace jointcomp {

struct FeedRateSpec {
  double speed = 0.03;        // m/s, cruise tool speed (the paper's test)
  double acceleration = 0.1;  // m/s^2, limit on |s_ddot| (the paper's test)
  // m/s^3, limit on |s_dddot|. Our choice, the paper gives none: with 0.1 m/s^2 the acceleration
  // ramps take 0.1 s, short next to the 30 s spiral yet enough to keep joint torques smooth.
  double jerk = 1.0;
  double controller_period = 0.004;  // s, spacing of the samples
};

// The symmetric jerk-limited motion law over a distance, in closed form: jerk +j, 0, -j while
// accelerating, cruise, then the mirror image. When the distance is too short to reach the speed
// limit (or the acceleration limit) the peak speed is lowered so that the profile still fits.
class SCurveProfile {
public:
  struct State {
    double s = 0.0;       // m, distance travelled
    double s_dot = 0.0;   // m/s
    double s_ddot = 0.0;  // m/s^2
  };

  // Throws InvalidArgument naming the field at fault: distance, or FeedRateSpec.speed,
  // .acceleration, .jerk not positive and finite. (controller_period is not used here.)
  SCurveProfile(double distance, const FeedRateSpec& spec);

  double distance() const { return distance_; }
  double duration() const { return 2.0 * accel_time_ + cruise_time_; }  // s
  double peakSpeed() const { return peak_speed_; }                      // m/s, <= spec.speed
  double peakAcceleration() const { return jerk_ * jerk_time_; }        // m/s^2, <= spec.acceleration
  double jerkTime() const { return jerk_time_; }                        // s, length of each constant-jerk phase
  double accelerationTime() const { return accel_time_; }               // s, rest to peak speed
  double cruiseTime() const { return cruise_time_; }                    // s, at peak speed

  // State at time t (s). Before 0 the profile is at rest at 0, after duration() at rest at distance();
  // at t = duration() exactly s == distance(). Throws InvalidArgument for a non-finite t.
  State at(double t) const;

private:
  State accelerating(double t) const;  // 0 <= t <= accel_time_

  double distance_ = 0.0;
  double jerk_ = 0.0;
  double peak_speed_ = 0.0;
  double jerk_time_ = 0.0;
  double accel_time_ = 0.0;
  double cruise_time_ = 0.0;
};

struct FeedRateSample {
  double t = 0.0;                                          // s, a whole number of controller periods
  double s = 0.0;                                          // m, arc length along the path
  double s_dot = 0.0;                                      // m/s
  double s_ddot = 0.0;                                     // m/s^2
  Eigen::Vector3d position = Eigen::Vector3d::Zero();      // m
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();      // m/s, tangent * s_dot
  Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();  // m/s^2, tangent s_ddot + curvature s_dot^2
};

// Plans the S-curve along the whole path and samples it every spec.controller_period, from t = 0 to
// the first period boundary at or after the end of the motion; the last sample is at rest with
// s == path.length() exactly and position == path.pointAt(path.length()). On a polyline the velocity
// direction jumps at the corners (they are not blended). Throws InvalidArgument naming the FeedRateSpec
// field at fault.
std::vector<FeedRateSample> planFeedRate(const Path& path, const FeedRateSpec& spec = {});

}  // namespace jointcomp
