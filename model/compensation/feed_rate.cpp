#include "model/compensation/feed_rate.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <string>

#include "model/common/errors.hpp"

namespace jointcomp {

namespace {

// A plan longer than this many samples is a unit mistake (e.g. a period in ms), not a real motion.
constexpr double kMaxSamples = 1e8;
// T / period within this of a whole number counts as whole: no extra sample for a rounding error.
constexpr double kPeriodCountTolerance = 1e-9;

// Shortest text that reads back as the same double, independent of the locale.
std::string formatNumber(double value) {
  std::array<char, 32> text{};
  const auto result = std::to_chars(text.data(), text.data() + text.size(), value);
  return std::string(text.data(), result.ptr);
}

void requirePositiveFinite(double value, const char* field) {
  if (!std::isfinite(value) || !(value > 0.0)) {
    throw InvalidArgument(std::string(field) + " must be positive and finite, got " + formatNumber(value));
  }
}

}  // namespace

SCurveProfile::SCurveProfile(double distance, const FeedRateSpec& spec) {
  requirePositiveFinite(distance, "SCurveProfile distance");
  requirePositiveFinite(spec.speed, "FeedRateSpec.speed");
  requirePositiveFinite(spec.acceleration, "FeedRateSpec.acceleration");
  requirePositiveFinite(spec.jerk, "FeedRateSpec.jerk");

  const double speed = spec.speed;
  const double accel = spec.acceleration;
  distance_ = distance;
  jerk_ = spec.jerk;

  // Rest to `speed` with |s_ddot| <= accel and |s_dddot| <= jerk: the acceleration limit is reached
  // only if speed >= accel^2 / jerk; otherwise the acceleration ramps up and straight down.
  if (speed * jerk_ >= accel * accel) {
    jerk_time_ = accel / jerk_;
    accel_time_ = jerk_time_ + speed / accel;
  } else {
    jerk_time_ = std::sqrt(speed / jerk_);
    accel_time_ = 2.0 * jerk_time_;
  }
  // The acceleration phase is point-symmetric about its midpoint, so it covers speed * accel_time / 2;
  // the deceleration phase covers as much again.
  if (speed * accel_time_ <= distance_) {
    peak_speed_ = speed;
    cruise_time_ = (distance_ - speed * accel_time_) / speed;
    return;
  }

  // Too short to cruise: the largest peak speed v with v * accel_time(v) = distance.
  cruise_time_ = 0.0;
  const double ramp_speed = accel * accel / jerk_;  // speed gained over the two jerk ramps alone
  if (distance_ >= 2.0 * accel * ramp_speed / jerk_) {
    // Acceleration limit still reached: v (accel / jerk + v / accel) = distance, a quadratic in v,
    // solved in the form that does not cancel.
    peak_speed_ = 2.0 * accel * distance_ / (ramp_speed + std::sqrt(ramp_speed * ramp_speed + 4.0 * accel * distance_));
    jerk_time_ = accel / jerk_;
    accel_time_ = jerk_time_ + peak_speed_ / accel;
  } else {
    // Pure jerk ramps: 2 v sqrt(v / jerk) = distance.
    peak_speed_ = std::cbrt(distance_ * distance_ * jerk_ / 4.0);
    jerk_time_ = std::sqrt(peak_speed_ / jerk_);
    accel_time_ = 2.0 * jerk_time_;
  }
}

SCurveProfile::State SCurveProfile::accelerating(double t) const {
  const double peak_accel = jerk_ * jerk_time_;
  if (t < jerk_time_) {
    return {jerk_ * t * t * t / 6.0, jerk_ * t * t / 2.0, jerk_ * t};
  }
  if (t < accel_time_ - jerk_time_) {
    return {peak_accel * (t * t / 2.0 - jerk_time_ * t / 2.0 + jerk_time_ * jerk_time_ / 6.0),
            peak_accel * (t - jerk_time_ / 2.0), peak_accel};
  }
  // Last ramp, written from its end (peak speed, zero acceleration) backwards.
  const double to_end = accel_time_ - t;
  return {peak_speed_ * accel_time_ / 2.0 - peak_speed_ * to_end + jerk_ * to_end * to_end * to_end / 6.0,
          peak_speed_ - jerk_ * to_end * to_end / 2.0, jerk_ * to_end};
}

SCurveProfile::State SCurveProfile::at(double t) const {
  if (!std::isfinite(t)) {
    throw InvalidArgument("SCurveProfile::at: time t must be finite, got " + formatNumber(t));
  }
  const double end = duration();
  if (t <= 0.0) return {0.0, 0.0, 0.0};
  if (t >= end) return {distance_, 0.0, 0.0};
  if (t < accel_time_) return accelerating(t);
  if (t <= accel_time_ + cruise_time_) {
    return {peak_speed_ * accel_time_ / 2.0 + peak_speed_ * (t - accel_time_), peak_speed_, 0.0};
  }
  // Deceleration mirrors the acceleration in time, so the end is reached exactly at s = distance.
  const State mirrored = accelerating(end - t);
  return {distance_ - mirrored.s, mirrored.s_dot, -mirrored.s_ddot};
}

std::vector<FeedRateSample> planFeedRate(const Path& path, const FeedRateSpec& spec) {
  requirePositiveFinite(spec.controller_period, "FeedRateSpec.controller_period");
  const SCurveProfile profile(path.length(), spec);

  const double duration = profile.duration();
  const double periods = std::ceil(duration / spec.controller_period - kPeriodCountTolerance);
  if (!(periods < kMaxSamples)) {
    throw InvalidArgument("FeedRateSpec.controller_period = " + formatNumber(spec.controller_period) + " s gives " +
                          formatNumber(periods) + " samples over the " + formatNumber(duration) +
                          " s motion; more than " + formatNumber(kMaxSamples) + " is taken for a unit mistake");
  }
  const auto last = static_cast<long long>(std::max(periods, 1.0));

  std::vector<FeedRateSample> samples;
  samples.reserve(static_cast<std::size_t>(last) + 1);
  for (long long k = 0; k <= last; ++k) {
    FeedRateSample sample;
    sample.t = static_cast<double>(k) * spec.controller_period;
    // The last sample is pinned to the end of the motion, even when rounding put it a hair before.
    const SCurveProfile::State state = profile.at(k == last ? duration : sample.t);
    sample.s = state.s;
    sample.s_dot = state.s_dot;
    sample.s_ddot = state.s_ddot;
    sample.position = path.pointAt(state.s);
    const Eigen::Vector3d tangent = path.tangentAt(state.s);
    sample.velocity = tangent * state.s_dot;
    sample.acceleration = tangent * state.s_ddot + path.curvatureVectorAt(state.s) * (state.s_dot * state.s_dot);
    samples.push_back(sample);
  }
  return samples;
}

}  // namespace jointcomp
