// Which beams of a rectangle of the beam grid may hit one triangle: the cost grows with the columns
// and the beams inside, not with the rectangle's area (for a short rect, with its rows times its
// columns that the triangle can reach, four columns at a time).
//
// Every beam starts at the sensor, so beam d passes through triangle (a, b, c) (sensor frame)
// exactly where m.d >= 0 for the three edge planes through the sensor, m = b x c, c x a, a x b
// (oriented inwards). A beam of elevation E and azimuth A is d = (cos E cos A, cos E sin A, sin E);
// dividing m.d by cos E > 0 leaves h(A) + m_z tan E with h(A) = m_x cos A + m_y sin A, linear in
// tan E. So in each column every edge bounds tan E from one side, and the beams inside are the rows
// whose tan E lies between the bounds: two look-ups per column in a tall rect, or in a short one
// each row's tan E compared with four columns' bounds at once. All of it is in float with a
// margin far above its rounding (the normals are scaled to |m|_1 = 1), so every beam the exact
// test could hit is let through, and the exact test decides.
//
// A beam is also held back when its current range is clearly nearer than the triangle's plane
// along it (t = |n.a| / |n.d| for the plane's normal n): such a hit could not be kept.
//
// For a block of a rotating sweep (beams/column_motion.h), whose beams leave from poses near the
// reference one, `widen` is sin(alpha): a beam turned by at most `turn` from d and leaving from at
// most `shift` from the sensor meets the triangle only if d lies within alpha = turn +
// asin(shift / near) of the triangle's cone from the sensor (near: no point of it is nearer), so
// within sin(alpha) of each unit edge plane, and |m|_2 <= |m|_1 = 1 makes that m.d >= -sin(alpha).
// The range test then takes the plane's distance from the sensor less `shift` (no origin is nearer
// to the plane by more) over |n.d| plus `turn` (|n.d' - n.d| <= |d' - d| <= turn for the scaled n).
#pragma once

#include <emmintrin.h>

#include <Eigen/Geometry>
#include <cmath>

#include "beams/beam_set.h"
#include "util/simd_math.h"

namespace laser_raycast {
namespace core {

// |[a, b, c]| (the triangle's corners as seen from the sensor) below this fraction of |a| |b| |c|:
// the triangle is seen nearly edge-on, and its edge planes say little about which beams meet it, so
// the column raster (ColumnRaster) and the row scan (EdgeFilter, edge_filter.h) test every beam.
inline constexpr double kEdgeOnRatio = 1e-6;

class ColumnRaster {
 public:
  // a, b, c in the sensor frame. The pattern's rows must allow it (BeamGrid::columnRaster()).
  ColumnRaster(const BeamSet& beams, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
               const Eigen::Vector3d& c, double widen = 0, double shift = 0, double turn = 0);

  // Calls f(row, col) for every beam of rect that may hit the triangle nearer than its current
  // range: row by row in a rect of fewer than kRowMajorRows rows, else column by column.
  template <class F>
  void forEachCandidate(const BeamSet& beams, const BeamRect& rect, F&& f) const;

 private:
  // The margin of every float test, relative to the scaled normals: the rounding of a dot
  // product of float normals and float directions is a few 1e-7, tan E's up to tan 80 degrees
  // (BeamGrid::kMaxColumnRasterElevation) a few times that.
  static constexpr float kMargin = 1e-5f;
  // Rects of fewer rows than this are scanned row by row, four columns at a time; taller ones
  // column by column, each column's rows looked up from its bounds. Only speed depends on it.
  static constexpr int kRowMajorRows = 16;
  // Four columns' bounds on tan E, their h(A) for the plane, and which of them are candidates.
  struct Group {
    __m128 lo, hi, hn;
    int base, mask;
  };
  // The groups are gathered, then scanned, this many at a time (an array on the stack).
  static constexpr int kChunkGroups = 16;
  template <class F>
  void scanRows(const BeamSet& beams, const BeamRect& rect, const Group* groups, int n,
                F&& f) const;
  template <class F>
  void scanColumns(const BeamSet& beams, const BeamRect& rect, const Group* groups, int n,
                   F&& f) const;

