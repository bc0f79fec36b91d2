// How a scan is cast: the triangle test, the search interval, the fast paths and threads. The
// caster and every walk read it; ScanSpec (scan_spec.h) derives it from a sensor's description.
#pragma once

#include "laser_raycast/core/triangle.h"

namespace laser_raycast {
namespace core {

struct CastConfig {
  TriangleMethod method = TriangleMethod::kWatertight;  // triangle test for meshes
  bool cull_backfaces = false;  // one-sided triangles: a beam reaching a back face passes through
  double tmin = 0.0;            // m, nearest accepted hit (>= 0)
  double tmax = 30.0;  // m, farthest accepted hit (> tmin); bodies wholly beyond are skipped
  bool planar_fast_path =
      true;  // planar fans: slice meshes in the scan plane instead of tracing beams
  bool raster_fast_path = true;  // other patterns: rasterise nearby meshes instead of tracing beams
  bool compute_incidence = false;  // fill ScanResult::cos_incidence
  // Threads a cast uses (the calling one included); 0: every core. The beams are split between
  // them; the result is the same, bit for bit, for any number.
  int threads = 1;
  static constexpr int kMaxThreads = 1024;  // more is a mistake, not a machine
  // Skip bodies and BVH nodes that every beam able to reach them has already passed (a nearer
  // hit). Never changes the result; off only to test that.
  bool occlusion_culling = true;
  // Planar fans: keep each mesh's slice by a scan plane met again (a sensor moving in its own
  // plane, as on a floor) and cast later scans through it (kept_slice.h). Never changes the
  // result; off to measure a cast whose plane is new every scan, or to test that.
  bool keep_slices = true;

  // Throws std::invalid_argument naming the field and its value.
  void validate() const;
  bool operator==(const CastConfig& o) const;
};

}  // namespace core
}  // namespace laser_raycast
