// Checks and copies of a block of doubles for the FMU's planned set (fmu/core/instance.cpp): two values per
// instruction with SSE2 (every x86-64 has it), one at a time elsewhere. A set of the 6 desired joint
// positions, the importer's call at every communication step, spent 126 instructions in these two loops
// one value at a time, and 46 two at a time. The scalar forms are always compiled: they define the result,
// and tests/fmu/test_value_blocks.cpp checks the packed forms against them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace jointcomp::fmu {

// True when every values[i] lies in [lowest[i], highest[i]]; NaN lies in no interval.
inline bool allWithinScalar(const double values[], const double lowest[], const double highest[], std::size_t count) {
  bool inside = true;
  for (std::size_t i = 0; i < count; ++i) inside &= (values[i] >= lowest[i]) & (values[i] <= highest[i]);
  return inside;
}

// to[i] = from[i] for the count values; true when the bits of any of them changed (so -0 for 0 is a change,
// as sameBits has it).
inline bool copyChangedScalar(double to[], const double from[], std::size_t count) {
  std::uint64_t differ = 0;
  for (std::size_t i = 0; i < count; ++i) {
    std::uint64_t old_bits, new_bits;
    std::memcpy(&old_bits, &to[i], sizeof old_bits);
    std::memcpy(&new_bits, &from[i], sizeof new_bits);
    differ |= old_bits ^ new_bits;
    to[i] = from[i];
  }
  return differ != 0;
}

[[gnu::always_inline]] inline bool allWithin(const double values[], const double lowest[], const double highest[],
                                             std::size_t count) {
#if defined(__SSE2__)
  __m128d inside = _mm_castsi128_pd(_mm_set1_epi32(-1));
  std::size_t i = 0;
  for (; i + 2 <= count; i += 2) {
    const __m128d x = _mm_loadu_pd(values + i);
    // The compares are ordered: false for NaN, as the scalar ones.
    const __m128d above = _mm_cmpge_pd(x, _mm_loadu_pd(lowest + i));
    const __m128d below = _mm_cmple_pd(x, _mm_loadu_pd(highest + i));
    inside = _mm_and_pd(inside, _mm_and_pd(above, below));
  }
  const bool pairs_inside = _mm_movemask_pd(inside) == 3;
  return pairs_inside && allWithinScalar(values + i, lowest + i, highest + i, count - i);
#else
  return allWithinScalar(values, lowest, highest, count);
#endif
}

[[gnu::always_inline]] inline bool copyChanged(double to[], const double from[], std::size_t count) {
#if defined(__SSE2__)
  __m128i differ = _mm_setzero_si128();
  std::size_t i = 0;
  for (; i + 2 <= count; i += 2) {
    const __m128i old_bits = _mm_loadu_si128(reinterpret_cast<const __m128i*>(to + i));
    const __m128i new_bits = _mm_loadu_si128(reinterpret_cast<const __m128i*>(from + i));
    differ = _mm_or_si128(differ, _mm_xor_si128(old_bits, new_bits));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(to + i), new_bits);
  }
  const bool pairs_changed = _mm_movemask_epi8(_mm_cmpeq_epi8(differ, _mm_setzero_si128())) != 0xFFFF;
  return copyChangedScalar(to + i, from + i, count - i) | pairs_changed;
#else
  return copyChangedScalar(to, from, count);
#endif
}

}  // namespace jointcomp::fmu
