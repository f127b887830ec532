// Bit-for-bit equality of doubles: what "unchanged" means where a cache or a round trip must be exact
// (NaN equals the same NaN, -0 differs from +0), compared as integers.
#pragma once

#include <cstdint>
#include <cstring>

namespace jointcomp {

inline std::uint64_t bitsOf(double x) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &x, sizeof bits);
  return bits;
}

inline bool sameBits(double a, double b) { return bitsOf(a) == bitsOf(b); }

}  // namespace jointcomp
