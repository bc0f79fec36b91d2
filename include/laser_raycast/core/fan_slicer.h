// The planar fast path: a 2D fan needs only the triangles that cross its plane. Each crossing
// triangle is cut into a segment in the scan plane and written into a 1D angular depth buffer, so
// the cost grows with the number of crossing triangles and beams, not with rays times tree depth.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "laser_raycast/core/mesh.h"
#include "laser_raycast/core/scan_pattern.h"

namespace laser_raycast {
namespace core {

// The per-beam nearest hit so far: distance, body and triangle.
struct DepthBuffer {
  std::vector<double>* range;
  std::vector<int>* body;
  std::vector<int>* triangle;
  // If set, every segment a beam crosses within [tmin, tmax] is counted, nearest or not: a closed
  // mesh's outline is crossed exactly once per beam from inside (the watertightness tests use it).
  std::vector<int>* crossings = nullptr;
};

// Beam index ranges of a fan that may see the angular interval [start, start + width] (rad, start
// measured from angle_min, width in [0, pi]). Padded by one beam each side: the exact side test
// decides. Calls f(first, last) for each index range (more than one when the fan spans more than a
// turn); the ranges are increasing and disjoint, so no beam is visited twice even when the padding
// of a coarse fan makes consecutive turns' windows overlap.
template <class F>
void forEachBeamRange(const ScanPattern& fan, double start, double width, F&& f) {
  const double inc = fan.angleIncrement();
  const int n = fan.azimuthCount();
  const double span = (n - 1) * inc;
  int next = 0;  // the first beam not yet visited
  for (int turn = -1;; ++turn) {
    const double lo = start + turn * 2 * M_PI;
    const double hi = lo + width;
    if (lo > span + inc) break;
    if (hi < -inc) continue;
    const int first = std::max(next, static_cast<int>(std::ceil(lo / inc)) - 1);
    const int last = std::min(n - 1, static_cast<int>(std::floor(hi / inc)) + 1);
    if (first <= last) {
      f(first, last);
      next = last + 1;
    }
  }
}

// Slices one mesh body by the fan's plane (the sensor's z = 0) and keeps, per beam, the nearest hit
// with t in [tmin, tmax]. Watertight: each crossing point is computed from its edge's two vertices
// in a fixed (lexicographic) order, so neighbouring triangles share bitwise-identical segment
// endpoints, and a beam is tested against a segment by the signs of two cross products with those
// endpoints. A beam exactly through a shared endpoint counts for one of the two segments (half-open
// segments), and a vertex exactly on the plane counts as just below it, so that an edge lying in
// the plane is cut once: a beam crosses a closed outline exactly once. A surface that only touches
// the plane from below (the top of a box at exactly the sensor's height) is therefore not seen;
// triangles lying in the plane are skipped, as the 3D tests skip a ray in a triangle's plane.
void sliceMesh(const Mesh& mesh, const Eigen::Isometry3d& sensor_from_mesh, const ScanPattern& fan,
               double tmin, double tmax, bool cull_backfaces, int body_index, DepthBuffer buffer);

}  // namespace core
}  // namespace laser_raycast
