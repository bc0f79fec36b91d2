// The beams of one scan as the caster walks bodies and BVH nodes front to back: the nearest hit of
// each beam so far, written into the cast's ScanResult, and the occlusion tiles over them, on the
// pattern's BeamGrid (beam_grid.h: directions, raster tables, the rects a view reaches).
//
// A beam keeps the hit that goes first by the order of hit_order.h (keepNearestHit): the result
// never depends on the order bodies, nodes or beams are visited in (and so not on how beams are
// split between threads).
#pragma once

#include <algorithm>
#include <memory>
#include <utility>
#include <vector>

#include "beams/beam_grid.h"
#include "beams/occlusion_tiles.h"
#include "geometry/hit_order.h"
#include "laser_raycast/core/cast_config.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/scan_result.h"
#include "laser_raycast/core/triangle.h"
#include "util/float_rounding.h"

namespace laser_raycast {
namespace core {

class BeamSet {
 public:
  // A bundle: each beam of the grid stands for sub-rays of its own in `directions`, each kept in
  // `result` at the same index: per_beam of them a beam, beam by beam (sub-ray k of beam i at
  // i * per_beam + k: a divergent beam's, a SubRayBundle's, Caster::castBundle, which with
  // from_origin leave from the sensor's origin itself; or one, a calibrated lidar's own beam,
  // Caster::castBeams). The sub-rays leave from the sensor, or with a ColumnMotion from their
  // column's origin as the grid's beams do. The grid's own ranges then hold the farthest of a
  // beam's sub-ray ranges, which is what culling reads, and the walks test each sub-ray where
  // they would test the beam.
  // With `first`, each grid beam stands for a list of its own instead (a cell of an angular grid
  // over beams off any grid, beams/beam_cells.h): sub-rays first[i] to first[i + 1] - 1; a grid
  // beam with none is never open.
  struct Bundle {
    const std::vector<Eigen::Vector3d>* directions = nullptr;  // by sub-ray
    ScanResult* result = nullptr;                             // by sub-ray
    int per_beam = 1;
    const std::vector<int>* first = nullptr;  // by grid beam, one more at the end
    // Every sub-ray leaves from the reference origin along its own direction, unturned (a cast
    // from one pose): the walks pre-test them against each triangle (walk/sub_ray_filter.h), four
    // at a time from their directions in float, which reset() then keeps.
    bool from_origin = false;
    // What keeps `directions` alive and unchanged, or null: while reset() is passed the same owner,
    // what it made of them (their float copy, the sub-rays' shears) is kept rather than made again.
    // The BeamSet holds the last owner it was passed until it is passed another.
    std::shared_ptr<const void> owner;
  };
  // Directions in float, one array per axis, indexed by sub-ray, with three zeros at the end.
  struct FloatDirections {
    std::vector<float> x, y, z;
  };

  // Starts a scan: every beam open (result's ranges as resetResult left them, and a bundle's
  // result's), the grid prepared for pattern and config. The walks write a bundle's sub-ray hits
  // into its result in place.
  void reset(const ScanPattern& pattern, const CastConfig& config, ScanResult* result,
             const Bundle* bundle = nullptr);

  const BeamGrid& grid() const { return grid_; }
  double range(int row, int col) const { return result_->range[grid_.beam(row, col)]; }

  // False only if every beam of rect has hit something nearer than `near` (small rects are read
  // beam by beam, larger ones through the occlusion tiles).
  bool anyOpen(const BeamRect& rect, float near) {
    return occlusion_culling_ ? tiles_.anyOpen(rect, near) : !rect.empty();
  }
  // The same for a double distance (rounded down: a beam counts as closed only if it certainly
  // is).
  bool anyOpen(const BeamRect& rect, double near) { return anyOpen(rect, floatBelow(near)); }

  // The farthest hit each beam can still keep (its current range, or tmax) rounded up to float,
  // one row at a time, padded like the grid's float directions.
  const float* rangeAbove(int row) const { return tiles_.row(row); }

  // Where a beam's range is decided, the one place that writes it: the hit (t, body, triangle) is
  // kept for the beam at (row, col) if it goes before the beam's current one by the order of
  // hit_order.h (nearer, or as near on a lower body, then a lower triangle); normal() gives its
  // unit normal in the sensor frame, asked only if the hit is kept and normals are wanted. True if
  // kept.
  template <class Normal>
  bool keepNearestHit(int row, int col, double t, int body, int triangle, Normal&& normal);

