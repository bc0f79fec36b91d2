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
//
// Given the block's ColumnMotion, the edge planes follow each column's origin o instead: the plane
// through o and edge (b, c) has the normal (b - o) x (c - o) = m - o x (c - b), linear in o, so
// each group of four columns gets its own three normals, and only the turn widens the tests. The
// shift then costs a triangle no columns, where the widening above adds asin(shift / near) to
// every side (a rack's small triangles a metre away, from a sensor moving a few millimetres in a
// block, gain two columns a side). It holds while no origin crosses the triangle's plane (then
// the inward orientation of the edges is the reference's); nearer planes take the widening.
// Scaled by the reference's |m|_1, a column's normal has |m'|_1 <= 1 + |o x e|_1 <= 1 +
// sqrt(3) shift |e|_1, which scales the margin and the turn's sin(turn) |m'|_2.
#pragma once

#include <emmintrin.h>

#include <Eigen/Geometry>
#include <cmath>

#include "beams/beam_set.h"
#include "beams/column_motion.h"
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
  // For a sweep's block: a, b, c in the reference sensor frame, the beams from motion's column
  // origins; near: no point of the triangle is nearer the reference sensor (a leaf's near). The
  // edge planes follow the columns' origins where the triangle's plane is farther than twice the
  // block's shift, else they are widened by it. motion must outlive the raster.
  ColumnRaster(const BeamSet& beams, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
               const Eigen::Vector3d& c, const ColumnMotion& motion, double near);

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
  static_assert(kRowMajorRows <= BeamGrid::kRowBlock, "scanRows reads a rect's rows at once");
  // Four columns' bounds on tan E, their h(A) for the plane, and which of them are candidates.
  struct Group {
    __m128 lo, hi, hn;
    int base, mask;
  };
  // The groups are gathered, then scanned, this many at a time (an array on the stack).
  static constexpr int kChunkGroups = 16;
  // The three normals, the widening and the plane from the reference pose; factor scales the
  // margin (a column's normals' largest |m|_1).
  // m: the edge normals b x c, c x a, a x b.
  // deviation: how far a beam's origin may lie from its column's (ColumnMotion::deviation).
  void init(const BeamSet& beams, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
            const Eigen::Vector3d& c, const Eigen::Vector3d (&m)[3], double widen, double shift,
            double turn, double deviation = 0);
  // Columns base..base + 3's bounds on tan E (lo > hi: none), from their cos A and sin A: from the
  // reference's normals with `margin`, or each column's own normals (following the origins).
  void referenceBounds(__m128 ca, __m128 sa, __m128 margin, __m128* lo, __m128* hi) const;
  void columnBounds(int base, __m128 ca, __m128 sa, __m128* lo, __m128* hi) const;
  // The columns whose bounds meet the rect's rows' (tan E from rows_lo to rows_hi), of first..last.
  static int meetsRows(__m128 lo, __m128 hi, __m128 rows_lo, __m128 rows_hi, int base, int first,
                       int last) {
    const int mask = _mm_movemask_ps(
        _mm_and_ps(_mm_cmple_ps(lo, hi),
                   _mm_and_ps(_mm_cmpnlt_ps(rows_hi, lo), _mm_cmpnlt_ps(hi, rows_lo))));
    return mask & (0xF << (first - base)) & (0xF >> (base + 3 - last));
  }
  template <class F>
  void scanRows(const BeamSet& beams, const BeamRect& rect, const Group* groups, int n,
                F&& f) const;
  template <class F>
  void scanColumns(const BeamSet& beams, const BeamRect& rect, const Group* groups, int n,
                   F&& f) const;

  bool all_ = false;  // seen edge-on, or too small for float: every beam of the rect is a candidate
  // What an edge's bound on tan E is: lower (m_z > 0), upper (m_z < 0), none (m_z = 0: h decides
  // alone), or any of these by column (kAny: a column's own normal may change the sign).
  enum class EdgeKind : char { kLower, kUpper, kFlat, kAny };
  // Per edge: (m_x, m_y) scaled, 1 / m_z (0 if m_z = 0) and its kind.
  __m128 mx_[3], my_[3], inv_mz_[3];
  EdgeKind kind_[3];
  __m128 edge_margin_;  // the margin over the smallest cos E of the pattern
  // Following the columns' origins: the block, each edge's m_z scaled and its (c - b, a - c,
  // b - a) scaled as m is.
  const ColumnMotion* motion_ = nullptr;
  __m128 mz_[3], ex_[3], ey_[3], ez_[3];
  EdgeKind column_kind_[3];  // kLower or kUpper where every column's m_z has the reference's sign
  // The margin of the reference's normals that lets through every column whose own normals do:
  // edge_margin_ plus the most any normal moves (|o x e|_2 <= shift |e|_1), a first cheap test.
  __m128 reference_margin_;
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
    __m128 lo, hi;
    referenceBounds(ca, sa, reference_margin_, &lo, &hi);
    // The columns whose bounds meet the rect's rows' (float bounds on their tan E): only those
    // need their rows looked at.
    const int first = std::max(base, rect.col_lo), last = std::min(base + 3, rect.col_hi);
    int mask = meetsRows(lo, hi, rows_tan_lo, rows_tan_hi, base, first, last);
    if (!mask) continue;
    if (motion_) {
      columnBounds(base, ca, sa, &lo, &hi);
      mask = meetsRows(lo, hi, rows_tan_lo, rows_tan_hi, base, first, last);
      if (!mask) continue;
    }
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

