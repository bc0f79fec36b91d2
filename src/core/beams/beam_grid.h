// The beams of a scan pattern as a grid of rows and columns, with the tables the walks read: the
// beams' directions (as the pattern computes them, and in float, padded for four-wide reads), the
// rows' and columns' sines and cosines for the column raster, look-ups from elevations to rows, and
// the rectangles of beams a sphere or a box can reach (emitter-centric culling: every beam starts at
// the sensor, so what a box can be hit by is fixed by the directions it covers). It depends on the
// pattern and the cast's settings only, never on what the beams hit (that is BeamSet's).
//
// Beams are addressed as (row, col): rows are the rings in ascending elevation, cols the azimuth
// indices.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <vector>

#include "beams/beam_window.h"
#include "beams/node_views.h"
#include "beams/occlusion_tiles.h"
#include "laser_raycast/core/cast_config.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/triangle.h"
#include "util/float_rounding.h"

namespace laser_raycast {
namespace core {

// Sorted values (the rows' elevations, or their tangents) and the index range of those in an
// interval, through a table of bins and a short exact step.
class RowTable {
 public:
  void build(std::vector<double> values);
  // The first and last index whose value lies in [lo, hi] (last < first if none; NaN: none).
  void find(double lo, double hi, int* first, int* last) const {
    // The bin indices in float, one bin further out on each side than rounded (the table is exact
    // for its own bin ends: the float rounding moves an index by far less than a bin), then the
    // exact step: the table's answer is at most a value or two wide of it.
    const int n = static_cast<int>(values_.size());
    const float x_lo = clampBin((static_cast<float>(lo) - base_) * scale_);
    const float x_hi = clampBin((static_cast<float>(hi) - base_) * scale_);
    const int b_lo = static_cast<int>(x_lo + 1.0f) - 2;  // floor(x_lo) - 1 (x_lo >= -1)
    const int b_hi = static_cast<int>(x_hi + 1.0f);      // floor(x_hi) + 1
    int f = b_lo < 0 ? 0 : first_at_or_above_[b_lo];
    int l = b_hi > kBins ? n - 1 : last_at_or_below_[b_hi];
    while (f < n && values_[f] < lo) ++f;
    while (l >= 0 && values_[l] > hi) --l;
    *first = f;
    *last = lo <= hi ? l : -1;  // NaN or empty: none
  }

 private:
  static constexpr int kBins = 1024;  // fine enough that a bin rarely holds two boundaries
  // x clamped to [-1, kBins]; NaN to -1.
  static float clampBin(float x) {
    return x > -1.0f ? (x < float(kBins) ? x : float(kBins)) : -1.0f;
  }
  std::vector<double> values_;
  std::vector<int> first_at_or_above_, last_at_or_below_;  // of each bin's lower/upper end
  float base_ = 0, scale_ = 0;
};

// The rings of pattern in ascending elevation (ties in ring order), as ring indices, into order:
// the rows of its grid.
void ringsByElevation(const ScanPattern& pattern, std::vector<int>* order);

class BeamGrid {
 public:
  // Patterns whose rows all lie within this elevation (rad, 80 degrees) can be rasterised column
  // by column (ColumnRaster divides by cos E); steeper ones use the row scan of EdgeFilter.
  static constexpr double kMaxColumnRasterElevation = 1.3962634015954636;

  // Prepares the grid for a scan of pattern with config's tmin, triangle method and back-face
  // culling; the tables are rebuilt only when one of those changed. pattern must outlive the scan.
  void reset(const ScanPattern& pattern, const CastConfig& config);

  const ScanPattern& pattern() const { return *pattern_; }
  int rows() const { return static_cast<int>(beam_of_row_.size()); }
  int cols() const { return pattern_->azimuthCount(); }
  BeamRect all() const { return BeamRect{0, rows() - 1, 0, cols() - 1}; }
  int beam(int row, int col) const { return beam_of_row_[row] * cols() + col; }
  const Eigen::Vector3d& direction(int row, int col) const {
    return pattern_->directions()[beam(row, col)];
  }

