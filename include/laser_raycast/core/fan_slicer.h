// The planar fast path: a 2D fan needs only the triangles that cross its plane. Each crossing
// triangle is cut into a segment in the scan plane and written into a 1D angular depth buffer, so
// the cost grows with the number of crossing triangles and beams, not with rays times tree depth.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "laser_raycast/core/beam_window.h"
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
  // If set, the hit triangle's front normal (sensor frame) is written with every nearer hit.
  std::vector<Eigen::Vector3d>* normal = nullptr;
};

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
