#include "slice/slice_views.h"

#include <cmath>
#include <cstddef>
#include <limits>

#include "beams/beam_window.h"
#include "util/simd_math.h"

namespace laser_raycast {
namespace core {
namespace {

using simd::absPs;
using simd::atan2Ps;
using simd::CornerTangents;
using simd::kViewSlack;
using simd::selectPs;

// floor(x) for |x| < 2^31 (SSE2 converts by truncation).
inline __m128 floorPs(__m128 x) {
  const __m128 t = _mm_cvtepi32_ps(_mm_cvttps_epi32(x));
  return _mm_sub_ps(t, _mm_and_ps(_mm_cmpgt_ps(t, x), _mm_set1_ps(1.0f)));
}

}  // namespace

SliceViewBasis::SliceViewBasis(const ScanPlane& p, double tmax, const ScanPattern& fan,
                               const Spread& spread)
    : spread_(spread) {
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

LASER_RAYCAST_HOT_INLINE void SliceViews::storeColumns(const SliceViewBasis& f, __m128 center,
                                                       __m128 half, __m128 narrow) {
  const __m128 zero = _mm_setzero_ps();
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

void SliceViews::compute(const WideBvh::Node& node, const SliceViewBasis& f) {
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
  if (f.spread_.any) {  // every origin of a sweep block's beams
    wx = _mm_add_ps(wx, f.spread_.shift);
    wy = _mm_add_ps(wy, f.spread_.shift);
  }
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
  // then every bearing).
  const __m128 rho2 = _mm_add_ps(_mm_mul_ps(sx, sx), _mm_mul_ps(sy, sy));
  const __m128 r2 = _mm_add_ps(_mm_mul_ps(wx, wx), _mm_mul_ps(wy, wy));
  const __m128 widen = _mm_set1_ps(1 + 8 * kViewSlack);
  const __m128 limited = _mm_cmpgt_ps(rho2, _mm_mul_ps(r2, widen));
  const __m128 denom = _mm_sqrt_ps(_mm_max_ps(_mm_sub_ps(rho2, r2), _mm_set1_ps(1e-30f)));
  __m128 half = _mm_mul_ps(_mm_div_ps(_mm_sqrt_ps(r2), denom), widen);
  __m128 center = atan2Ps(sy, sx);
  // The circle is loose (up to 1.4 times a square box's bearings, many times a long box's seen
  // end on): the box's corners narrow it (simd::CornerTangents), but not with a spread, whose shift
  // can move a corner too far for the narrowing's bound. Each corner in the sensor's x, y is a few
  // roundings off, at most the slack times the magnitudes mx, my.
  if (!f.spread_.any) {
    CornerTangents corners;
    const __m128 xs[2] = {lo_x, hi_x}, ys[2] = {lo_y, hi_y};
    for (int i = 0; i < 4; ++i) {
      const __m128 x = xs[i & 1], y = ys[i >> 1];
      corners.add(_mm_add_ps(_mm_add_ps(_mm_mul_ps(f.a_, x), _mm_mul_ps(f.b_, y)), f.tx_),
                  _mm_add_ps(_mm_add_ps(_mm_mul_ps(f.c_, x), _mm_mul_ps(f.d_, y)), f.ty_), sx, sy,
                  rho2);
    }
    corners.narrow(_mm_mul_ps(slack, _mm_add_ps(mx, my)), rho2, &center, &half);
  }
  half = _mm_add_ps(half, _mm_set1_ps(static_cast<float>(2 * kBearingError)));
  half = f.spread_.widenHalf(half);
  const __m128 narrow =
      f.spread_.keepLimited(_mm_and_ps(limited, _mm_cmplt_ps(half, _mm_set1_ps(1.5f))));
  _mm_store_ps(az_half, selectPs(narrow, half, _mm_set1_ps(-1)));
  _mm_store_ps(az_center, center);
  if (!f.fast_) return;
  storeColumns(f, center, half, narrow);
}

}  // namespace core
}  // namespace laser_raycast
