// Feed-rate planning: limits checked on finite differences of the samples, the end state, the total
// time against the closed form of a symmetric S-curve, and the 3-D kinematics against differences of
// the sampled positions.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/compensation/feed_rate.hpp"
#include "model/compensation/path.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

Path paperSpiral() {
  SpiralSpec spec;
  spec.centre = Eigen::Vector3d(0.9, 0.0, 0.2);
  return logarithmicSpiral(spec);
}

Path lineOfLength(double length) {
  const Eigen::Vector3d start(0.7, -0.1, 0.4);
  return straightLine(start, start + length * Eigen::Vector3d(0.0, 0.6, 0.8));
}

// Maximum over the samples of |difference quotient| of a field.
template <typename Field>
double maxDifferenceQuotient(const std::vector<FeedRateSample>& samples, Field field) {
  double largest = 0.0;
  for (std::size_t k = 1; k < samples.size(); ++k) {
    const double dt = samples[k].t - samples[k - 1].t;
    largest = std::max(largest, std::abs(field(samples[k]) - field(samples[k - 1])) / dt);
  }
  return largest;
}

// The limits hold on the samples: s_dot, s_ddot directly; speed, acceleration and jerk also as finite
// differences (a difference quotient is a mean of the derivative, so it obeys the same bound).
void expectWithinLimits(const std::vector<FeedRateSample>& samples, const FeedRateSpec& spec) {
  const double slack = 1e-9;
  for (const FeedRateSample& sample : samples) {
    EXPECT_GE(sample.s_dot, 0.0);
    EXPECT_LE(sample.s_dot, spec.speed * (1.0 + slack));
    EXPECT_LE(std::abs(sample.s_ddot), spec.acceleration * (1.0 + slack));
  }
  EXPECT_LE(maxDifferenceQuotient(samples, [](const auto& x) { return x.s; }), spec.speed * (1.0 + slack));
  EXPECT_LE(maxDifferenceQuotient(samples, [](const auto& x) { return x.s_dot; }), spec.acceleration * (1.0 + slack));
  EXPECT_LE(maxDifferenceQuotient(samples, [](const auto& x) { return x.s_ddot; }), spec.jerk * (1.0 + 1e-6));
}

void expectStartsAndEndsAtRest(const Path& path, const std::vector<FeedRateSample>& samples, const FeedRateSpec& spec) {
  ASSERT_GE(samples.size(), 2u);
  const FeedRateSample& first = samples.front();
  const FeedRateSample& last = samples.back();
  EXPECT_EQ(first.t, 0.0);
  EXPECT_EQ(first.s, 0.0);
  EXPECT_EQ(first.s_dot, 0.0);
  EXPECT_EQ(first.s_ddot, 0.0);
  EXPECT_EQ(first.position, path.pointAt(0.0));
  EXPECT_EQ(last.s, path.length());
  EXPECT_EQ(last.s_dot, 0.0);
  EXPECT_EQ(last.s_ddot, 0.0);
  EXPECT_EQ(last.position, path.pointAt(path.length()));
  EXPECT_EQ(last.velocity, Eigen::Vector3d::Zero());
  EXPECT_EQ(last.acceleration, Eigen::Vector3d::Zero());
  for (std::size_t k = 0; k < samples.size(); ++k) {
    EXPECT_NEAR(samples[k].t, static_cast<double>(k) * spec.controller_period, 1e-12);
    if (k > 0) {
      EXPECT_GE(samples[k].s, samples[k - 1].s);  // never backwards
    }
  }
}

TEST(FeedRateSpec, DefaultsAreThePapersAndOurJerk) {
  const FeedRateSpec spec;
  EXPECT_EQ(spec.speed, 0.03);
  EXPECT_EQ(spec.acceleration, 0.1);
  EXPECT_EQ(spec.jerk, 1.0);
  EXPECT_EQ(spec.controller_period, 0.004);
}

TEST(PlanFeedRate, PaperSpiralRespectsLimitsAndEndsAtRestAtTheEnd) {
  const Path path = paperSpiral();
  const FeedRateSpec spec;
  const std::vector<FeedRateSample> samples = planFeedRate(path, spec);
  expectWithinLimits(samples, spec);
  expectStartsAndEndsAtRest(path, samples, spec);
  // Cruise is reached and held at the commanded speed.
  const auto cruising =
      std::count_if(samples.begin(), samples.end(), [&](const auto& x) { return x.s_dot == spec.speed; });
  EXPECT_GT(cruising, static_cast<long>(samples.size() * 9 / 10));
}

