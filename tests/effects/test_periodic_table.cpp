// The periodic table effect: a uniform periodic cubic B-spline of a gear part's angle. Identities (the
// weights sum to one, the function repeats every revolution and is C2), finite differences of the
// weights' slopes, the spectrum of a table fitted to a known sine, the joint error through the model
// against a re-derivation from the gear ratios, and the JSON round trip and its errors.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "model/common/errors.hpp"
#include "model/effects/periodic_table.hpp"
#include "model/io/parameter_file.hpp"
#include "tests/effects/effects_test_support.hpp"

namespace jointcomp {
namespace {

using namespace effects_test;
constexpr double kTwoPi = 2.0 * 3.14159265358979323846;

double splineAt(const std::vector<double>& c, double angle) {
  const int knots = static_cast<int>(c.size());
  const PeriodicSplineWeights w = periodicSplineWeights(knots, angle);
  double f = 0.0;
  for (int k = 0; k < 4; ++k) f += w.weight[k] * c[static_cast<std::size_t>((w.first + k) % knots)];
  return f;
}

TEST(PeriodicTable, WeightsArePositiveSumToOneAndRepeatEveryRevolution) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> angle(-40.0, 40.0);
  for (const int knots : {4, 12, 24, 97}) {
    for (int trial = 0; trial < 200; ++trial) {
      const double x = angle(rng);
      const PeriodicSplineWeights w = periodicSplineWeights(knots, x);
      double sum = 0.0, slope = 0.0;
      for (int k = 0; k < 4; ++k) {
        EXPECT_GE(w.weight[k], 0.0);
        sum += w.weight[k];
        slope += w.slope[k];
      }
      EXPECT_NEAR(sum, 1.0, 1e-14);
      EXPECT_NEAR(slope, 0.0, 1e-12);  // a constant table has no slope
      const PeriodicSplineWeights turned = periodicSplineWeights(knots, x + 3 * kTwoPi);
      EXPECT_EQ(turned.first, w.first);
      for (int k = 0; k < 4; ++k) EXPECT_NEAR(turned.weight[k], w.weight[k], 1e-12);
      ASSERT_GE(w.first, 0);
      ASSERT_LT(w.first, knots);
    }
  }
}

TEST(PeriodicTable, SlopesMatchFiniteDifferencesAndTheShapeIsC2AtKnots) {
  std::mt19937 rng(6);
  std::normal_distribution<double> value(0.0, 1.0);
  std::vector<double> c(12);
  for (double& v : c) v = value(rng);
  const int knots = 12;
  for (double x = 0.013; x < kTwoPi; x += 0.37) {
    const PeriodicSplineWeights w = periodicSplineWeights(knots, x);
    double slope = 0.0;
    for (int k = 0; k < 4; ++k) slope += w.slope[k] * c[static_cast<std::size_t>((w.first + k) % knots)];
    const double h = 1e-6;
    EXPECT_NEAR(slope, (splineAt(c, x + h) - splineAt(c, x - h)) / (2 * h), 1e-6) << x;
  }
  // Across a knot, value, slope and curvature are continuous (second differences from both sides agree).
  for (int knot = 0; knot < knots; ++knot) {
    const double x = kTwoPi * knot / knots, h = 1e-4;
    const double left = (splineAt(c, x) - 2 * splineAt(c, x - h) + splineAt(c, x - 2 * h)) / (h * h);
    const double right = (splineAt(c, x + 2 * h) - 2 * splineAt(c, x + h) + splineAt(c, x)) / (h * h);
    EXPECT_NEAR(left, right, 0.05 * (1.0 + std::abs(left))) << "knot " << knot;
    EXPECT_NEAR(splineAt(c, x - 1e-12), splineAt(c, x + 1e-12), 1e-9);
  }
}

// A table least-squares fitted to a pure order-3 sine holds that order and little else: the spectrum
// names the part's order.
TEST(PeriodicTable, SpectrumOfAFittedSineNamesItsOrder) {
  const int knots = 24, samples = 480;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(samples, knots);
  Eigen::VectorXd b(samples);
  for (int n = 0; n < samples; ++n) {
    const double x = kTwoPi * n / samples;
    const PeriodicSplineWeights w = periodicSplineWeights(knots, x);
    for (int k = 0; k < 4; ++k) a(n, (w.first + k) % knots) += w.weight[k];
    b[n] = 2e-4 * std::sin(3 * x + 0.4);
  }
  const Eigen::VectorXd c = a.colPivHouseholderQr().solve(b);
  const std::vector<double> spectrum = periodicTableSpectrum(std::vector<double>(c.data(), c.data() + knots), 12);
  EXPECT_NEAR(spectrum[2], 2e-4, 2e-6);
  for (int order = 1; order <= 12; ++order) {
    if (order != 3) {
      EXPECT_LT(spectrum[static_cast<std::size_t>(order - 1)], 2e-6) << order;
    }
  }
}

// Through the model: the joint error of a table of joint 3's motor equals the spline at the motor angle
// re-derived from the gear train's motor angles.
TEST(PeriodicTable, JointErrorIsTheSplineOfThePartsAngle) {
  JointErrorModel model = rx170Model();
  std::vector<double> c(16);
  for (int k = 0; k < 16; ++k) c[static_cast<std::size_t>(k)] = 1e-4 * std::sin(0.7 * k) + (k % 5 == 0 ? 5e-5 : 0.0);
  PeriodicTable table;
  table.joint = 2;
  table.stage = 1;
  table.coefficients_rad = c;
  PeriodicTableEffect effect(model.robot(), model.gears(), {table});
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const JointVector q = randomConfiguration(model.robot(), rng);
    JointContext ctx(model.robot().dof());
    ctx.command = q;
    ctx.q = q;
    model.gears().motorAngles(q, ctx.motor);
    JointVector dq = JointVector::Zero(6);
    effect.addJointError(model.robot(), ctx, dq);
    EXPECT_NEAR(dq[2], splineAt(c, ctx.motor[2]), 1e-15);
    for (int j : {0, 1, 3, 4, 5}) EXPECT_EQ(dq[j], 0.0);
  }
}

