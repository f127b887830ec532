// sinCos and sinCosBatch against long-double sinl and cosl (64-bit significands: their own error is below
// 1e-3 ulp of a double) over dense grids, the joint ranges, the angles where the reduction or the quadrant
// changes, tiny angles, signed zeros, the reduction bound and beyond, inf and NaN; the identity
// sin^2 + cos^2 = 1; the batch's bits against the scalar's.
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "model/common/bits.hpp"
#include "model/common/sin_cos.hpp"

namespace jointcomp {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr long double kPiLong = 3.141592653589793238462643383279502884L;
constexpr double kPi = static_cast<double>(kPiLong);

// |got - exact| in units of the last place of the exact value rounded to double (the smallest subnormal's
// unit at zero).
double ulpError(double got, long double exact) {
  const double rounded = static_cast<double>(exact);
  const double magnitude = std::abs(rounded);
  const double ulp = std::nextafter(magnitude, kInf) - magnitude;
  return static_cast<double>(std::abs(static_cast<long double>(got) - exact) / ulp);
}

struct Errors {
  double largest_ulp = 0.0, largest_absolute = 0.0, worst_angle = 0.0;
  void add(double x) {
    double sine, cosine;
    sinCos(x, sine, cosine);
    const long double exact_sin = std::sin(static_cast<long double>(x));
    const long double exact_cos = std::cos(static_cast<long double>(x));
    const double ulp = std::max(ulpError(sine, exact_sin), ulpError(cosine, exact_cos));
    if (ulp > largest_ulp) {
      largest_ulp = ulp;
      worst_angle = x;
    }
    largest_absolute = std::max(
        largest_absolute, static_cast<double>(std::max(std::abs(sine - exact_sin), std::abs(cosine - exact_cos))));
  }
};

// The angles near which a reduction loses the most (multiples of pi/4 and pi/2 up to the bound), each with
// its neighbours a few ulps away.
std::vector<double> nearMultiplesOfQuarterPi(int largest_multiple) {
  std::vector<double> angles;
  for (int m = -largest_multiple; m <= largest_multiple; ++m) {
    const double centre = static_cast<double>(m * kPiLong / 4);
    double below = centre, above = centre;
    for (int step = 0; step < 4; ++step) {
      angles.push_back(below);
      angles.push_back(above);
      below = std::nextafter(below, -kInf);
      above = std::nextafter(above, kInf);
    }
  }
  return angles;
}

TEST(SinCos, WithinAnUlpOverFourTurnsAndTheJointRanges) {
  Errors errors;
  // A dense grid over +-4 pi, the joint ranges' +-2 pi at random, and a grid offset by an irrational step.
  for (int i = 0; i <= 400000; ++i) errors.add(-4.0 * kPi + 8.0 * kPi * i / 400000.0);
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> joint(-2.0 * kPi, 2.0 * kPi);
  for (int i = 0; i < 400000; ++i) errors.add(joint(rng));
  for (double x = -8.0; x <= 8.0; x += 1.0 / 4097.0 * 1.4142135623730951) errors.add(x);
  for (const double x : nearMultiplesOfQuarterPi(10)) errors.add(x);
  // Measured: 0.77 ulp (a correctly rounded sin and cos would give 0.5), 8.5e-17 absolute.
  EXPECT_LE(errors.largest_ulp, 0.8) << "at " << errors.worst_angle;
  EXPECT_LE(errors.largest_absolute, 1e-16);
}

TEST(SinCos, TinyAnglesAndSignedZeros) {
  Errors errors;
  for (double x = 1e-300; x < 1e-2; x *= 1.37) {
    errors.add(x);
    errors.add(-x);
  }
  errors.add(std::numeric_limits<double>::denorm_min());
  EXPECT_LE(errors.largest_ulp, 0.5) << "at " << errors.worst_angle;  // measured 0.4995
  for (const double zero : {0.0, -0.0}) {
    double sine, cosine;
    sinCos(zero, sine, cosine);
    EXPECT_TRUE(sameBits(sine, zero)) << zero;  // sin(-0) = -0, as libm
    EXPECT_EQ(cosine, 1.0);
  }
  // Below 2^-27, sin x rounds to x and cos x to 1.
  for (const double x : {1e-9, -3e-12, 1e-200, -std::numeric_limits<double>::min()}) {
    double sine, cosine;
    sinCos(x, sine, cosine);
    EXPECT_EQ(sine, x);
    EXPECT_EQ(cosine, 1.0);
  }
}

TEST(SinCos, LargeAnglesUpToTheBoundAndLibmBeyond) {
  Errors errors;
  std::mt19937_64 rng(1717);
  std::uniform_real_distribution<double> large(-kSinCosReductionBound, kSinCosReductionBound);
  for (int i = 0; i < 300000; ++i) errors.add(large(rng));
  for (const double x : nearMultiplesOfQuarterPi(127323)) {  // up to 1e5: 4e5 / pi multiples of pi/4
    if (std::abs(x) <= kSinCosReductionBound) errors.add(x);
  }
  for (const double x : {kSinCosReductionBound, -kSinCosReductionBound}) errors.add(x);
  // Measured 0.86 ulp and 9.5e-17 absolute, next to the multiples of pi/2 too (pi/2's tail kept in lo).
  EXPECT_LE(errors.largest_ulp, 0.9) << "at " << errors.worst_angle;
  EXPECT_LE(errors.largest_absolute, 1e-16);
  // The bound's bits are the ones the batch's vectorised test adds to.
  EXPECT_EQ(bitsOf(kSinCosReductionBound), sin_cos_detail::kReductionBoundBits);
  // Beyond the bound, libm's values bit for bit.
  const double just_beyond = std::nextafter(kSinCosReductionBound, kInf);
  for (const double x : {just_beyond, -just_beyond, 1e6, -3.3e7, 1e22, 1e300, -std::numeric_limits<double>::max()}) {
    double sine, cosine;
    sinCos(x, sine, cosine);
    EXPECT_TRUE(sameBits(sine, std::sin(x))) << x;
    EXPECT_TRUE(sameBits(cosine, std::cos(x))) << x;
  }
}

TEST(SinCos, InfAndNanGiveNan) {
  for (const double x : {kInf, -kInf, std::numeric_limits<double>::quiet_NaN()}) {
    double sine = 0.0, cosine = 0.0;
    sinCos(x, sine, cosine);
    EXPECT_TRUE(std::isnan(sine)) << x;
    EXPECT_TRUE(std::isnan(cosine)) << x;
  }
}

TEST(SinCos, SquaresSumToOne) {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> angle(-100.0, 100.0);
  double largest = 0.0;
  for (int i = 0; i < 400000; ++i) {
    double sine, cosine;
    sinCos(angle(rng), sine, cosine);
    const long double sum = static_cast<long double>(sine) * sine + static_cast<long double>(cosine) * cosine;
    largest = std::max(largest, static_cast<double>(std::abs(sum - 1.0L)));
  }
  // Two ulps of 1 (2.2e-16 above it): measured 2.15e-16.
  EXPECT_LE(largest, 2.0 * std::numeric_limits<double>::epsilon());
}

TEST(SinCos, BatchGivesTheScalarsBits) {
  // Every count (the vectorised loop's pairs, its remainder, the alignment), angles of every kind mixed in
  // so that the libm fall-back meets vectorised neighbours.
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> angle(-7.0, 7.0);
  const std::vector<double> special = {0.0,        -0.0,
                                       1e-300,     kSinCosReductionBound,
                                       -1e5 - 1.0, kInf,
                                       -kInf,      2e9,
                                       kPi / 2,    std::numeric_limits<double>::quiet_NaN()};
  for (int count = 0; count <= 13; ++count) {
    for (int offset = 0; offset < 2; ++offset) {
      for (int trial = 0; trial < 50; ++trial) {
        std::vector<double> angles(static_cast<std::size_t>(count + offset));
        for (double& x : angles) x = angle(rng);
        if (count > 0 && trial % 2 == 1) {
          angles[static_cast<std::size_t>(offset) + rng() % static_cast<std::size_t>(count)] =
              special[rng() % special.size()];
        }
        std::vector<double> sines(angles.size(), 9.0), cosines(angles.size(), 9.0);
        sinCosBatch(angles.data() + offset, count, sines.data() + offset, cosines.data() + offset);
        for (int i = offset; i < count + offset; ++i) {
          const std::size_t k = static_cast<std::size_t>(i);
          double sine, cosine;
          sinCos(angles[k], sine, cosine);
          EXPECT_TRUE(sameBits(sines[k], sine)) << angles[k] << " count " << count;
          EXPECT_TRUE(sameBits(cosines[k], cosine)) << angles[k] << " count " << count;
        }
        if (offset == 1) {
          EXPECT_EQ(sines[0], 9.0);  // nothing written outside the batch
        }
      }
    }
  }
}

// The reduction's quadrant: sin and cos of x + k pi/2 are those of x rotated, to the rounding of the
// shifted angle (independent of the Taylor series: checked against the unshifted value).
TEST(SinCos, QuarterTurnsRotateTheValues) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> angle(-0.7, 0.7);
  for (int i = 0; i < 20000; ++i) {
    const double x = angle(rng);
    double sine, cosine;
    sinCos(x, sine, cosine);
    for (int k = -9; k <= 9; ++k) {
      const long double shifted_exact = static_cast<long double>(x) + k * kPiLong / 2;
      const double shifted = static_cast<double>(shifted_exact);
      double s, c;
      sinCos(shifted, s, c);
      // The rounding of the shifted angle moves its values by up to |shifted - shifted_exact|.
      const double moved = static_cast<double>(std::abs(shifted - shifted_exact)) + 2.3e-16;
      const int q = ((k % 4) + 4) % 4;
      const double expected_sin = q == 0 ? sine : q == 1 ? cosine : q == 2 ? -sine : -cosine;
      const double expected_cos = q == 0 ? cosine : q == 1 ? -sine : q == 2 ? -cosine : sine;
      ASSERT_NEAR(s, expected_sin, moved) << x << " + " << k << " pi/2";
      ASSERT_NEAR(c, expected_cos, moved) << x << " + " << k << " pi/2";
    }
  }
}

}  // namespace
}  // namespace jointcomp
