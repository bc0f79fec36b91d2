// Small SSE2 helpers shared by the float computations in front of the exact tests (node_views.cpp,
// plane_views.cpp, column_raster.h, primitive_cast.cpp).
#pragma once

#include <emmintrin.h>

#include <cmath>

namespace laser_raycast {
namespace core {
namespace simd {

// Relative slack for the float view arithmetic: every quantity is a few roundings (at 2^-24 each)
// away from its exact value, so widening by 32 of them keeps each window and distance on the safe
// side with room to spare.
inline constexpr float kViewSlack = 32.0f / (1 << 24);

inline __m128 absPs(__m128 x) { return _mm_andnot_ps(_mm_set1_ps(-0.0f), x); }
inline __m128 selectPs(__m128 mask, __m128 a, __m128 b) {
  return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b));
}

// approxAtan2 (beam_window.h) for four angles: the same polynomial, in float. The float rounding
// adds at most a few 1e-7 rad to the polynomial's 1e-5, within kBearingError.
inline __m128 atan2Ps(__m128 y, __m128 x) {
  const __m128 ax = absPs(x), ay = absPs(y);
  const __m128 big = _mm_max_ps(ax, ay), small = _mm_min_ps(ax, ay);
  const __m128 nonzero = _mm_cmpgt_ps(big, _mm_setzero_ps());
  const __m128 a = _mm_and_ps(nonzero, _mm_div_ps(small, selectPs(nonzero, big, _mm_set1_ps(1))));
  const __m128 z = _mm_mul_ps(a, a);
  __m128 p = _mm_set1_ps(0.0208351f);
  p = _mm_add_ps(_mm_mul_ps(p, z), _mm_set1_ps(-0.0851330f));
  p = _mm_add_ps(_mm_mul_ps(p, z), _mm_set1_ps(0.1801410f));
  p = _mm_add_ps(_mm_mul_ps(p, z), _mm_set1_ps(-0.3302995f));
  p = _mm_add_ps(_mm_mul_ps(p, z), _mm_set1_ps(0.9998660f));
  __m128 r = _mm_mul_ps(a, p);
  r = selectPs(_mm_cmpgt_ps(ay, ax), _mm_sub_ps(_mm_set1_ps(static_cast<float>(M_PI / 2)), r), r);
  r = selectPs(_mm_cmplt_ps(x, _mm_setzero_ps()),
               _mm_sub_ps(_mm_set1_ps(static_cast<float>(M_PI)), r), r);
  // The sign of y (also for -0, as atan2 does).
  return _mm_or_ps(r, _mm_and_ps(y, _mm_set1_ps(-0.0f)));
}

}  // namespace simd
}  // namespace core
}  // namespace laser_raycast