TEST(PlanFeedRate, LongPathTakesTheClosedFormTime) {
  // Symmetric S-curve reaching both limits: T = L / v + v / a + a / j.
  const Path path = paperSpiral();
  const FeedRateSpec spec;
  const double expected = path.length() / spec.speed + spec.speed / spec.acceleration + spec.acceleration / spec.jerk;
  const SCurveProfile profile(path.length(), spec);
  EXPECT_NEAR(profile.duration(), expected, 1e-12);
  EXPECT_EQ(profile.peakSpeed(), spec.speed);
  EXPECT_NEAR(profile.peakAcceleration(), spec.acceleration, 1e-15);
  const std::vector<FeedRateSample> samples = planFeedRate(path, spec);
  EXPECT_NEAR(samples.back().t, std::ceil(expected / spec.controller_period) * spec.controller_period, 1e-9);
  // The sample before last is still moving: no padding at rest beyond one period.
  EXPECT_LT(samples[samples.size() - 2].s, path.length());

  // Acceleration limit not reachable (v j < a^2): the ramps take 2 sqrt(v / j), T = L / v + 2 sqrt(v / j).
  FeedRateSpec slow;
  slow.speed = 0.005;
  const SCurveProfile slow_profile(path.length(), slow);
  EXPECT_NEAR(slow_profile.duration(), path.length() / slow.speed + 2.0 * std::sqrt(slow.speed / slow.jerk), 1e-10);
  EXPECT_NEAR(slow_profile.peakAcceleration(), std::sqrt(slow.speed * slow.jerk), 1e-15);
  expectWithinLimits(planFeedRate(path, slow), slow);
}

TEST(PlanFeedRate, ShortPathsLowerThePeakSpeed) {
  const FeedRateSpec spec;
  // 10 mm: too short for 0.03 m/s (needs 12 mm) but long enough to reach 0.1 m/s^2 (needs 2 mm);
  // 1 mm: reaches neither; 0.1 um: a tiny move still works.
  for (const double length : {0.01, 0.001, 1e-7}) {
    SCOPED_TRACE(length);
    const Path path = lineOfLength(length);
    const SCurveProfile profile(length, spec);
    EXPECT_LT(profile.peakSpeed(), spec.speed);
    EXPECT_EQ(profile.cruiseTime(), 0.0);
    // No cruise: half way in time is half way in space, at the peak speed.
    const SCurveProfile::State middle = profile.at(profile.duration() / 2.0);
    EXPECT_NEAR(middle.s, length / 2.0, 1e-12 * length);
    EXPECT_NEAR(middle.s_dot, profile.peakSpeed(), 1e-12);
    const std::vector<FeedRateSample> samples = planFeedRate(path, spec);
    expectWithinLimits(samples, spec);
    expectStartsAndEndsAtRest(path, samples, spec);
  }
  // The lowered peak is as high as the limits allow: 10 mm reaches the acceleration limit
  // (v (a/j + v/a) = L with v = 0.02701562), 1 mm is pure jerk ramps (2 v sqrt(v/j) = L).
  EXPECT_NEAR(SCurveProfile(0.01, spec).peakSpeed(), (-0.1 + std::sqrt(0.41)) / 20.0, 1e-15);
  EXPECT_NEAR(SCurveProfile(0.01, spec).peakAcceleration(), spec.acceleration, 1e-15);
  const double jerk_only_peak = SCurveProfile(0.001, spec).peakSpeed();
  EXPECT_NEAR(2.0 * jerk_only_peak * std::sqrt(jerk_only_peak / spec.jerk), 0.001, 1e-15);
  EXPECT_LT(SCurveProfile(0.001, spec).peakAcceleration(), spec.acceleration);
}

TEST(SCurveProfile, DerivativesAreFiniteDifferencesAndContinuous) {
  const FeedRateSpec spec;
  for (const double length : {0.9, 0.01, 0.001}) {
    SCOPED_TRACE(length);
    const SCurveProfile profile(length, spec);
    const double h = 1e-6;
    const int count = 5000;
    for (int i = 0; i <= count; ++i) {
      const double t = profile.duration() * i / count;
      const SCurveProfile::State state = profile.at(t);
      const SCurveProfile::State before = profile.at(t - h);
      const SCurveProfile::State after = profile.at(t + h);
      EXPECT_NEAR(state.s_dot, (after.s - before.s) / (2.0 * h), 1e-8);
      EXPECT_NEAR(state.s_ddot, (after.s_dot - before.s_dot) / (2.0 * h), 1e-6);
      // Continuity of s, s_dot, s_ddot (the jerk is bounded, so s_ddot moves at most j h).
      EXPECT_LE(std::abs(after.s_ddot - before.s_ddot), 2.0 * h * spec.jerk * (1.0 + 1e-6));
    }
    // Phase boundaries, approached from both sides.
    for (const double boundary : {profile.jerkTime(), profile.accelerationTime() - profile.jerkTime(),
                                  profile.accelerationTime(), profile.accelerationTime() + profile.cruiseTime(),
                                  profile.duration() - profile.accelerationTime() + profile.jerkTime(),
                                  profile.duration() - profile.jerkTime()}) {
      const SCurveProfile::State left = profile.at(boundary - 1e-12);
      const SCurveProfile::State right = profile.at(boundary + 1e-12);
      EXPECT_NEAR(left.s, right.s, 1e-13);
      EXPECT_NEAR(left.s_dot, right.s_dot, 1e-11);
      EXPECT_NEAR(left.s_ddot, right.s_ddot, 1e-10);
    }
    // Total distance as the integral of the speed (Simpson), independent of the position formula.
    const int panels = 200000;  // Simpson errs only at the jerk switches, O(dt^3)
    const double dt = profile.duration() / panels;
    double integral = 0.0;
    for (int i = 0; i <= panels; ++i) {
      const double weight = (i == 0 || i == panels) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
      integral += weight * profile.at(i * dt).s_dot;
    }
    EXPECT_NEAR(integral * dt / 3.0, length, 1e-9 * length);
    EXPECT_EQ(profile.at(profile.duration()).s, length);
    EXPECT_EQ(profile.at(-1.0).s, 0.0);
    EXPECT_EQ(profile.at(profile.duration() + 1.0).s, length);
  }
}