// Through the Effect interface alone (as the plant and the compensator call it): the one-pass value and
// slope are addJointError's and addMotorSlope's bits, added onto values already there, and the joints whose
// error follows the command are the tables' joints, no others.
TEST(PeriodicTable, OnePassValueAndSlopeAreTheTwoCallsAndOnlyItsJointsFollowTheCommand) {
  JointErrorModel model = rx170Model();
  std::vector<PeriodicTable> tables(2);
  for (int t = 0; t < 2; ++t) {
    tables[t].joint = 1 + 2 * t;
    tables[t].stage = 1 + t;
    for (int k = 0; k < 24; ++k) tables[t].coefficients_rad.push_back(1e-4 * std::cos(0.3 * k * (t + 1)));
  }
  const PeriodicTableEffect table(model.robot(), model.gears(), tables);
  const Effect& effect = table;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> start(-1e-3, 1e-3);
  for (int trial = 0; trial < 50; ++trial) {
    JointContext ctx(6);
    ctx.command = randomConfiguration(model.robot(), rng);
    model.gears().motorAngles(ctx.command, ctx.motor);
    JointVector dq(6), slope(6);
    for (int j = 0; j < 6; ++j) {
      dq[j] = start(rng);
      slope[j] = start(rng);
    }
    JointVector direct = dq, direct_slope = slope;
    ASSERT_TRUE(effect.addJointErrorAndMotorSlope(model.robot(), ctx, dq, slope));
    effect.addJointError(model.robot(), ctx, direct);
    ASSERT_TRUE(effect.addMotorSlope(model.robot(), ctx, direct_slope));
    EXPECT_EQ(dq, direct) << "trial " << trial;
    EXPECT_EQ(slope, direct_slope) << "trial " << trial;
  }
  bool joints[kMaxJoints] = {};
  effect.markCommandJoints(6, joints);
  for (int j = 0; j < 6; ++j) EXPECT_EQ(joints[j], j == 1 || j == 3) << "joint " << j;
}

TEST(PeriodicTable, RoundTripsThroughTheParameterFileAndRefusesBadTables) {
  nlohmann::json json = rx170Json();
  std::vector<double> c(12);
  for (int k = 0; k < 12; ++k) c[static_cast<std::size_t>(k)] = 1e-5 * (k * k % 7) - 2e-5;
  json["effects"].push_back(
      {{"type", "periodic_table"}, {"tables", {{{"joint", "joint_2"}, {"of", "output"}, {"coefficients_rad", c}}}}});
  const JointErrorModel model = parseParameters(json.dump(), "with a table", rx170());
  const int index = model.findEffect(PeriodicTableEffect::kType);
  ASSERT_GE(index, 0);
  const auto& effect = dynamic_cast<const PeriodicTableEffect&>(model.effect(index));
  EXPECT_EQ(effect.tables()[0].coefficients_rad, c);
  EXPECT_EQ(effect.tables()[0].stage, model.gears().stageCount(1) + 1);
  const JointErrorModel again = parseParameters(parametersToJson(model), "again", rx170());
  EXPECT_EQ(parametersToJson(again), parametersToJson(model));

  const auto refused = [&](nlohmann::json table, const std::string& fragment) {
    nlohmann::json broken = rx170Json();
    broken["effects"].push_back({{"type", "periodic_table"}, {"tables", {table}}});
    try {
      parseParameters(broken.dump(), "broken", rx170());
      ADD_FAILURE() << "accepted: " << table.dump();
    } catch (const ParameterError& error) {
      EXPECT_THAT(error.what(), ::testing::HasSubstr(fragment));
    }
  };
  refused({{"joint", "joint_9"}, {"of", "motor"}, {"coefficients_rad", c}}, "no joint named 'joint_9'");
  refused({{"joint", "joint_2"}, {"of", "wheel"}, {"coefficients_rad", c}}, "found \"wheel\"");
  refused({{"joint", "joint_2"}, {"of", "motor"}, {"coefficients_rad", {1e-5, 2e-5}}}, "expected 4 to 720");
  refused({{"joint", "joint_2"}, {"of", "motor"}, {"coefficients_rad", {1e-5, "x", 0, 0}}}, "coefficient 1");
  refused({{"joint", "joint_2"}, {"of", "motor"}, {"coefficients_rad", c}, {"knots", 12}}, "knots");
}

}  // namespace
}  // namespace jointcomp
