// The beams of one scan as the caster walks bodies and BVH nodes front to back: the nearest hit of
// each beam so far, the occlusion tiles over them, and the rectangle of beams a sphere or a box can
// reach (emitter-centric culling: every beam starts at the sensor, so what a box can be hit by is
// fixed by the directions it covers).
//
// Beams are addressed as (row, col): rows are the rings in ascending elevation, cols the azimuth
// indices. A hit is kept if it is nearer than the beam's current one, or as near from a lower body
// index, then a lower triangle index: the result never depends on the order bodies, nodes or beams
// are visited in (and so not on how beams are split between threads).
#pragma once

#include <Eigen/Geometry>
#include <atomic>
#include <cstdint>
#include <optional>
#include <variant>
#include <vector>

#include "laser_raycast/core/beam_window.h"
#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/node_views.h"
#include "laser_raycast/core/occlusion_tiles.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/triangle.h"
#include "laser_raycast/core/wide_bvh.h"

namespace laser_raycast {
namespace core {

class BeamSet {
 public:
  // Starts a scan: every beam open (result's ranges as resetResult left them).
  void reset(const ScanPattern& pattern, const CastConfig& config, ScanResult* result);

  const ScanPattern& pattern() const { return *pattern_; }
  int rows() const { return static_cast<int>(beam_of_row_.size()); }
  int cols() const { return pattern_->azimuthCount(); }
  BeamRect all() const { return BeamRect{0, rows() - 1, 0, cols() - 1}; }
  int beam(int row, int col) const { return beam_of_row_[row] * cols() + col; }
  const Eigen::Vector3d& direction(int row, int col) const {
    return pattern_->directions()[beam(row, col)];
  }
  double range(int row, int col) const { return result_->range[beam(row, col)]; }

  // Calls f(rect) for each piece of `within` that the view can reach (several pieces when its
  // azimuths wrap around the fan's ends). A planar pattern's one row is reached only by views
  // that cross the plane.
  template <class F>
  void forEachRect(const View& view, const BeamRect& within, F&& f) const;
  // The same for child k of a wide node's views.
  template <class F>
  void forEachChildRect(const NodeViews& views, int k, const BeamRect& within, F&& f) const;
  // How many beams of the whole pattern the view can reach.
  long long beamsReached(const View& view) const;

  // False only if every beam of rect has hit something nearer than `near` (small rects are read
  // beam by beam, larger ones through the occlusion tiles).
  bool anyOpen(const BeamRect& rect, double near);

  // The beams as rays from the sensor (sensor frame, origin 0) for the rasterising walk, prepared
  // for config's method, tmin and back-face culling when the pattern or these change.
  template <TriangleMethod M>
  const PreparedRay<double, M>& sensorRay(int row, int col) const {
    return std::get<std::vector<PreparedRay<double, M>>>(sensor_rays_)[beam(row, col)];
  }
  // The beams' directions in float, one row at a time, each row padded to a multiple of four
  // columns (x and y; z is the same for a whole row).
  const float* directionX(int row) const { return &direction_x_[row * padded_cols_]; }
  const float* directionY(int row) const { return &direction_y_[row * padded_cols_]; }
  float directionZ(int row) const { return direction_z_[row]; }

  // Each beam as a ray in the frame of the body being walked, for box tests, built once per (beam,
  // body walk). A walk takes a fresh stamp; the rays of other walks are rebuilt when asked for.
  std::uint32_t newWalkStamp() { return walk_stamp_.fetch_add(1) + 1; }
  template <class Make>
  const WideBoxRay& boxRay(int row, int col, std::uint32_t stamp, Make&& make);

  // Offers a hit (t, body, triangle) to the beam at (row, col); normal() gives its unit normal in
  // the sensor frame, asked only if the hit is kept and normals are wanted. True if kept.
  template <class Normal>
  bool offer(int row, int col, double t, int body, int triangle, Normal&& normal);

 private:
  void rowsReached(const View& view, int* lo, int* hi) const;

  const ScanPattern* pattern_ = nullptr;
  ScanResult* result_ = nullptr;
  bool planar_ = false;
  bool with_normals_ = false;
  bool occlusion_culling_ = true;
  void prepareSensorRays(const CastConfig& config);

  // What sensor_rays_ and the float directions were built for.
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
  std::variant<std::vector<PreparedRay<double, TriangleMethod::kSeedPlane>>,
               std::vector<PreparedRay<double, TriangleMethod::kSeedUv>>,
               std::vector<PreparedRay<double, TriangleMethod::kCramer>>,
               std::vector<PreparedRay<double, TriangleMethod::kMollerTrumbore>>,
               std::vector<PreparedRay<double, TriangleMethod::kWatertight>>>
      sensor_rays_;
  int padded_cols_ = 0;
  std::vector<float> direction_x_, direction_y_, direction_z_;

  std::vector<WideBoxRay> box_rays_;
  std::vector<std::uint32_t> ray_stamp_;      // the walk each cached ray was built for
  std::atomic<std::uint32_t> walk_stamp_{0};  // walks of several threads take stamps
  std::vector<int> beam_of_row_;              // the ring of each row
  std::vector<double> row_elevation_;         // ascending
  OcclusionTiles tiles_;
};

template <class F>
void BeamSet::forEachRect(const View& view, const BeamRect& within, F&& f) const {
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
void BeamSet::forEachChildRect(const NodeViews& views, int k, const BeamRect& within, F&& f) const {
  View view;
  view.near = views.near[k];
  view.crosses = true;  // NodeViews::mask already holds the plane test
  view.azimuth_limited = views.az_half[k] >= 0;
  if (view.azimuth_limited) {
    view.azimuth_start =
        wrapToTurn(double(views.az_center[k]) - views.az_half[k] - pattern_->angleMin());
    view.azimuth_width = 2.0 * views.az_half[k];
  }
  view.elevation_lo = planar_ ? -M_PI / 2 : views.el_lo[k];
  view.elevation_hi = planar_ ? M_PI / 2 : views.el_hi[k];
  forEachRect(view, within, f);
}

template <class Make>
const WideBoxRay& BeamSet::boxRay(int row, int col, std::uint32_t stamp, Make&& make) {
  const int i = beam(row, col);
  if (ray_stamp_[i] != stamp) {
    box_rays_[i] = make(direction(row, col));
    ray_stamp_[i] = stamp;
  }
  return box_rays_[i];
}

template <class Normal>
bool BeamSet::offer(int row, int col, double t, int body, int triangle, Normal&& normal) {
  const int i = beam(row, col);
  double& range = result_->range[i];
  int& hit_body = result_->body[i];
  int& hit_triangle = result_->triangle[i];
  const bool nearer =
      t < range ||
      (t == range && (body < hit_body || (body == hit_body && triangle < hit_triangle)));
  if (!nearer) return false;
  range = t;
  hit_body = body;
  hit_triangle = triangle;
  if (with_normals_) result_->normal[i] = normal();
  tiles_.touched(row, col);
  return true;
}

}  // namespace core
}  // namespace laser_raycast
