// The least-squares periodogram: a known order in a synthetic, irregularly sampled signal is found with
// its amplitude; noise has no order that stands out; only the orders asked for are scanned.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "model/common/periodogram.hpp"
#include "model/common/random.hpp"

namespace jointcomp {
namespace {

TEST(Periodogram, FindsAKnownOrderAndItsAmplitude) {
  DeterministicRandom random(5);
  std::vector<double> angle, residual;
  for (int i = 0; i < 400; ++i) {
    angle.push_back(random.uniform(-2.5, 2.5));
    residual.push_back(3e-5 + 2e-4 * std::cos(7.0 * angle.back() + 0.4) + 1e-5 * random.normal());
  }
  const OrderPeak o = strongestOrder(residual, angle, 1, 24);
  EXPECT_EQ(o.order, 7);
  EXPECT_NEAR(o.amplitude, 2e-4, 1e-5);
  EXPECT_TRUE(o.stands_out);
}

TEST(Periodogram, NoOrderStandsOutOfNoise) {
  DeterministicRandom random(6);
  std::vector<double> angle, residual;
  for (int i = 0; i < 400; ++i) {
    angle.push_back(random.uniform(-2.5, 2.5));
    residual.push_back(1e-5 * random.normal());
  }
  EXPECT_FALSE(strongestOrder(residual, angle, 1, 24).stands_out);
  EXPECT_EQ(strongestOrder(std::vector<double>(5, 1.0), std::vector<double>(5, 0.0), 1, 24).order, 0);  // too few rows
  // Only the orders asked for are scanned: order 7 is not among 8 .. 24.
  std::vector<double> seven;
  for (double x : angle) seven.push_back(2e-4 * std::cos(7.0 * x));
  EXPECT_NE(strongestOrder(seven, angle, 8, 24).order, 7);
}

}  // namespace
}  // namespace jointcomp
