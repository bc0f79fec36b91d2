// Small SSE2 helpers shared by the float computations in front of the exact tests (node_views.cpp,
// slice_views.cpp, column_raster.h, primitive_cast.cpp).
#pragma once

#include <emmintrin.h>

#include <cmath>
#include <limits>

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

// The bearings of a box's corners off a reference direction u = (ux, uy) pointing into the box,
// four boxes at a time, for the narrow windows of node_views.cpp and slice_views.cpp. A corner's
// bearing off u, delta, is bounded by tan delta = (u x c) / (u . c), which is farther from 0 than
// delta on either side; seen from the sensor, a convex box that does not hold it spans the bearings
// of its corners, on both sides of u (but for u's rounding: where tan delta and delta agree far
// below any pad). So [lo, hi] of the corners' tangents, around u's bearing, holds the box's.
// A corner 60 degrees or more off u (u . c < |u| |c| / 2), or NaN, clears ok: a box that near the
// sensor keeps its coarser window.
struct CornerTangents {
  __m128 lo = _mm_set1_ps(std::numeric_limits<float>::infinity());
  __m128 hi = _mm_set1_ps(-std::numeric_limits<float>::infinity());
  __m128 min_dot = _mm_set1_ps(std::numeric_limits<float>::infinity());
  __m128 ok = _mm_castsi128_ps(_mm_set1_epi32(-1));

  // u2: |u|^2.
  void add(__m128 x, __m128 y, __m128 ux, __m128 uy, __m128 u2) {
    const __m128 cross = _mm_sub_ps(_mm_mul_ps(ux, y), _mm_mul_ps(uy, x));
    const __m128 dot = _mm_add_ps(_mm_mul_ps(ux, x), _mm_mul_ps(uy, y));
    const __m128 c2 = _mm_add_ps(_mm_mul_ps(x, x), _mm_mul_ps(y, y));
    const __m128 quarter = _mm_mul_ps(_mm_set1_ps(0.25f), _mm_mul_ps(u2, c2));
    ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmpgt_ps(dot, _mm_setzero_ps()),
                                   _mm_cmpgt_ps(_mm_mul_ps(dot, dot), quarter)));
    const __m128 t = _mm_div_ps(cross, dot);
    lo = _mm_min_ps(lo, t);
    hi = _mm_max_ps(hi, t);
    min_dot = _mm_min_ps(min_dot, dot);
  }

  // Narrows the window (*center, *half: bearings, rad) to [lo, hi] around it where every corner
  // was usable and that is narrower. The corners may each be off by up to `error` (sensor frame):
  // that turns a corner by at most error / |c| <= error |u| / (u . c), and its tangent by at most
  // four times that within 60 degrees; kRoundingPad covers the float cross and dot products and
  // the division (a few ulps of tan 60 degrees) and the sums below.
  void narrow(__m128 error, __m128 u2, __m128* center, __m128* half) const {
    constexpr float kRoundingPad = 1e-5f;
    const __m128 shift =
        _mm_div_ps(_mm_mul_ps(_mm_mul_ps(_mm_set1_ps(4.0f), error), _mm_sqrt_ps(u2)), min_dot);
    const __m128 tight_half =
        _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_sub_ps(hi, lo), _mm_set1_ps(0.5f)), shift),
                   _mm_set1_ps(kRoundingPad));
    const __m128 tight_center =
        _mm_add_ps(*center, _mm_mul_ps(_mm_add_ps(lo, hi), _mm_set1_ps(0.5f)));
    const __m128 use = _mm_and_ps(ok, _mm_cmplt_ps(tight_half, *half));  // NaN: not used
    *center = selectPs(use, tight_center, *center);
    *half = selectPs(use, tight_half, *half);
  }
};

}  // namespace simd
}  // namespace core
}  // namespace laser_raycast
