// A triangle mesh in its own (link-local) frame, with its BVH and bounds, built once and shared by
// every body that instances it.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include "laser_raycast/core/bvh.h"
#include "laser_raycast/core/surface.h"

namespace laser_raycast {
namespace core {

class WideBvh;

// A mesh's vertices, kept in float (12 bytes a vertex instead of 24) when every coordinate is
// exactly a float times its axis' scale (floatTimesScale: a mesh file's float coordinates, scaled
// as the URDF says); operator[] gives back the same doubles, bit for bit, either way.
class MeshVertices {
 public:
  MeshVertices() = default;
  explicit MeshVertices(std::vector<Eigen::Vector3d> vertices) : full_(std::move(vertices)) {}

  std::size_t size() const { return packed_.empty() ? full_.size() : packed_.size(); }
  bool empty() const { return size() == 0; }
  Eigen::Vector3d operator[](std::size_t i) const {
    if (packed_.empty()) return full_[i];
    const std::array<float, 3>& f = packed_[i];
    return {static_cast<double>(f[0]) * scale_[0], static_cast<double>(f[1]) * scale_[1],
            static_cast<double>(f[2]) * scale_[2]};
  }
  // Every vertex, in double.
  std::vector<Eigen::Vector3d> toVector() const;
  bool packed() const { return !packed_.empty(); }
  // Keeps the vertices in float if every coordinate is a float times scale (positive and finite
  // on each axis); returns whether they are.
  bool pack(const Eigen::Vector3d& scale);
  // Bytes the vertices take (what the vectors hold).
  std::size_t bytes() const {
    return full_.capacity() * sizeof(Eigen::Vector3d) + packed_.capacity() * sizeof(packed_[0]);
  }

 private:
  std::vector<Eigen::Vector3d> full_;
  std::vector<std::array<float, 3>> packed_;
  Eigen::Vector3d scale_ = Eigen::Vector3d::Ones();
};

class Mesh {
 public:
  // Throws std::invalid_argument naming the problem: no triangles, a non-finite vertex (with its
  // index and value), or a triangle index out of range. Degenerate triangles are kept in
  // triangles() but left out of the BVH; a mesh whose triangles are all degenerate is rejected.
  // float_scale: the per-axis scale the vertices were read with if they came from a file's float
  // coordinates (an STL's, scaled as the URDF says). When every vertex is exactly such a float
  // times it, the vertices and the BVH's slots are kept in float, half the bytes, giving back the
  // same doubles (MeshVertices::pack, SlotVertices::pack); otherwise, or for any other scale, in
  // double.
  Mesh(std::vector<Eigen::Vector3d> vertices, std::vector<TriangleIndices> triangles,
       const BvhConfig& bvh_config = {},
       const Eigen::Vector3d& float_scale = Eigen::Vector3d::Ones());
  // The wide BVH refers to the binary one: a Mesh stays where it was built (share it by pointer).
  Mesh(const Mesh&) = delete;
  Mesh& operator=(const Mesh&) = delete;
  ~Mesh();

  const MeshVertices& vertices() const { return vertices_; }
  const std::vector<TriangleIndices>& triangles() const { return triangles_; }
  // The triangles' BVH slots (triangleVertices, triangleIds) and bounds. Its binary tree is
  // released once the wide BVH is built from it (Bvh::releaseTree): walk the mesh's boxes with
  // visit().
  const Bvh& bvh() const { return bvh_; }
  // The caster's BVH: 4-wide, over the same triangle slots (src/core/accel/wide_bvh.h, private to
  // the core); a leaf holds the triangles of one connected component where the binary BVH allows.
  const WideBvh& wideBvh() const { return *wide_; }
  // Depth-first walk over the wide BVH's subtrees whose box (mesh frame, containing the exact box
  // of what is below) satisfies descend(box); calls leaf(slot) for each BVH slot of every such
  // leaf.
  void visit(const std::function<bool(const Aabb&)>& descend,
             const std::function<void(std::uint32_t)>& leaf) const;
  // The connected component of each triangle, numbered from 0 in order of first triangle
  // (triangles sharing a vertex index are in one), and how many there are. Not kept: components()
  // labels them anew at each call.
  std::vector<std::uint32_t> components() const;
  std::uint32_t componentCount() const { return component_count_; }
  // Closed surfaces, whose back faces a sensor outside them never sees first: for a BVH slot, +1 if
  // its triangle's component is closed and consistently wound with the front normals
  // ((b - a) x (c - a)) pointing out of the solid, -1 if pointing in, 0 if the component is open,
  // inconsistently wound, or encloses no volume. A component is closed when every edge between two
  // of its vertex indices is used by exactly two of its triangles, once in each direction.
  int slotFacing(std::uint32_t slot) const {
    return slot_closed_.empty() || slot_closed_[slot] == 0
               ? 0
               : closed_components_[slot_closed_[slot] - 1].facing;
  }
  bool hasClosedComponents() const { return !slot_closed_.empty(); }
  // For a slot whose slotFacing is not 0, the bounds of its triangle's component (the sensor must
  // be outside them).
  const Aabb& slotComponentBounds(std::uint32_t slot) const {
    return closed_components_[slot_closed_[slot] - 1].bounds;
  }
  const Aabb& bounds() const { return bounds_; }
  // A sphere containing every vertex that a triangle uses: centre of their bounds, radius to the
  // farthest of them.
  const Eigen::Vector3d& sphereCenter() const { return sphere_center_; }
  double sphereRadius() const { return sphere_radius_; }
  std::size_t degenerateTriangleCount() const {
    return triangles_.size() - bvh_.triangleIds().size();
  }
  // Colours, texture coordinates, vertex normals and materials (surface.h); null if none.
  const SurfaceAttributes* surface() const { return surface_.get(); }
  // Throws std::invalid_argument if surface does not fit this mesh (SurfaceAttributes::validate).
  // Set it before the mesh is shared.
  void setSurface(std::shared_ptr<const SurfaceAttributes> surface);
  // Bytes the mesh holds: vertices, triangles, closed components, its BVH's slots and nodes (not
  // the surface attributes, which may be shared).
  std::size_t bytes() const;
  // Geometric unit normal of a triangle, (b - a) x (c - a) normalised (the front face's side).
  Eigen::Vector3d normal(std::uint32_t triangle) const;

