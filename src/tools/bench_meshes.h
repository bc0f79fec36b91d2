// Procedural meshes for the benchmark's generated scenes, in their own (local) frame, and the long
// double pose type that places them. Vertices are double: these are the "stored triangles" that
// every method, and the reference, is given.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <vector>

#include "laser_raycast/core/bvh.h"
#include "laser_raycast/core/mesh.h"

namespace laser_raycast {
namespace bench {

using Real = long double;
using Vec3L = Eigen::Matrix<Real, 3, 1>;
using Mat3L = Eigen::Matrix<Real, 3, 3>;

// A rigid pose in long double: world = rot * local + trans.
struct PoseL {
  Mat3L rot = Mat3L::Identity();
  Vec3L trans = Vec3L::Zero();

  Vec3L apply(const Vec3L& p) const { return rot * p + trans; }
  PoseL operator*(const PoseL& o) const { return PoseL{rot * o.rot, rot * o.trans + trans}; }
};

// The pose x, y, z, roll, pitch, yaw (URDF: Rz(yaw) Ry(pitch) Rx(roll)), computed in long double
// from the double parameters: the unrounded pose the reference uses.
PoseL poseFromParams(double x, double y, double z, double roll, double pitch, double yaw);
// The pose rounded once to double: what the pipeline is given.
Eigen::Isometry3d toIsometry(const PoseL& pose);
// A double pose, exactly.
PoseL fromIsometry(const Eigen::Isometry3d& pose);

// An indexed triangle mesh.
struct MeshData {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<core::TriangleIndices> triangles;

  // Appends other's triangles (other's vertices follow ours).
  void append(const MeshData& other);
  // Adds quad (a, b, c, d), counter-clockwise seen from its front, as two triangles.
  void quad(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d);
};

// The mesh as a mesh file would give it to the loader: every coordinate rounded to float (an STL's
// or a Collada file's), so that it is built as the node builds such a file.
std::shared_ptr<const core::Mesh> meshAsRead(const MeshData& mesh);

// The side of a cylinder (axis z, centred on it): a ring of `segments` vertices at each height in
// ring_z (ascending), joined by quads facing outwards; with caps, a centre vertex closes each end.
MeshData cylinderMesh(double radius, const std::vector<double>& ring_z, int segments, bool caps);
// The same with the radius going linearly from bottom_radius at ring_z.front() to top_radius at
// ring_z.back() (a tapered trunk). Equal radii give cylinderMesh's vertices exactly.
MeshData taperedCylinderMesh(double bottom_radius, double top_radius,
                             const std::vector<double>& ring_z, int segments, bool caps);

// A latitude-longitude sphere centred at the origin: `segments` vertices per ring, `stacks` bands
// from pole to pole (triangle fans at the poles, so no degenerate triangles).
MeshData uvSphereMesh(double radius, int segments, int stacks);

// A box centred at the origin with edge lengths size: 8 vertices, 12 triangles facing outwards.
MeshData boxMesh(const Eigen::Vector3d& size);
// The same box moved to pose (its vertices transformed and rounded once, in double).
MeshData boxMesh(const Eigen::Vector3d& size, const Eigen::Isometry3d& pose);

// A height field over [x0, x1] x [y0, y1] with nx x ny cells, z = height(x, y).
template <class Height>
MeshData heightFieldMesh(double x0, double x1, double y0, double y1, int nx, int ny,
                         Height&& height) {
  MeshData m;
  for (int j = 0; j <= ny; ++j) {
    for (int i = 0; i <= nx; ++i) {
      const double x = x0 + (x1 - x0) * i / nx;
      const double y = y0 + (y1 - y0) * j / ny;
      m.vertices.emplace_back(x, y, height(x, y));
    }
  }
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const auto v = static_cast<std::uint32_t>(j * (nx + 1) + i);
      m.quad(v, v + 1, v + 1 + (nx + 1), v + (nx + 1));
    }
  }
  return m;
}

// A closed band of wall around a convex polygon (corners counter-clockwise in the xy plane): each
// side split into `columns` columns, with a row of vertices at each height in row_z (ascending).
// Neighbouring sides share their corner columns, so the band has no cracks.
MeshData wallBandMesh(const std::vector<Eigen::Vector2d>& corners, int columns,
                      const std::vector<double>& row_z);

}  // namespace bench
}  // namespace laser_raycast
