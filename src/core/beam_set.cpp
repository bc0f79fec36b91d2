#include "laser_raycast/core/beam_set.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace laser_raycast {
namespace core {
void BeamSet::reset(const ScanPattern& pattern, const CastConfig& config, ScanResult* result) {
  pattern_ = &pattern;
  result_ = result;
  planar_ = pattern.planar();
  with_normals_ = !result->normal.empty();
  occlusion_culling_ = config.occlusion_culling;
  const auto& elevations = pattern.elevations();
  beam_of_row_.resize(elevations.size());
  std::iota(beam_of_row_.begin(), beam_of_row_.end(), 0);
  std::stable_sort(beam_of_row_.begin(), beam_of_row_.end(),
                   [&](int a, int b) { return elevations[a] < elevations[b]; });
  row_elevation_.clear();
  for (const int ring : beam_of_row_) row_elevation_.push_back(elevations[ring]);
  tiles_.reset(&result->range, &beam_of_row_, rows(), cols());
  const std::size_t beams = pattern.directions().size();
  box_rays_.resize(beams);
  if (ray_stamp_.size() != beams) ray_stamp_.assign(beams, 0);
  prepareSensorRays(config);
}

void BeamSet::prepareSensorRays(const CastConfig& config) {
  PreparedKey key;
  key.angle_min = pattern_->angleMin();
  key.angle_increment = pattern_->angleIncrement();
  key.azimuths = pattern_->azimuthCount();
  key.elevations = pattern_->elevations();
  key.tmin = config.tmin;
  key.cull_backfaces = config.cull_backfaces;
  key.method = config.method;
  if (prepared_key_ && *prepared_key_ == key) return;
  prepared_key_ = key;
  const auto& dirs = pattern_->directions();
  dispatchTriangleMethod(config.method, [&](auto method) {
    constexpr TriangleMethod M = decltype(method)::value;
    std::vector<PreparedRay<double, M>> rays;
    rays.reserve(dirs.size());
    for (const Eigen::Vector3d& d : dirs) {
      Ray ray;
      ray.origin = Eigen::Vector3d::Zero();
      ray.dir = d;
      ray.tmin = config.tmin;
      rays.emplace_back(ray, config.cull_backfaces);
    }
    sensor_rays_ = std::move(rays);
  });
  padded_cols_ = (cols() + 3) / 4 * 4;
  direction_x_.assign(static_cast<std::size_t>(rows()) * padded_cols_, 0.0f);
  direction_y_.assign(direction_x_.size(), 0.0f);
  direction_z_.assign(rows(), 0.0f);
  for (int row = 0; row < rows(); ++row) {
    direction_z_[row] = static_cast<float>(direction(row, 0).z());
    for (int col = 0; col < cols(); ++col) {
      direction_x_[row * padded_cols_ + col] = static_cast<float>(direction(row, col).x());
      direction_y_[row * padded_cols_ + col] = static_cast<float>(direction(row, col).y());
    }
  }
}

bool BeamSet::anyOpen(const BeamRect& rect, double near) {
  if (!occlusion_culling_) return !rect.empty();
  // Reading up to this many beams directly is about as cheap as the tiles, and exact.
  constexpr long long kDirect = 32;
  if (rect.beams() > kDirect) return tiles_.anyOpen(rect, near);
  for (int row = rect.row_lo; row <= rect.row_hi; ++row) {
    for (int col = rect.col_lo; col <= rect.col_hi; ++col) {
      if (!(range(row, col) < near)) return true;
    }
  }
  return false;
}

void BeamSet::rowsReached(const View& view, int* lo, int* hi) const {
  if (planar_) {
    *lo = view.crosses ? 0 : 1;
    *hi = 0;
    return;
  }
  *lo = static_cast<int>(
      std::lower_bound(row_elevation_.begin(), row_elevation_.end(), view.elevation_lo) -
      row_elevation_.begin());
  *hi = static_cast<int>(
            std::upper_bound(row_elevation_.begin(), row_elevation_.end(), view.elevation_hi) -
            row_elevation_.begin()) -
        1;
}

long long BeamSet::beamsReached(const View& view) const {
  long long n = 0;
  forEachRect(view, all(), [&](const BeamRect& rect) { n += rect.beams(); });
  return n;
}

}  // namespace core
}  // namespace laser_raycast
