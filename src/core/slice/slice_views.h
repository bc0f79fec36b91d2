// How the four children of a node of a kept slice's tree (kept_slice.h) look from the sensor under
// a planar fan, computed together in float with SSE2: each child's nearest distance and the fan's
// columns its box can be seen in. The boxes are 2D, in the plane's coordinates; the map to the
// sensor's x, y is ScanPlane's. Everything is conservative, as NodeViews is: every rounding widens
// a window and lowers a distance, so a beam whose exact ray enters a child's box is always among
// the child's columns. Only the amount of work depends on them.
#pragma once

#include <emmintrin.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <limits>

#include "beams/beam_window.h"
#include "beams/node_views.h"
#include "slice/slicer.h"
#include "laser_raycast/core/scan_pattern.h"
#include "accel/wide_bvh.h"

namespace laser_raycast {
namespace core {

// The plane's map and the fan's columns, prepared for SliceViews.
class SliceViewBasis {
 public:
  // spread: a sweep block's beams leave from poses near the reference one (beam_window.h); their
  // planes are the reference's (the caster walks a kept slice with a block only then).
  SliceViewBasis(const ScanPlane& plane, double tmax, const ScanPattern& fan,
                 const Spread& spread = Spread());

 private:
  friend struct SliceViews;
  __m128 a_, b_, c_, d_, abs_a_, abs_b_, abs_c_, abs_d_, tx_, ty_, abs_tx_, abs_ty_, tmax_;
  // Columns: index = (angle - start) * inv_increment, a turn is `turn` columns; pad covers the
  // float rounding of that arithmetic. fast_: the fan spans at most a turn.
  __m128 start_, inv_increment_, turn_, inv_turn_, pad_;
  int columns_;
  bool fast_;
  SpreadPs spread_;
};

struct SliceViews {
  int mask;                   // bit k: child k exists and may be nearer than tmax
  int columns_known;          // bit k: col_lo/col_hi hold child k's columns
  alignas(16) float near[4];  // no point of the child's box is nearer to the sensor
  alignas(16) int col_lo[4];  // the child's columns, where known (may be empty: lo > hi)
  alignas(16) int col_hi[4];
  // Otherwise (a window that wraps around the fan's ends): its bearing window (rad), for
  // BeamGrid::forEachColumnRange; az_half < 0: every column.
  alignas(16) float az_center[4];
  alignas(16) float az_half[4];

  void compute(const WideBvh::Node& node, const SliceViewBasis& basis);

 private:
  // compute's last step: the columns of the children whose bearing window neither starts before
  // the fan nor ends after a turn.
  void storeColumns(const SliceViewBasis& f, __m128 center, __m128 half, __m128 narrow);
};

// A beam in plane coordinates, prepared for conservative box tests against a slice tree's nodes,
// four children at a time, in x and y only (the boxes' heights are not the walk's), with the origin
// rounded once each way and shared by every beam of a walk.
class PlaneRay : public WideSlabRay<2> {
 public:
  // Origin: plane coordinates, moved by frameSlack() each way, since the segments are tested
  // mapped to the sensor's x, y.
  using WideSlabRay<2>::WideSlabRay;
};

}  // namespace core
}  // namespace laser_raycast