// One edge's bounds on tan E, into lo and hi, from its normal's h(A) = m_x cos A + m_y sin A and 1 /
// m_z, with masks of the columns where m_z > 0 (a lower bound), < 0 (an upper one) or = 0.
inline void edgeBounds(__m128 h, __m128 inv_mz, __m128 lower, __m128 upper, __m128 flat,
                       __m128 neg_margin, __m128* lo, __m128* hi) {
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
  // h + m_z tan E >= -margin  <=>  tan E >= or <= (-margin - h) / m_z.
  const __m128 bound = _mm_mul_ps(_mm_sub_ps(neg_margin, h), inv_mz);
  *lo = _mm_max_ps(*lo, _mm_or_ps(_mm_and_ps(lower, bound), _mm_andnot_ps(lower, *lo)));
  *hi = _mm_min_ps(*hi, _mm_or_ps(_mm_and_ps(upper, bound), _mm_andnot_ps(upper, *hi)));
  // A flat edge (m_z = 0) keeps a column only if h >= -margin.
  const __m128 out = _mm_and_ps(flat, _mm_cmplt_ps(h, neg_margin));
  *lo = _mm_or_ps(_mm_and_ps(out, inf), _mm_andnot_ps(out, *lo));
}

inline void ColumnRaster::referenceBounds(__m128 ca, __m128 sa, __m128 margin, __m128* lo,
                                          __m128* hi) const {
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
  const __m128 neg_margin = _mm_sub_ps(_mm_setzero_ps(), margin);
  __m128 l = _mm_sub_ps(_mm_setzero_ps(), inf), u = inf;
  // As edgeBounds with every column's masks equal (the reference's normals): each edge bounds
  // one side, or, flat, keeps a column by h alone. The kind is the same for every group of the
  // triangle, so the branch is predicted.
  for (int k = 0; k < 3; ++k) {
    const __m128 h = _mm_add_ps(_mm_mul_ps(mx_[k], ca), _mm_mul_ps(my_[k], sa));
    switch (kind_[k]) {
      case EdgeKind::kLower:
        l = _mm_max_ps(l, _mm_mul_ps(_mm_sub_ps(neg_margin, h), inv_mz_[k]));
        break;
      case EdgeKind::kUpper:
        u = _mm_min_ps(u, _mm_mul_ps(_mm_sub_ps(neg_margin, h), inv_mz_[k]));
        break;
      case EdgeKind::kFlat: {
        const __m128 out = _mm_cmplt_ps(h, neg_margin);
        l = _mm_or_ps(_mm_and_ps(out, inf), _mm_andnot_ps(out, l));
        break;
      }
      case EdgeKind::kAny:  // never the reference's
        break;
    }
  }
  *lo = l;
  *hi = u;
}

inline void ColumnRaster::columnBounds(int base, __m128 ca, __m128 sa, __m128* lo_out,
                                       __m128* hi_out) const {
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
  const __m128 zero = _mm_setzero_ps(), neg_margin = _mm_sub_ps(zero, edge_margin_);
  // Kept in registers until the end (written through the pointers, every step would be stored
  // and loaded again).
  __m128 lo = _mm_sub_ps(zero, inf), hi = inf;
  const __m128 ox = _mm_loadu_ps(motion_->originX(base));
  const __m128 oy = _mm_loadu_ps(motion_->originY(base));
  const __m128 oz = _mm_loadu_ps(motion_->originZ(base));
  for (int k = 0; k < 3; ++k) {
    // m - o x e, each column's own.
    const __m128 mx =
        _mm_sub_ps(mx_[k], _mm_sub_ps(_mm_mul_ps(oy, ez_[k]), _mm_mul_ps(oz, ey_[k])));
    const __m128 my =
        _mm_sub_ps(my_[k], _mm_sub_ps(_mm_mul_ps(oz, ex_[k]), _mm_mul_ps(ox, ez_[k])));
    const __m128 mz =
        _mm_sub_ps(mz_[k], _mm_sub_ps(_mm_mul_ps(ox, ey_[k]), _mm_mul_ps(oy, ex_[k])));
    const __m128 h = _mm_add_ps(_mm_mul_ps(mx, ca), _mm_mul_ps(my, sa));
    // As edgeBounds does it, without the masks where every column bounds the same side.
    if (column_kind_[k] != EdgeKind::kAny) {
      const __m128 bound = _mm_mul_ps(_mm_sub_ps(neg_margin, h), _mm_div_ps(_mm_set1_ps(1.0f), mz));
      if (column_kind_[k] == EdgeKind::kLower) {
        lo = _mm_max_ps(lo, bound);
      } else {
        hi = _mm_min_ps(hi, bound);
      }
      continue;
    }
    const __m128 flat = _mm_cmpeq_ps(mz, zero);
    // 1 / m_z where it is not 0 (there the bound is not used).
    const __m128 inv_mz = _mm_andnot_ps(flat, _mm_div_ps(_mm_set1_ps(1.0f), mz));
    edgeBounds(h, inv_mz, _mm_cmpgt_ps(mz, zero), _mm_cmplt_ps(mz, zero), flat, neg_margin, &lo,
               &hi);
  }
  *lo_out = lo;
  *hi_out = hi;
}

