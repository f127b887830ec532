// Sine and cosine without libm, a pure function of the angle (no history, the same bits on every call and in
// every order): for the forward kinematics and the transmission error's harmonics, where libm's sincos was
// a tenth of a plant step. One angle (sinCos) or a batch (sinCosBatch, the joints' angles together), written
// so that GCC vectorises the batch with plain SSE2 and gives each element the scalar's bits.
//
// Method: Cody-Waite reduction x = k pi/2 + r with pi/2 split in three parts whose products with k are exact
// (the constants pio2_1, pio2_2, pio2_3 of FDLIBM's e_rem_pio2.c, Sun Microsystems 1993), the rounding error
// of the second subtraction kept (two-sum) as r's low part with the third part and pi/2's tail beyond it; then the
// Taylor series of sin (to r^17) and cos (to r^18) on |r| <= pi/4, whose first omitted terms are below 1e-19; the
// quadrant k mod 4 swaps and negates them through bit masks, without branches. Beyond kSinCosReductionBound, and for
// inf and NaN, libm's.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

namespace jointcomp {

// Up to this |x| the reduction is exact: k <= 2^16, far below the 2^20 up to which k * pio2_1 (33 bits) and
// k * pio2_2 (33 bits) are exact doubles; the neglected tail of pi/2 (8.5e-32) times k stays below 6e-27.
constexpr double kSinCosReductionBound = 1e5;

namespace sin_cos_detail {

constexpr double kTwoOverPi = 0.63661977236758134308;          // 2/pi, rounded
constexpr double kPio2Part1 = 1.57079632673412561417e+00;      // first 33 bits of pi/2 (FDLIBM pio2_1)
constexpr double kPio2Part2 = 6.07710050630396597660e-11;      // next 33 bits (FDLIBM pio2_2)
constexpr double kPio2Part3 = 2.02226624871116645580e-21;      // next 33 bits (FDLIBM pio2_3)
constexpr double kPio2Part3Tail = 8.47842766036889956997e-32;  // pi/2 - the three parts (FDLIBM pio2_3t)
// Adding 1.5 * 2^52 rounds to an integer (round to nearest, |value| < 2^51) and leaves it in the low bits.
constexpr double kRoundToInteger = 6755399441055744.0;

inline std::uint64_t bitsOf(double x) {
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  return bits;
}

inline double fromBits(std::uint64_t bits) {
  double x;
  std::memcpy(&x, &bits, sizeof x);
  return x;
}

// sin and cos of x for |x| <= kSinCosReductionBound; garbage (but no undefined behaviour) beyond. No
// branches: the batch loop vectorises.
inline void sinCosReduced(double x, double& sine, double& cosine) {
  const double shifted = x * kTwoOverPi + kRoundToInteger;
  const double k = shifted - kRoundToInteger;
  const std::uint64_t quadrant = bitsOf(shifted);  // k mod 4 in the low two bits (two's complement for k < 0)
  // x - k pi/2 as hi + lo: the first product and difference are exact, the second difference's rounding
  // error is recovered exactly (Knuth's two-sum), the third part and the rest of pi/2 only matter in lo:
  // next to a multiple of pi/2, where sin or cos is as small as 1e-16 for |x| < 8, they keep it to an ulp.
  const double t = x - k * kPio2Part1;
  const double w = k * kPio2Part2;
  const double hi = t - w;
  const double back = hi - t;
  // Written so that lo is -0 for x = +-0, and sin(+-0) below keeps its sign (x - 0 would be +0).
  const double lo = -(((w + back) - (t - (hi - back))) + (k * kPio2Part3 + k * kPio2Part3Tail));

  const double z = hi * hi;
  // sin(hi + lo) = hi - hi z (1/3! - z/5! + ...) + lo cos hi, cos hi to 1 - z/2 (lo is below 1e-16: the
  // rest is below 1e-34).
  const double minus_sin_tail =
      z * (1.0 / 6.0 +
           z * (-1.0 / 120.0 +
                z * (1.0 / 5040.0 +
                     z * (-1.0 / 362880.0 +
                          z * (1.0 / 39916800.0 + z * (-1.0 / 6227020800.0 + z * (1.0 / 1307674368000.0 +
                                                                                  z * (-1.0 / 355687428096000.0))))))));
  const double sin_r = hi - (hi * minus_sin_tail - lo * (1.0 - 0.5 * z));
  // cos(hi + lo) = cos hi - lo sin hi; 1 - z/2 with its rounding error kept, so that only z's rounding is lost.
  const double cos_tail =
      z * z *
      (1.0 / 24.0 +
       z * (-1.0 / 720.0 +
            z * (1.0 / 40320.0 +
                 z * (-1.0 / 3628800.0 +
                      z * (1.0 / 479001600.0 + z * (-1.0 / 87178291200.0 + z * (1.0 / 20922789888000.0 +
                                                                                z * (-1.0 / 6402373705728000.0))))))));
  const double half_z = 0.5 * z;
  const double one_minus = 1.0 - half_z;
  const double one_minus_error = (1.0 - one_minus) - half_z;
  const double cos_r = one_minus + (cos_tail - (hi * lo - one_minus_error));

  // Quadrant q: sin x = (s, c, -s, -c)[q], cos x = (c, -s, -c, s)[q], by masks.
  const std::uint64_t swap = 0 - (quadrant & 1);
  const std::uint64_t sin_sign = (quadrant & 2) << 62;
  const std::uint64_t cos_sign = ((quadrant + 1) & 2) << 62;
  const std::uint64_t sin_bits = bitsOf(sin_r), cos_bits = bitsOf(cos_r);
  sine = fromBits(((sin_bits & ~swap) | (cos_bits & swap)) ^ sin_sign);
  cosine = fromBits(((cos_bits & ~swap) | (sin_bits & swap)) ^ cos_sign);
}

}  // namespace sin_cos_detail

// sin(x) and cos(x): within about 0.8 ulp of the exact values up to kSinCosReductionBound (tests/common/
// test_sin_cos.cpp measures it), libm's beyond; NaN for inf and NaN. Allocates nothing.
inline void sinCos(double x, double& sine, double& cosine) {
  sin_cos_detail::sinCosReduced(x, sine, cosine);
  if (!(std::abs(x) <= kSinCosReductionBound)) {
    sine = std::sin(x);
    cosine = std::cos(x);
  }
}

namespace sin_cos_detail {
// Bit 63 set where |x| > kSinCosReductionBound or x is inf or NaN (their bits as integers are larger):
// an addition, so that the batch loop ORs it into a vectorised reduction (SSE2 has no 64-bit compare).
constexpr std::uint64_t kMagnitudeBits = ~std::uint64_t{0} >> 1;
constexpr std::uint64_t kReductionBoundBits = 0x40F86A0000000000;  // 1e5's bits (the tests check)
inline std::uint64_t beyondReductionBound(double x) {
  return (bitsOf(x) & kMagnitudeBits) + (kMagnitudeBits - kReductionBoundBits);
}
}  // namespace sin_cos_detail

// sinCos of count angles, element by element the same bits as sinCos (vectorised: no branch per element
// but the rare fall-back to libm). The outputs must not overlap the input.
inline void sinCosBatch(const double* __restrict angles, int count, double* __restrict sines,
                        double* __restrict cosines) {
  std::uint64_t beyond = 0;
  for (int i = 0; i < count; ++i) {
    sin_cos_detail::sinCosReduced(angles[i], sines[i], cosines[i]);
    beyond |= sin_cos_detail::beyondReductionBound(angles[i]);
  }
  if (beyond >> 63) {
    for (int i = 0; i < count; ++i) {
      if (!(std::abs(angles[i]) <= kSinCosReductionBound)) {
        sines[i] = std::sin(angles[i]);
        cosines[i] = std::cos(angles[i]);
      }
    }
  }
}

}  // namespace jointcomp
