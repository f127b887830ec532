// Accuracy metrics on data small enough to score by hand, plus the identities that tie them together.
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "model/common/errors.hpp"
#include "model/compensation/metrics.hpp"

namespace jointcomp {
namespace {

using ::testing::HasSubstr;

TEST(ZDeviation, RaAndRzByHand) {
  // |z| = 1, 2, 3 um: Ra = 2 um; the extremes are +3 and -2 um: Rz = 5 um.
  const std::vector<double> z = {1e-6, -2e-6, 3e-6};
  EXPECT_NEAR(averageAbsoluteDeviation(z), 2e-6, 1e-21);
  EXPECT_NEAR(peakToPeakDeviation(z), 5e-6, 1e-21);
  // A single point has no spread but a deviation.
  EXPECT_EQ(peakToPeakDeviation({-4e-6}), 0.0);
  EXPECT_EQ(averageAbsoluteDeviation({-4e-6}), 4e-6);
}

TEST(ZDeviation, RzIgnoresAnOffsetAndRaDoesNot) {
  const std::vector<double> z = {0.1e-3, -0.05e-3, 0.2e-3, 0.0, -0.08e-3};
  std::vector<double> shifted;
  std::vector<double> mirrored;
  for (const double value : z) {
    shifted.push_back(value + 1e-3);  // all positive now: Ra becomes the mean, 1 mm + 0.034 mm
    mirrored.push_back(-value);
  }
  EXPECT_NEAR(peakToPeakDeviation(shifted), peakToPeakDeviation(z), 1e-15);
  EXPECT_NEAR(peakToPeakDeviation(z), 0.28e-3, 1e-15);
  EXPECT_NEAR(averageAbsoluteDeviation(shifted), 1.034e-3, 1e-15);
  EXPECT_NEAR(averageAbsoluteDeviation(z), 0.086e-3, 1e-15);
  EXPECT_EQ(averageAbsoluteDeviation(mirrored), averageAbsoluteDeviation(z));
  EXPECT_EQ(peakToPeakDeviation(mirrored), peakToPeakDeviation(z));
}

TEST(AccuracyMetrics, ByHand) {
  // Norms 5, 2 and 0 mm (a 3-4-5 triangle, a pure Z error, no error).
  const std::vector<Eigen::Vector3d> errors = {Eigen::Vector3d(3e-3, 4e-3, 0.0), Eigen::Vector3d(0.0, 0.0, -2e-3),
                                               Eigen::Vector3d::Zero()};
  const AccuracyMetrics metrics = accuracyMetrics(errors);
  EXPECT_NEAR(metrics.ra, 2e-3 / 3.0, 1e-18);    // z = 0, -2, 0 mm
  EXPECT_NEAR(metrics.rz, 2e-3, 1e-18);          // 0 - (-2) mm
  EXPECT_NEAR(metrics.mean, 7e-3 / 3.0, 1e-18);  // (5 + 2 + 0) / 3 mm
  EXPECT_NEAR(metrics.max, 5e-3, 1e-18);
  EXPECT_NEAR(metrics.rms, std::sqrt(29.0 / 3.0) * 1e-3, 1e-18);  // sqrt((25 + 4 + 0) / 3) mm
}

TEST(AccuracyMetrics, AgreesWithTheZFunctionsAndTheMeanSquareIdentity) {
  std::vector<Eigen::Vector3d> errors;
  std::vector<double> z;
  for (int k = 0; k < 500; ++k) {
    // A spread of deterministic errors of a tenth of a millimetre.
    const Eigen::Vector3d error =
        1e-4 * Eigen::Vector3d(std::sin(0.3 * k), std::cos(1.7 * k), std::sin(0.11 * k + 0.4) - 0.2);
    errors.push_back(error);
    z.push_back(error.z());
  }
  const AccuracyMetrics metrics = accuracyMetrics(errors);
  EXPECT_NEAR(metrics.ra, averageAbsoluteDeviation(z), 1e-18);
  EXPECT_EQ(metrics.rz, peakToPeakDeviation(z));
  // rms^2 = mean^2 + variance of the norms, so rms >= mean, and max bounds both.
  double variance = 0.0;
  for (const Eigen::Vector3d& error : errors) {
    variance += std::pow(error.norm() - metrics.mean, 2);
  }
  variance /= static_cast<double>(errors.size());
  EXPECT_NEAR(metrics.rms * metrics.rms, metrics.mean * metrics.mean + variance, 1e-20);
  EXPECT_GT(metrics.rms, metrics.mean);
  EXPECT_GE(metrics.max, metrics.rms);
  // Ra never exceeds the mean norm (|z| <= |e|), and Rz never exceeds twice the largest norm.
  EXPECT_LE(metrics.ra, metrics.mean);
  EXPECT_LE(metrics.rz, 2.0 * metrics.max);
}

TEST(AccuracyMetrics, RejectsEmptyAndNonFiniteInputNamingTheIndex) {
  const auto expect_message = [](auto call, const std::string& fragment) {
    try {
      call();
      ADD_FAILURE() << "no InvalidArgument, expected '" << fragment << "'";
    } catch (const InvalidArgument& error) {
      EXPECT_THAT(error.what(), HasSubstr(fragment));
    }
  };
  const double nan = std::nan("");
  const double inf = std::numeric_limits<double>::infinity();
  expect_message([] { accuracyMetrics({}); }, "errors is empty");
  expect_message([] { averageAbsoluteDeviation({}); }, "z_deviations is empty");
  expect_message([] { peakToPeakDeviation({}); }, "z_deviations is empty");
  expect_message(
      [&] {
        accuracyMetrics({Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), Eigen::Vector3d(0, nan, 0)});
      },
      "errors[2]");
  expect_message([&] { accuracyMetrics({Eigen::Vector3d(inf, 0, 0)}); }, "errors[0]");
  expect_message([&] { averageAbsoluteDeviation({0.0, nan}); }, "z_deviations[1]");
  expect_message([&] { peakToPeakDeviation({0.0, 1.0, 2.0, -inf}); }, "z_deviations[3]");
}

}  // namespace
}  // namespace jointcomp
