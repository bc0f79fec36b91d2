#include "laser_raycast/core/plane_views.h"

#include <cmath>
#include <cstddef>
#include <limits>

#include "laser_raycast/core/beam_window.h"
#include "laser_raycast/core/simd_math.h"

namespace laser_raycast {
namespace core {
namespace {

using simd::absPs;
using simd::atan2Ps;
using simd::kViewSlack;
using simd::selectPs;

// floor(x) for |x| < 2^31 (SSE2 converts by truncation).
inline __m128 floorPs(__m128 x) {
  const __m128 t = _mm_cvtepi32_ps(_mm_cvttps_epi32(x));
  return _mm_sub_ps(t, _mm_and_ps(_mm_cmpgt_ps(t, x), _mm_set1_ps(1.0f)));
}

// The circle around a box bounds its bearings loosely: for a long box seen end on, many times
// wider than the box. Its corners bound them tightly: seen from the sensor, the bearings of a box
// that does not hold the sensor span those of its corners. Each corner's bearing relative to the
// centre's direction u = (sx, sy), delta, is bounded by tan delta = (u x c) / (u . c), which is
// farther from 0 than delta on either side; a window [min, max] of those around the centre's
// bearing holds the box's (u points into the box, so its extreme bearings lie on both sides of u,
// but for u's rounding, a turn of 1e-7 rad, where tan delta and delta agree far below the pad).
// Where a corner is 60 degrees or more off u (dot < |u| |c| / 2; near the sensor), the circle's
// half-width is kept.
//
// The rounding: a corner in the sensor frame is off by at most the slack times the magnitudes
// (mx, my, as for the box's extents), which turns it by at most that over its distance (no less
// than nearest); the float cross and dot products, the division and u's own rounding (u is only
// the reference direction: the centre's bearing is computed from the same floats) add a few ulps
// of tan 60 degrees, far below kCornerError.
void tightenToCorners(__m128 lo_x, __m128 lo_y, __m128 hi_x, __m128 hi_y, __m128 sx, __m128 sy,
                      __m128 mx, __m128 my, __m128 nearest, const __m128 (&map)[6], __m128* center,
                      __m128* half) {
  constexpr float kCornerError = 1e-5f;
  const __m128 xs[2] = {lo_x, hi_x}, ys[2] = {lo_y, hi_y};
  const __m128 quarter_u2 =
      _mm_mul_ps(_mm_set1_ps(0.25f), _mm_add_ps(_mm_mul_ps(sx, sx), _mm_mul_ps(sy, sy)));
  __m128 lo = _mm_set1_ps(std::numeric_limits<float>::infinity());
  __m128 hi = _mm_sub_ps(_mm_setzero_ps(), lo);
  __m128 ok = _mm_castsi128_ps(_mm_set1_epi32(-1));
  for (int i = 0; i < 4; ++i) {
    const __m128 x = xs[i & 1], y = ys[i >> 1];
    // map: a, b, c, d, tx, ty (PlaneFrame's, in float).
    const __m128 cx = _mm_add_ps(_mm_add_ps(_mm_mul_ps(map[0], x), _mm_mul_ps(map[1], y)), map[4]);
    const __m128 cy = _mm_add_ps(_mm_add_ps(_mm_mul_ps(map[2], x), _mm_mul_ps(map[3], y)), map[5]);
    const __m128 cross = _mm_sub_ps(_mm_mul_ps(sx, cy), _mm_mul_ps(sy, cx));
    const __m128 dot = _mm_add_ps(_mm_mul_ps(sx, cx), _mm_mul_ps(sy, cy));
    // dot > 0 and dot^2 > |u|^2 |c|^2 / 4 (NaN: not ok).
    const __m128 c2 = _mm_add_ps(_mm_mul_ps(cx, cx), _mm_mul_ps(cy, cy));
    ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmpgt_ps(dot, _mm_setzero_ps()),
                                   _mm_cmpgt_ps(_mm_mul_ps(dot, dot), _mm_mul_ps(quarter_u2, c2))));
    const __m128 t = _mm_div_ps(cross, dot);
    lo = _mm_min_ps(lo, t);
    hi = _mm_max_ps(hi, t);
  }
  // The corners' turn by their rounding: slack times the magnitudes over the nearest distance.
  const __m128 shift =
      _mm_div_ps(_mm_mul_ps(_mm_set1_ps(4 * kViewSlack), _mm_add_ps(mx, my)), nearest);
  const __m128 pad = _mm_add_ps(shift, _mm_set1_ps(kCornerError));
  const __m128 tight_half = _mm_add_ps(_mm_mul_ps(_mm_sub_ps(hi, lo), _mm_set1_ps(0.5f)), pad);
  const __m128 tight_center =
      _mm_add_ps(*center, _mm_mul_ps(_mm_add_ps(lo, hi), _mm_set1_ps(0.5f)));
  // Only where every corner was usable, the pad is finite and the result is tighter.
  ok = _mm_and_ps(ok, _mm_cmplt_ps(tight_half, *half));
  *center = selectPs(ok, tight_center, *center);
  *half = selectPs(ok, tight_half, *half);
}

}  // namespace