TEST(PlanFeedRate, CartesianVelocityAndAccelerationAreDifferencesOfPositions) {
  const Path path = paperSpiral();
  FeedRateSpec spec;
  spec.controller_period = 1e-3;
  const std::vector<FeedRateSample> samples = planFeedRate(path, spec);
  for (std::size_t k = 1; k + 1 < samples.size(); k += 7) {
    const double dt = samples[k + 1].t - samples[k].t;
    const Eigen::Vector3d velocity = (samples[k + 1].position - samples[k - 1].position) / (2.0 * dt);
    const Eigen::Vector3d acceleration =
        (samples[k + 1].position - 2.0 * samples[k].position + samples[k - 1].position) / (dt * dt);
    EXPECT_LT((samples[k].velocity - velocity).norm(), 1e-6) << "t = " << samples[k].t;
    // A second difference straddling a jerk switch errs by up to dt * jerk / 6.
    EXPECT_LT((samples[k].acceleration - acceleration).norm(), dt * spec.jerk / 2.0) << "t = " << samples[k].t;
    EXPECT_NEAR(samples[k].velocity.norm(), samples[k].s_dot, 1e-15);
    EXPECT_EQ(samples[k].position, path.pointAt(samples[k].s));
  }
  // At cruise the acceleration is centripetal, v^2 times the curvature 1 / (R sqrt(1 + b^2)): about
  // 0.037 m/s^2 on the tight first turn of the paper's spiral.
  const auto inner_turn =
      std::find_if(samples.begin(), samples.end(), [&](const auto& x) { return x.s_ddot == 0.0 && x.s_dot > 0.0; });
  ASSERT_NE(inner_turn, samples.end());
  const double radius = (inner_turn->position - Eigen::Vector3d(0.9, 0.0, 0.2)).norm();
  EXPECT_NEAR(inner_turn->acceleration.norm(), spec.speed * spec.speed / (radius * std::sqrt(1.0 + 0.15 * 0.15)),
              1e-12);
}

TEST(PlanFeedRate, IsDeterministic) {
  const Path path = paperSpiral();
  const std::vector<FeedRateSample> first = planFeedRate(path);
  const std::vector<FeedRateSample> second = planFeedRate(path);
  ASSERT_EQ(first.size(), second.size());
  for (std::size_t k = 0; k < first.size(); ++k) {
    ASSERT_EQ(first[k].s, second[k].s);
    ASSERT_EQ(first[k].acceleration, second[k].acceleration);
  }
}

TEST(PlanFeedRate, RejectsBadSpecNamingTheField) {
  const Path path = lineOfLength(0.1);
  const double nan = std::nan("");
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    double FeedRateSpec::*field;
    double value;
    std::string name;
  };
  const std::vector<Case> cases = {
      {&FeedRateSpec::speed, 0.0, "FeedRateSpec.speed"},
      {&FeedRateSpec::speed, -0.03, "FeedRateSpec.speed"},
      {&FeedRateSpec::speed, inf, "FeedRateSpec.speed"},
      {&FeedRateSpec::acceleration, nan, "FeedRateSpec.acceleration"},
      {&FeedRateSpec::acceleration, -1.0, "FeedRateSpec.acceleration"},
      {&FeedRateSpec::jerk, 0.0, "FeedRateSpec.jerk"},
      {&FeedRateSpec::jerk, inf, "FeedRateSpec.jerk"},
      {&FeedRateSpec::controller_period, 0.0, "FeedRateSpec.controller_period"},
      {&FeedRateSpec::controller_period, nan, "FeedRateSpec.controller_period"},
      {&FeedRateSpec::controller_period, 1e-12, "FeedRateSpec.controller_period"},  // 1e11 samples
  };
  for (const Case& bad : cases) {
    FeedRateSpec spec;
    spec.*bad.field = bad.value;
    SCOPED_TRACE(bad.name + " = " + std::to_string(bad.value));
    try {
      planFeedRate(path, spec);
      ADD_FAILURE() << "no InvalidArgument";
    } catch (const InvalidArgument& error) {
      EXPECT_THAT(error.what(), HasSubstr(bad.name));
    }
  }
  EXPECT_THROW(SCurveProfile(0.0, FeedRateSpec{}), InvalidArgument);
  EXPECT_THROW(SCurveProfile(std::nan(""), FeedRateSpec{}), InvalidArgument);
  EXPECT_THROW(SCurveProfile(1.0, FeedRateSpec{}).at(nan), InvalidArgument);
}

}  // namespace
}  // namespace jointcomp
