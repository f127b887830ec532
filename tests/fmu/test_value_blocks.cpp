// The FMU's packed checks and copies of a set's values (fmu/value_blocks.hpp) give what the one-at-a-time
// forms give, for every count up to 9 (pairs and an odd tail), at the edges of each interval, for NaN and
// infinities, and for -0 against 0; and the copy writes exactly the values it is given and nothing beyond.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "fmu/core/value_blocks.hpp"

namespace jointcomp::fmu {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kBig = std::numeric_limits<double>::max();
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// One value drawn from the cases that matter against the interval [lowest, highest].
double drawValue(std::mt19937& random, double lowest, double highest) {
  switch (std::uniform_int_distribution<int>(0, 9)(random)) {
    case 0: return lowest;
    case 1: return highest;
    case 2: return std::nextafter(lowest, -kInf);
    case 3: return std::nextafter(highest, kInf);
    case 4: return kNan;
    case 5: return std::uniform_int_distribution<int>(0, 1)(random) ? kInf : -kInf;
    case 6: return -0.0;
    default: return std::uniform_real_distribution<double>(-4.0, 4.0)(random);
  }
}

TEST(ValueBlocks, AllWithinAgreesWithTheScalarTestForEveryCountAndEdge) {
  std::mt19937 random(20261127);
  int outside = 0, inside = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const std::size_t count = static_cast<std::size_t>(trial % 10);
    std::vector<double> values(count + 1), lowest(count + 1), highest(count + 1);
    for (std::size_t i = 0; i < count; ++i) {
      // Finite bounds, as the FMU keeps them (an unbounded side is the largest double).
      lowest[i] = trial % 3 == 0 ? -kBig : std::uniform_real_distribution<double>(-3.0, 0.0)(random);
      highest[i] = trial % 5 == 0 ? kBig : std::uniform_real_distribution<double>(0.0, 3.0)(random);
      // Mostly values inside, so that a whole list passes often enough to test the pass.
      values[i] = trial % 2 == 0 ? 0.5 * (lowest[i] + highest[i]) : drawValue(random, lowest[i], highest[i]);
      if (trial % 7 == 0 && count > 0 && i == count - 1) values[i] = kNan;  // a NaN in the odd tail or a pair
    }
    values[count] = kNan;  // past the end: must not be read
    const bool scalar = allWithinScalar(values.data(), lowest.data(), highest.data(), count);
    ASSERT_EQ(allWithin(values.data(), lowest.data(), highest.data(), count), scalar) << "trial " << trial;
    (scalar ? inside : outside) += 1;
  }
  EXPECT_GT(inside, 5000);  // both outcomes were exercised
  EXPECT_GT(outside, 5000);
}

TEST(ValueBlocks, AllWithinRefusesEachKindOfBadValueInEveryPlace) {
  for (std::size_t count = 1; count <= 7; ++count) {
    for (std::size_t bad = 0; bad < count; ++bad) {
      for (const double wrong : {kNan, kInf, -kInf, std::nextafter(2.0, kInf), std::nextafter(-1.0, -kInf)}) {
        std::vector<double> values(count, 0.5), lowest(count, -1.0), highest(count, 2.0);
        EXPECT_TRUE(allWithin(values.data(), lowest.data(), highest.data(), count));
        values[bad] = wrong;
        EXPECT_FALSE(allWithin(values.data(), lowest.data(), highest.data(), count))
            << wrong << " at " << bad << " of " << count;
      }
    }
  }
}

std::uint64_t bits(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

TEST(ValueBlocks, CopyChangedCopiesExactlyTheValuesAndSaysWhetherAnyBitsChanged) {
  std::mt19937 random(7);
  for (int trial = 0; trial < 5000; ++trial) {
    const std::size_t count = static_cast<std::size_t>(trial % 10);
    std::vector<double> from(count), packed(count + 2, 9.5), scalar(count + 2, 9.5);
    for (std::size_t i = 0; i < count; ++i) {
      packed[i + 1] = scalar[i + 1] = std::uniform_real_distribution<double>(-1.0, 1.0)(random);
      // The same value (half of them), another value, or 0 replaced by -0.
      switch (std::uniform_int_distribution<int>(0, 3)(random)) {
        case 1: from[i] = std::uniform_real_distribution<double>(-1.0, 1.0)(random); break;
        case 2:
          packed[i + 1] = scalar[i + 1] = 0.0;
          from[i] = -0.0;
          break;
        default: from[i] = packed[i + 1]; break;
      }
    }
    bool any_bits_differ = false;
    for (std::size_t i = 0; i < count; ++i) any_bits_differ |= bits(from[i]) != bits(packed[i + 1]);
    // Unaligned on purpose (one element in) as the FMU's table block may be.
    const bool packed_changed = copyChanged(packed.data() + 1, from.data(), count);
    const bool scalar_changed = copyChangedScalar(scalar.data() + 1, from.data(), count);
    ASSERT_EQ(packed_changed, any_bits_differ) << "trial " << trial;
    ASSERT_EQ(scalar_changed, any_bits_differ) << "trial " << trial;
    for (std::size_t i = 0; i < count; ++i) {
      ASSERT_EQ(bits(packed[i + 1]), bits(from[i]));
      ASSERT_EQ(bits(scalar[i + 1]), bits(from[i]));
    }
    EXPECT_EQ(packed.front(), 9.5);  // nothing written before or after the block
    EXPECT_EQ(packed.back(), 9.5);
  }
}

TEST(ValueBlocks, ASignOfZeroAloneIsAChange) {
  for (std::size_t count = 1; count <= 5; ++count) {
    for (std::size_t at = 0; at < count; ++at) {
      std::vector<double> to(count, 0.0), from(count, 0.0);
      EXPECT_FALSE(copyChanged(to.data(), from.data(), count));
      from[at] = -0.0;
      EXPECT_TRUE(copyChanged(to.data(), from.data(), count)) << at << " of " << count;
      EXPECT_TRUE(std::signbit(to[at]));
    }
  }
}

}  // namespace
}  // namespace jointcomp::fmu