  // Calls f(rect) for each piece of `within` that the view can reach (several pieces when its
  // azimuths wrap around the fan's ends). A planar pattern's one row is reached only by views
  // that cross the plane.
  template <class F>
  void forEachRect(const View& view, const BeamRect& within, F&& f) const;
  // The same for child k of a wide node's views.
  template <class F>
  void forEachChildRect(const NodeViews& views, int k, const BeamRect& within, F&& f) const;
  // Calls f(first, last) for the column ranges an azimuth window (centre, half width, rad) can
  // reach; the same ranges as forEachBeamRange or more, computed without wrapping angles for fans
  // of at most a turn.
  template <class F>
  void forEachColumnRange(double center, double half, F&& f) const;

  // A beam as a ray from the sensor (sensor frame, origin 0) for the triangle tests, prepared for
  // the cast's method, tmin and back-face culling. Prepared when asked for, from the direction
  // rebuilt from its row's and column's sines and cosines (the pattern's own expression, so the
  // same bits): cheaper than reading a stored one from a scan of many beams, out of the cache.
  template <TriangleMethod M>
  PreparedRay<double, M> sensorRay(int row, int col) const {
    Ray ray;
    ray.origin.setZero();
    ray.dir = rebuiltDirection(row, col);
    ray.tmin = tmin_;
    return PreparedRay<double, M>(ray, cull_backfaces_);
  }
  // direction(row, col), bit for bit, from small tables.
  Eigen::Vector3d rebuiltDirection(int row, int col) const {
    return Eigen::Vector3d(row_ce_[row] * column_cos_d_[col], row_ce_[row] * column_sin_d_[col],
                           row_se_[row]);
  }
  // The beams' directions in float, one row at a time, each row padded to a multiple of four
  // columns (x and y; z is the same for a whole row).
  const float* directionX(int row) const { return &direction_x_[row * padded_cols_]; }
  const float* directionY(int row) const { return &direction_y_[row * padded_cols_]; }
  float directionZ(int row) const { return direction_z_[row]; }
  // For ColumnRaster: whether the pattern allows it, the columns' cos and sin of the azimuth and
  // the rows' cos and sin of the elevation (float, columns padded to a multiple of four), the
  // smallest cos of an elevation, and the rows whose tan of the elevation lies in [lo, hi].
  bool columnRaster() const { return column_raster_; }
  const float* columnCos() const { return column_cos_.data(); }
  const float* columnSin() const { return column_sin_.data(); }
  float rowCos(int row) const { return row_cos_[row]; }
  float rowSin(int row) const { return row_sin_[row]; }
  float smallestRowCos() const { return smallest_row_cos_; }
  // A row's tan of the elevation rounded to float down and up.
  float rowTanBelow(int row) const { return row_tan_below_[row]; }
  float rowTanAbove(int row) const { return row_tan_above_[row]; }
  // The same from row on, readable kRowBlock values on from any row (those past the last row are
  // NaN).
  static constexpr int kRowBlock = 16;
  const float* rowTansBelow(int row) const { return row_tan_below_.data() + row; }
  const float* rowTansAbove(int row) const { return row_tan_above_.data() + row; }
  void rowsWithTan(double lo, double hi, int* row_lo, int* row_hi) const {
    row_tan_.find(lo, hi, row_lo, row_hi);
  }

 private:
  void rowsReached(const View& view, int* lo, int* hi) const {
    rowsOf(view.elevation_lo, view.elevation_hi, lo, hi);
    if (planar_ && !view.crosses) *lo = 1;  // the one row lies in the plane the view misses
  }
  // The rows whose elevation lies in [lo, hi].
  void rowsOf(double lo, double hi, int* row_lo, int* row_hi) const {
    if (planar_) {
      *row_lo = *row_hi = 0;
    } else {
      row_elevation_.find(lo, hi, row_lo, row_hi);
    }
  }
  void prepareRows();

  const ScanPattern* pattern_ = nullptr;
  bool planar_ = false;
  void prepareSensorRays(const CastConfig& config);