  // The bundle being cast, or null.
  const Bundle* bundle() const { return bundle_; }
  // The sub-rays of the beam at (row, col) are s = subBegin(...) to subEnd(...) - 1.
  int subBegin(int row, int col) const { return firstSub(grid_.beam(row, col)); }
  int subEnd(int row, int col) const { return firstSub(grid_.beam(row, col) + 1); }
  // Sub-ray s: its direction (sensor frame) and its range so far.
  const Eigen::Vector3d& subDirection(int s) const { return sub_direction_[s]; }
  double subRange(int s) const { return sub_range_[s]; }
  // Each sub-ray's shear for the watertight test (PreparedRay::shearOf its direction), made once
  // for the bundle's owner: for a bundle from_origin (from the sensor's origin itself: a
  // SubRayBundle's, a calibrated Velodyne's parts, a beam list's cells) with an owner, cast with
  // the watertight test; else null.
  using SubShear = PreparedRay<double, TriangleMethod::kWatertight>::Shear;
  const SubShear* subShears() const { return use_shears_ ? sub_shears_.data() : nullptr; }
  // The sub-rays' directions in float for a bundle cast from_origin, else null.
  const FloatDirections* subDirectionsFloat() const {
    return bundle_ && bundle_->from_origin ? &sub_direction_float_ : nullptr;
  }
  // keepNearestHit for sub-ray s of the beam at (row, col), by the same order; the beam's culling
  // range follows the farthest of its sub-rays'.
  template <class Normal>
  bool keepNearestSubHit(int s, int row, int col, double t, int body, int triangle,
                         Normal&& normal);
  // The same in two steps, for a walk that tests several of a beam's sub-rays against one
  // triangle: each sub-ray's hit (keepSubHit), then once for the beam (settleSubHits) its
  // culling range. The same ranges as keepNearestSubHit for each.
  template <class Normal>
  bool keepSubHit(int s, double t, int body, int triangle, Normal&& normal);
  void settleSubHits(int row, int col);

 private:
  int firstSub(int beam) const { return first_ ? (*first_)[beam] : beam * sub_rays_; }

  BeamGrid grid_;
  const Bundle* bundle_ = nullptr;
  // The sub-rays while a bundle is cast (its arrays): a fixed number a beam (sub_rays_) kept beam
  // by beam (sub-ray k of beam i at i * sub_rays_ + k), so that a beam's sub-rays share cache
  // lines, or a bundle's own lists (first_).
  const std::vector<int>* first_ = nullptr;
  int sub_rays_ = 0;
  const Eigen::Vector3d* sub_direction_ = nullptr;
  double* sub_range_ = nullptr;
  int *sub_body_ = nullptr, *sub_triangle_ = nullptr;
  Eigen::Vector3d* sub_normal_ = nullptr;
  FloatDirections sub_direction_float_;
  std::shared_ptr<const void> float_owner_;  // the owner sub_direction_float_ was made for
  std::vector<SubShear> sub_shears_;
  std::shared_ptr<const void> shear_owner_;  // the owner sub_shears_ was made for
  bool use_shears_ = false;
  ScanResult* result_ = nullptr;
  bool with_normals_ = false;
  bool occlusion_culling_ = true;
  OcclusionTiles tiles_;
};

template <class Normal>
bool BeamSet::keepNearestHit(int row, int col, double t, int body, int triangle, Normal&& normal) {
  const int i = grid_.beam(row, col);
  double& range = result_->range[i];
  int& hit_body = result_->body[i];
  int& hit_triangle = result_->triangle[i];
  if (!hitBefore(t, body, triangle, range, hit_body, hit_triangle)) return false;
  range = t;
  hit_body = body;
  hit_triangle = triangle;
  if (with_normals_) result_->normal[i] = normal();
  tiles_.lower(row, col, floatAbove(t));
  return true;
}

template <class Normal>
bool BeamSet::keepNearestSubHit(int s, int row, int col, double t, int body, int triangle,
                                Normal&& normal) {
  if (!keepSubHit(s, t, body, triangle, std::forward<Normal>(normal))) return false;
  settleSubHits(row, col);
  return true;
}

template <class Normal>
bool BeamSet::keepSubHit(int s, double t, int body, int triangle, Normal&& normal) {
  if (!hitBefore(t, body, triangle, sub_range_[s], sub_body_[s], sub_triangle_[s])) return false;
  sub_range_[s] = t;
  sub_body_[s] = body;
  sub_triangle_[s] = triangle;
  if (with_normals_) sub_normal_[s] = normal();
  return true;
}

__attribute__((always_inline)) inline void BeamSet::settleSubHits(int row, int col) {
  const int i = grid_.beam(row, col);
  double farthest = 0;
  for (int j = firstSub(i), end = firstSub(i + 1); j < end; ++j) {
    farthest = std::max(farthest, sub_range_[j]);
  }
  if (farthest < result_->range[i]) {
    result_->range[i] = farthest;
    tiles_.lower(row, col, floatAbove(farthest));
  }
}

}  // namespace core
}  // namespace laser_raycast