PlaneViewFrame::PlaneViewFrame(const PlaneFrame& p, double tmax, const ScanPattern& fan) {
  auto set = [](double x) { return _mm_set1_ps(static_cast<float>(x)); };
  a_ = set(p.a);
  b_ = set(p.b);
  c_ = set(p.c);
  d_ = set(p.d);
  abs_a_ = set(std::abs(p.a));
  abs_b_ = set(std::abs(p.b));
  abs_c_ = set(std::abs(p.c));
  abs_d_ = set(std::abs(p.d));
  tx_ = set(p.tx);
  ty_ = set(p.ty);
  abs_tx_ = set(std::abs(p.tx));
  abs_ty_ = set(std::abs(p.ty));
  tmax_ = _mm_set1_ps(floatAbove(tmax));
  const double inv = 1 / fan.angleIncrement();
  const double turn = 2 * M_PI * inv;
  columns_ = fan.azimuthCount();
  fast_ = (columns_ - 1) * fan.angleIncrement() <= 2 * M_PI && turn < 1e6;
  start_ = set(fan.angleMin());
  inv_increment_ = set(inv);
  turn_ = set(turn);
  inv_turn_ = set(1 / turn);
  // The float rounding of an index: a few ulps of the magnitudes involved (the angles in units of
  // columns, a turn, the fan), with room to spare.
  const double magnitude = (std::abs(fan.angleMin()) + 2 * M_PI) * inv + turn + columns_;
  pad_ = set(64 * std::numeric_limits<float>::epsilon() * magnitude + 0.01);
}