// All ones in the lanes of the bits of mask (bit j: lane j).
inline __m128 laneMask(int mask) {
  return _mm_castsi128_ps(_mm_cmpeq_epi32(
      _mm_and_si128(_mm_set1_epi32(mask), _mm_setr_epi32(1, 2, 4, 8)), _mm_setr_epi32(1, 2, 4, 8)));
}

// The rows of rect (at most BeamGrid::kRowBlock) whose tan E lies within [lo, hi], as a bit mask
// (bit i: row rect.row_lo + i), four rows a compare, no branches.
inline unsigned rowsWithin(const BeamGrid& grid, const BeamRect& rect, __m128 lo, __m128 hi) {
  const float* below = grid.rowTansBelow(rect.row_lo);
  const float* above = grid.rowTansAbove(rect.row_lo);
  const int rows = rect.row_hi - rect.row_lo + 1;
  unsigned mask = 0;
  for (int i = 0; i < rows; i += 4) {
    const __m128 in = _mm_and_ps(_mm_cmpge_ps(_mm_loadu_ps(below + i), lo),
                                 _mm_cmple_ps(_mm_loadu_ps(above + i), hi));
    mask |= static_cast<unsigned>(_mm_movemask_ps(in)) << i;
  }
  return mask & ((2u << (rows - 1)) - 1);
}

template <class F>
void ColumnRaster::scanRows(const BeamSet& beams, const BeamRect& rect, const Group* groups, int n,
                            F&& f) const {
  const __m128 margin = _mm_set1_ps(along_margin_), distance = _mm_set1_ps(plane_distance_);
  const __m128 nz = _mm_set1_ps(nz_);
  const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
  for (int i = 0; i < n; ++i) {
    const Group& g = groups[i];
    // Only the rows within some column's bounds (a triangle thinner than the rows' spacing, as a
    // shelf's edge between two rings, holds none of them): the smallest lo and largest hi of the
    // group's columns, the others' lanes set to +inf and -inf (and a column with a NaN bound,
    // which no row's test passes).
    const __m128 keep = _mm_and_ps(laneMask(g.mask), _mm_cmpord_ps(g.lo, g.hi));
    __m128 lo = _mm_or_ps(_mm_and_ps(keep, g.lo), _mm_andnot_ps(keep, inf));
    __m128 hi =
        _mm_or_ps(_mm_and_ps(keep, g.hi), _mm_andnot_ps(keep, _mm_sub_ps(_mm_setzero_ps(), inf)));
    lo = _mm_min_ps(lo, _mm_shuffle_ps(lo, lo, _MM_SHUFFLE(2, 3, 0, 1)));
    lo = _mm_min_ps(lo, _mm_shuffle_ps(lo, lo, _MM_SHUFFLE(1, 0, 3, 2)));
    hi = _mm_max_ps(hi, _mm_shuffle_ps(hi, hi, _MM_SHUFFLE(2, 3, 0, 1)));
    hi = _mm_max_ps(hi, _mm_shuffle_ps(hi, hi, _MM_SHUFFLE(1, 0, 3, 2)));
    for (unsigned rows = rowsWithin(beams.grid(), rect, lo, hi); rows; rows &= rows - 1) {
      const int row = rect.row_lo + __builtin_ctz(rows);
      const __m128 tan_lo = _mm_set1_ps(beams.grid().rowTanBelow(row));
      const __m128 tan_hi = _mm_set1_ps(beams.grid().rowTanAbove(row));
      const __m128 cos_e = _mm_set1_ps(beams.grid().rowCos(row));
      const __m128 z = _mm_mul_ps(nz, _mm_set1_ps(beams.grid().rowSin(row)));
      const float* range = beams.rangeAbove(row);
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