  bool all_ = false;  // seen edge-on, or too small for float: every beam of the rect is a candidate
  // Per edge: (m_x, m_y) scaled, and what the bound on tan E does: lower (m_z > 0), upper
  // (m_z < 0) or nothing (m_z = 0: the edge decides by h(A) alone).
  __m128 mx_[3], my_[3], inv_mz_[3], lower_[3], upper_[3], flat_[3];
  __m128 edge_margin_;  // the margin over the smallest cos E of the pattern
  // The plane: normal (scaled), |n.a| rounded down.
  __m128 nx_, ny_;
  float nz_, plane_distance_;
  float along_margin_ = kMargin;  // kMargin, plus a sweep block's turn
};

template <class F>
void ColumnRaster::forEachCandidate(const BeamSet& beams, const BeamRect& rect, F&& f) const {
  if (all_) {
    for (int col = rect.col_lo; col <= rect.col_hi; ++col) {
      for (int row = rect.row_lo; row <= rect.row_hi; ++row) f(row, col);
    }
    return;
  }
  const float* cos_a = beams.grid().columnCos();
  const float* sin_a = beams.grid().columnSin();
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
  const __m128 rows_tan_lo = _mm_set1_ps(beams.grid().rowTanBelow(rect.row_lo));
  const __m128 rows_tan_hi = _mm_set1_ps(beams.grid().rowTanAbove(rect.row_hi));
  const bool by_rows = rect.row_hi - rect.row_lo < kRowMajorRows;
  // The columns' bounds, a chunk of groups of four at a time: only the groups with a column
  // whose bounds meet the rect's rows.
  Group groups[kChunkGroups];
  int n = 0;
  auto flush = [&] {
    if (by_rows) {
      scanRows(beams, rect, groups, n, f);
    } else {
      scanColumns(beams, rect, groups, n, f);
    }
    n = 0;
  };
  for (int base = rect.col_lo & ~3; base <= rect.col_hi; base += 4) {
    const __m128 ca = _mm_loadu_ps(cos_a + base), sa = _mm_loadu_ps(sin_a + base);
    __m128 lo = _mm_sub_ps(_mm_setzero_ps(), inf), hi = inf;
    for (int k = 0; k < 3; ++k) {
      const __m128 h = _mm_add_ps(_mm_mul_ps(mx_[k], ca), _mm_mul_ps(my_[k], sa));
      // h + m_z tan E >= -margin  <=>  tan E >= or <= (-margin - h) / m_z.
      const __m128 bound =
          _mm_mul_ps(_mm_sub_ps(_mm_sub_ps(_mm_setzero_ps(), edge_margin_), h), inv_mz_[k]);
      lo = _mm_max_ps(lo, _mm_or_ps(_mm_and_ps(lower_[k], bound), _mm_andnot_ps(lower_[k], lo)));
      hi = _mm_min_ps(hi, _mm_or_ps(_mm_and_ps(upper_[k], bound), _mm_andnot_ps(upper_[k], hi)));
      // A flat edge (m_z = 0) keeps a column only if h >= -margin.
      const __m128 out =
          _mm_and_ps(flat_[k], _mm_cmplt_ps(h, _mm_sub_ps(_mm_setzero_ps(), edge_margin_)));
      lo = _mm_or_ps(_mm_and_ps(out, inf), _mm_andnot_ps(out, lo));
    }
    // The columns whose bounds meet the rect's rows' (float bounds on their tan E): only those
    // need their rows looked at.
    int mask = _mm_movemask_ps(
        _mm_and_ps(_mm_cmple_ps(lo, hi),
                   _mm_and_ps(_mm_cmpnlt_ps(rows_tan_hi, lo), _mm_cmpnlt_ps(hi, rows_tan_lo))));
    const int first = std::max(base, rect.col_lo), last = std::min(base + 3, rect.col_hi);
    mask &= (0xF << (first - base)) & (0xF >> (base + 3 - last));
    if (!mask) continue;
    Group& g = groups[n++];
    g.base = base;
    g.mask = mask;
    g.lo = lo;
    g.hi = hi;
    g.hn = _mm_add_ps(_mm_mul_ps(nx_, ca), _mm_mul_ps(ny_, sa));
    if (n == kChunkGroups) flush();
  }
  if (n > 0) flush();
}

template <class F>
void ColumnRaster::scanRows(const BeamSet& beams, const BeamRect& rect, const Group* groups, int n,
                            F&& f) const {
  const __m128 margin = _mm_set1_ps(along_margin_), distance = _mm_set1_ps(plane_distance_);
  const __m128 nz = _mm_set1_ps(nz_);
  for (int row = rect.row_lo; row <= rect.row_hi; ++row) {
    const __m128 tan_lo = _mm_set1_ps(beams.grid().rowTanBelow(row));
    const __m128 tan_hi = _mm_set1_ps(beams.grid().rowTanAbove(row));
    const __m128 cos_e = _mm_set1_ps(beams.grid().rowCos(row));
    const __m128 z = _mm_mul_ps(nz, _mm_set1_ps(beams.grid().rowSin(row)));
    const float* range = beams.rangeAbove(row);
    for (int i = 0; i < n; ++i) {
      const Group& g = groups[i];
      // The row's tan E within the column's bounds, as scanColumns looks rows up: for a float
      // bound x, tan E >= x exactly iff tan E rounded down is, and <= x iff rounded up is. And
      // not clearly beyond the beam's range; written so that a NaN range is never held back.
      const __m128 along = _mm_add_ps(simd::absPs(_mm_add_ps(_mm_mul_ps(cos_e, g.hn), z)), margin);
      const __m128 in =
          _mm_and_ps(_mm_and_ps(_mm_cmpge_ps(tan_lo, g.lo), _mm_cmple_ps(tan_hi, g.hi)),
                     _mm_cmpngt_ps(distance, _mm_mul_ps(_mm_loadu_ps(range + g.base), along)));
      for (int mask = _mm_movemask_ps(in) & g.mask; mask; mask &= mask - 1) {
        f(row, g.base + __builtin_ctz(static_cast<unsigned>(mask)));
      }
    }
  }
}

template <class F>
void ColumnRaster::scanColumns(const BeamSet& beams, const BeamRect& rect, const Group* groups,
                               int n, F&& f) const {
  for (int i = 0; i < n; ++i) {
    const Group& g = groups[i];
    alignas(16) float lo_v[4], hi_v[4], hn_v[4];
    _mm_store_ps(lo_v, g.lo);
    _mm_store_ps(hi_v, g.hi);
    _mm_store_ps(hn_v, g.hn);
    for (int mask = g.mask; mask; mask &= mask - 1) {
      const int j = __builtin_ctz(static_cast<unsigned>(mask));
      const int col = g.base + j;
      int row_lo, row_hi;
      beams.grid().rowsWithTan(lo_v[j], hi_v[j], &row_lo, &row_hi);
      row_lo = std::max(row_lo, rect.row_lo);
      row_hi = std::min(row_hi, rect.row_hi);
      for (int row = row_lo; row <= row_hi; ++row) {
        // Written so that a NaN range (a beam that could not be cast) is never held back.
        const float along =
            std::abs(beams.grid().rowCos(row) * hn_v[j] + nz_ * beams.grid().rowSin(row)) +
            along_margin_;
        if (plane_distance_ > beams.rangeAbove(row)[col] * along) continue;
        f(row, col);
      }
    }
  }
}

}  // namespace core
}  // namespace laser_raycast