void PlaneViews::compute(const WideBvh::Node& node, const PlaneViewFrame& f) {
  const __m128 half_ps = _mm_set1_ps(0.5f), slack = _mm_set1_ps(kViewSlack);
  const __m128 lo_x = _mm_load_ps(node.lo[0]), lo_y = _mm_load_ps(node.lo[1]);
  const __m128 hi_x = _mm_load_ps(node.hi[0]), hi_y = _mm_load_ps(node.hi[1]);
  const __m128 cx = _mm_mul_ps(_mm_add_ps(lo_x, hi_x), half_ps);
  const __m128 cy = _mm_mul_ps(_mm_add_ps(lo_y, hi_y), half_ps);
  const __m128 ex = _mm_mul_ps(_mm_sub_ps(hi_x, lo_x), half_ps);
  const __m128 ey = _mm_mul_ps(_mm_sub_ps(hi_y, lo_y), half_ps);
  // The boxes in the sensor's x, y: centre and half extents, widened by the rounding.
  const __m128 sx = _mm_add_ps(_mm_add_ps(_mm_mul_ps(f.a_, cx), _mm_mul_ps(f.b_, cy)), f.tx_);
  const __m128 sy = _mm_add_ps(_mm_add_ps(_mm_mul_ps(f.c_, cx), _mm_mul_ps(f.d_, cy)), f.ty_);
  __m128 wx = _mm_add_ps(_mm_mul_ps(f.abs_a_, ex), _mm_mul_ps(f.abs_b_, ey));
  __m128 wy = _mm_add_ps(_mm_mul_ps(f.abs_c_, ex), _mm_mul_ps(f.abs_d_, ey));
  const __m128 ax = _mm_add_ps(absPs(cx), ex), ay = _mm_add_ps(absPs(cy), ey);
  const __m128 mx =
      _mm_add_ps(_mm_add_ps(f.abs_tx_, _mm_mul_ps(f.abs_a_, ax)), _mm_mul_ps(f.abs_b_, ay));
  const __m128 my =
      _mm_add_ps(_mm_add_ps(f.abs_ty_, _mm_mul_ps(f.abs_c_, ax)), _mm_mul_ps(f.abs_d_, ay));
  wx = _mm_add_ps(wx, _mm_mul_ps(slack, _mm_add_ps(mx, wx)));
  wy = _mm_add_ps(wy, _mm_mul_ps(slack, _mm_add_ps(my, wy)));
  // Nearest distance: the norm of the gap between the sensor and the box, lowered by the slack.
  const __m128 zero = _mm_setzero_ps();
  const __m128 gx = _mm_max_ps(_mm_sub_ps(absPs(sx), wx), zero);
  const __m128 gy = _mm_max_ps(_mm_sub_ps(absPs(sy), wy), zero);
  const __m128 sum = _mm_add_ps(_mm_mul_ps(gx, gx), _mm_mul_ps(gy, gy));
  const __m128 finite = _mm_cmplt_ps(sum, _mm_set1_ps(std::numeric_limits<float>::infinity()));
  __m128 nearest = selectPs(finite, _mm_sqrt_ps(sum), _mm_max_ps(gx, gy));
  const __m128 magnitude = _mm_add_ps(_mm_add_ps(absPs(sx), wx), _mm_add_ps(absPs(sy), wy));
  nearest =
      _mm_max_ps(_mm_sub_ps(nearest, _mm_mul_ps(slack, _mm_add_ps(nearest, magnitude))), zero);
  _mm_store_ps(near, nearest);
  mask = _mm_movemask_ps(_mm_cmple_ps(nearest, f.tmax_)) & node.presentMask();
  columns_known = 0;
  if (!mask) return;

  // Bearings: the box lies in a disc of radius r around (sx, sy); seen from the sensor the disc
  // spans half-angle asin(r / rho) <= r / sqrt(rho^2 - r^2), unless it holds the sensor (or nearly:
  // then every bearing). The box's corners narrow that where they can (tightenToCorners).
  const __m128 rho2 = _mm_add_ps(_mm_mul_ps(sx, sx), _mm_mul_ps(sy, sy));
  const __m128 r2 = _mm_add_ps(_mm_mul_ps(wx, wx), _mm_mul_ps(wy, wy));
  const __m128 widen = _mm_set1_ps(1 + 8 * kViewSlack);
  const __m128 limited = _mm_cmpgt_ps(rho2, _mm_mul_ps(r2, widen));
  const __m128 denom = _mm_sqrt_ps(_mm_max_ps(_mm_sub_ps(rho2, r2), _mm_set1_ps(1e-30f)));
  __m128 half = _mm_mul_ps(_mm_div_ps(_mm_sqrt_ps(r2), denom), widen);
  __m128 center = atan2Ps(sy, sx);
  const __m128 map[6] = {f.a_, f.b_, f.c_, f.d_, f.tx_, f.ty_};
  tightenToCorners(lo_x, lo_y, hi_x, hi_y, sx, sy, mx, my, nearest, map, &center, &half);
  half = _mm_add_ps(half, _mm_set1_ps(static_cast<float>(2 * kBearingError)));
  const __m128 narrow = _mm_and_ps(limited, _mm_cmplt_ps(half, _mm_set1_ps(1.5f)));
  _mm_store_ps(az_half, selectPs(narrow, half, _mm_set1_ps(-1)));
  _mm_store_ps(az_center, center);
  if (!f.fast_) return;

  // Columns: the window's start in columns from the fan's start, reduced into [0, turn); known
  // where the window neither starts before the fan nor ends after a turn (no wrap).
  __m128 s = _mm_mul_ps(_mm_sub_ps(_mm_sub_ps(center, half), f.start_), f.inv_increment_);
  s = _mm_sub_ps(s, _mm_mul_ps(f.turn_, floorPs(_mm_mul_ps(s, f.inv_turn_))));
  const __m128 lo = _mm_sub_ps(s, f.pad_);
  const __m128 hi =
      _mm_add_ps(_mm_add_ps(s, _mm_mul_ps(_mm_add_ps(half, half), f.inv_increment_)), f.pad_);
  const __m128 inside = _mm_and_ps(_mm_cmpge_ps(lo, zero), _mm_cmplt_ps(hi, f.turn_));
  columns_known = _mm_movemask_ps(_mm_and_ps(narrow, inside)) & mask;
  if (!columns_known) return;
  // ceil(lo) and floor(hi), both >= 0 here; hi clamped to the last column (and far below 2^31).
  const __m128i lo_i = _mm_cvttps_epi32(lo);
  const __m128i lo_up =
      _mm_sub_epi32(lo_i, _mm_castps_si128(_mm_cmpgt_ps(lo, _mm_cvtepi32_ps(lo_i))));
  const __m128 hi_c = _mm_min_ps(hi, _mm_set1_ps(static_cast<float>(f.columns_ - 1)));
  _mm_store_si128(reinterpret_cast<__m128i*>(col_lo), lo_up);
  _mm_store_si128(reinterpret_cast<__m128i*>(col_hi), _mm_cvttps_epi32(hi_c));
}

}  // namespace core
}  // namespace laser_raycast