  // What the directions' tables were built for.
  struct PreparedKey {
    double angle_min = 0, angle_increment = 0;
    int azimuths = 0;
    std::vector<double> elevations;
    double tmin = -1;
    bool cull_backfaces = false;
    TriangleMethod method = TriangleMethod::kWatertight;
    bool operator==(const PreparedKey& o) const {
      return angle_min == o.angle_min && angle_increment == o.angle_increment &&
             azimuths == o.azimuths && elevations == o.elevations && tmin == o.tmin &&
             cull_backfaces == o.cull_backfaces && method == o.method;
    }
  };
  std::optional<PreparedKey> prepared_key_;
  // Each row's cos and sin of its elevation, each column's of its azimuth: the directions' factors.
  std::vector<double> row_ce_, row_se_, column_cos_d_, column_sin_d_;
  double tmin_ = 0;
  bool cull_backfaces_ = false;
  int padded_cols_ = 0;
  std::vector<float> direction_x_, direction_y_, direction_z_;

  std::vector<int> beam_of_row_;      // the ring of each row
  RowTable row_elevation_, row_tan_;  // of the rows, ascending
  bool column_raster_ = false;
  std::vector<float> column_cos_, column_sin_, row_cos_, row_sin_, row_tan_below_, row_tan_above_;
  float smallest_row_cos_ = 1;
  // Columns: the fan's start, increment and the index pad for rounding; one_turn_: the fan spans
  // at most a turn, so forEachColumnRange needs at most the turns before and after.
  double col_start_ = 0, col_inv_increment_ = 0, col_turn_ = 0, col_pad_ = 0;
  bool one_turn_ = false;
};


template <class F>
void BeamGrid::forEachColumnRange(double center, double half, F&& f) const {
  if (!one_turn_) {
    forEachBeamRange(*pattern_, wrapToTurn(center - half - col_start_), 2 * half, f);
    return;
  }
  // In units of columns from the first beam; the window is [s, s + w], s reduced into [0, turn).
  double s = (center - half - col_start_) * col_inv_increment_;
  const double w = 2 * half * col_inv_increment_;
  s -= col_turn_ * floorToInt(s / col_turn_);
  const int last_col = cols() - 1;
  // The turn before (a window starting just below a whole turn, reduced to just above 0).
  if (s <= col_pad_) {
    const int before = std::max(0, ceilToInt(s - col_pad_ + col_turn_));
    if (before <= last_col) f(before, last_col);
  }
  const int first = std::max(0, ceilToInt(s - col_pad_));
  const int last = std::min(last_col, floorToInt(std::min(s + w + col_pad_, col_turn_ + cols())));
  if (first <= last) f(first, last);
  // The turn after (a window past the fan's end that wraps to its start).
  if (s + w + col_pad_ >= col_turn_) {
    const int wrapped = std::min(last_col, floorToInt(s + w + col_pad_ - col_turn_));
    if (wrapped >= 0) f(0, wrapped);
  }
}

template <class F>
void BeamGrid::forEachRect(const View& view, const BeamRect& within, F&& f) const {
  int row_lo, row_hi;
  rowsReached(view, &row_lo, &row_hi);
  row_lo = std::max(row_lo, within.row_lo);
  row_hi = std::min(row_hi, within.row_hi);
  if (row_lo > row_hi) return;
  if (!view.azimuth_limited) {
    f(BeamRect{row_lo, row_hi, within.col_lo, within.col_hi});
    return;
  }
  forEachBeamRange(*pattern_, view.azimuth_start, view.azimuth_width, [&](int first, int last) {
    const BeamRect rect{row_lo, row_hi, std::max(first, within.col_lo),
                        std::min(last, within.col_hi)};
    if (!rect.empty()) f(rect);
  });
}

template <class F>
void BeamGrid::forEachChildRect(const NodeViews& views, int k, const BeamRect& within, F&& f) const {
  int row_lo = 0, row_hi = 0;
  if (!planar_) rowsOf(views.el_lo[k], views.el_hi[k], &row_lo, &row_hi);
  row_lo = std::max(row_lo, within.row_lo);
  row_hi = std::min(row_hi, within.row_hi);
  if (row_lo > row_hi) return;
  if (!(views.az_half[k] >= 0)) {
    f(BeamRect{row_lo, row_hi, within.col_lo, within.col_hi});
    return;
  }
  forEachColumnRange(views.az_center[k], views.az_half[k], [&](int first, int last) {
    const BeamRect rect{row_lo, row_hi, std::max(first, within.col_lo),
                        std::min(last, within.col_hi)};
    if (!rect.empty()) f(rect);
  });
}

}  // namespace core
}  // namespace laser_raycast