 private:
  void findClosedComponents(const std::vector<std::uint32_t>& component);

  MeshVertices vertices_;
  std::vector<TriangleIndices> triangles_;
  Aabb bounds_;
  Eigen::Vector3d sphere_center_;
  double sphere_radius_ = 0;
  // A closed component's bounds and facing (+1 or -1), and per BVH slot 1 + the index of its
  // triangle's closed component, or 0 if open; slot_closed_ is empty if none is closed (an open
  // mesh keeps no bytes per triangle for them).
  struct ClosedComponent {
    Aabb bounds;
    int facing;
  };
  std::uint32_t component_count_ = 0;
  std::vector<ClosedComponent> closed_components_;
  std::vector<std::uint32_t> slot_closed_;
  Bvh bvh_;
  std::unique_ptr<const WideBvh> wide_;  // refers to bvh_
  std::shared_ptr<const SurfaceAttributes> surface_;
};

// Whether the triangle in BVH slot `slot` is a back face of a closed component (slotFacing) as seen
// from a sensor at `eye` (mesh frame) outside the component's bounds and no nearer to them than
// tmin: a beam from there meets one of the component's front faces first, so it never reports this
// triangle. Only clear cases count: the triangle's plane must pass the eye by more than rounding.
inline bool hiddenBackFace(const Mesh& mesh, std::uint32_t slot, const Eigen::Vector3d& eye,
                           double tmin, double spread = 0) {
  const int facing = mesh.slotFacing(slot);
  if (!facing) return false;
  // In scalars throughout: Eigen's temporaries here went through the stack, and a wide load of
  // narrow stores cannot be forwarded (a sweep asks this of every slot in every block: one such
  // load held a sixth of its profile's samples).
  const Aabb& box = mesh.slotComponentBounds(slot);
  const double ex = eye.x(), ey = eye.y(), ez = eye.z();
  auto gap = [](double lo, double hi, double e) { return std::max(std::max(lo - e, e - hi), 0.0); };
  const double gx = gap(box.lo.x(), box.hi.x(), ex), gy = gap(box.lo.y(), box.hi.y(), ey),
               gz = gap(box.lo.z(), box.hi.z(), ez);
  const double gap2 = gx * gx + gy * gy + gz * gz;
  // Outside the bounds, and its front faces no nearer than tmin (written so that NaN fails); with
  // a spread, from every eye within that distance of `eye` (a rotating sweep's block): a gap above
  // spread + tmin, compared squared (a square root's wait was a tenth of this test's time). Each
  // side is widened by far more than its rounding.
  if (spread == 0) {
    if (!(gap2 > 0 && gap2 > tmin * tmin * (1 + 1e-9))) return false;
  } else {
    const double need = (spread + tmin) * (1 + 1e-9);
    if (!(gap2 > need * need * (1 + 1e-9))) return false;
  }
  const auto& v = mesh.bvh().triangleVertices()[slot];
  const double ax = v[0].x(), ay = v[0].y(), az = v[0].z();
  const double bx = v[1].x() - ax, by = v[1].y() - ay, bz = v[1].z() - az;  // b - a
  const double cx = v[2].x() - ax, cy = v[2].y() - ay, cz = v[2].z() - az;  // c - a
  const double fx = ax - ex, fy = ay - ey, fz = az - ez;                    // a - eye
  // The front normal's side of the eye: positive when it points away from it (from every eye of
  // the spread: an eye moved by d changes it by at most |n| |d|, compared squared as above).
  const double nx = by * cz - bz * cy, ny = bz * cx - bx * cz, nz = bx * cy - by * cx;
  const double side = nx * fx + ny * fy + nz * fz;
  const double tolerance = 1e-10 * (std::abs(bx) + std::abs(by) + std::abs(bz)) *
                           (std::abs(cx) + std::abs(cy) + std::abs(cz)) *
                           (std::abs(fx) + std::abs(fy) + std::abs(fz) + 3 * spread);
  const double clear = facing * side - tolerance;
  if (!(clear > 0)) return false;
  if (spread == 0) return true;
  const double moved = spread * (1 + 1e-9);
  return clear * clear > (nx * nx + ny * ny + nz * nz) * moved * moved * (1 + 1e-9);
}

}  // namespace core
}  // namespace laser_raycast
