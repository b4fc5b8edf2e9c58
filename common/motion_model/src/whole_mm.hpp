#pragma once
// whole_mm (motion_model.hpp) inline, for the code that converts every value of every instance
// learned: the history and the table call these in their loops; everyone else the functions.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "ssl_formation/motion_model/motion_model.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace ssl_formation {
inline namespace motion_model {
namespace detail {

inline std::int32_t whole_mm_of(double value) {
  // Round half away from zero without std::round's call: this runs for every value of every
  // instance trained. Adding copysign(0.5) is adding 0.5 or subtracting it, without a branch on
  // the sign, which half the velocities and displacements would mispredict.
  const double clamped = std::clamp(value, -1.0e9, 1.0e9);
  return static_cast<std::int32_t>(clamped + std::copysign(0.5, clamped));
}

inline WholePoint whole_mm_of(Point p) {
#if defined(__SSE2__)
  // Both coordinates in one register: the clamp, the signed half and the truncation are one
  // instruction each for the two (whole_mm(double) is about fourteen per value, two of them
  // jumps), and training converts 14 values per instance learned. The operands are ordered as
  // whole_mm(double) computes: a NaN stays NaN through the clamp and truncates to the same
  // integer.
  static_assert(offsetof(Point, y) == sizeof(double), "x and y are loaded as one pair");
  __m128d v = _mm_loadu_pd(&p.x);
  v = _mm_max_pd(_mm_set1_pd(-1.0e9), v);
  v = _mm_min_pd(_mm_set1_pd(1.0e9), v);
  const __m128d sign = _mm_and_pd(v, _mm_set1_pd(-0.0));
  v = _mm_add_pd(v, _mm_or_pd(sign, _mm_set1_pd(0.5)));
  const __m128i whole = _mm_cvttpd_epi32(v);
  return {_mm_cvtsi128_si32(whole), _mm_cvtsi128_si32(_mm_srli_si128(whole, 4))};
#else
  return {whole_mm_of(p.x), whole_mm_of(p.y)};
#endif
}

}  // namespace detail
}  // namespace motion_model
}  // namespace ssl_formation
