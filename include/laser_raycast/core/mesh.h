// A triangle mesh in its own (link-local) frame, with its BVH and bounds, built once and shared by
// every body that instances it.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

#include "laser_raycast/core/bvh.h"
#include "laser_raycast/core/wide_bvh.h"

namespace laser_raycast {
namespace core {

class Mesh {
 public:
  // Throws std::invalid_argument naming the problem: no triangles, a non-finite vertex (with its
  // index and value), or a triangle index out of range. Degenerate triangles are kept in
  // triangles() but left out of the BVH; a mesh whose triangles are all degenerate is rejected.
  Mesh(std::vector<Eigen::Vector3d> vertices, std::vector<TriangleIndices> triangles,
       const BvhConfig& bvh_config = {});
  // The wide BVH refers to the binary one: a Mesh stays where it was built (share it by pointer).
  Mesh(const Mesh&) = delete;
  Mesh& operator=(const Mesh&) = delete;

  const std::vector<Eigen::Vector3d>& vertices() const { return vertices_; }
  const std::vector<TriangleIndices>& triangles() const { return triangles_; }
  const Bvh& bvh() const { return bvh_; }
  // The caster's BVH: 4-wide, over the same triangle slots; each connected component (triangles
  // joined by shared vertex indices) fills whole subtrees, and childGroup() names it.
  const WideBvh& wideBvh() const { return wide_; }
  // The connected component of each triangle, numbered from 0, and how many there are.
  const std::vector<std::uint32_t>& components() const { return component_; }
  std::uint32_t componentCount() const { return component_count_; }
  const Aabb& bounds() const { return bounds_; }
  // A sphere containing every vertex that a triangle uses: centre of their bounds, radius to the
  // farthest of them.
  const Eigen::Vector3d& sphereCenter() const { return sphere_center_; }
  double sphereRadius() const { return sphere_radius_; }
  std::size_t degenerateTriangleCount() const {
    return triangles_.size() - bvh_.triangleIds().size();
  }
  // Geometric unit normal of a triangle, (b - a) x (c - a) normalised (the front face's side).
  Eigen::Vector3d normal(std::uint32_t triangle) const;

 private:
  void labelComponents();

  std::vector<Eigen::Vector3d> vertices_;
  std::vector<TriangleIndices> triangles_;
  Aabb bounds_;
  Eigen::Vector3d sphere_center_;
  double sphere_radius_ = 0;
  std::vector<std::uint32_t> component_;
  std::uint32_t component_count_ = 0;
  Bvh bvh_;
  WideBvh wide_;
};

}  // namespace core
}  // namespace laser_raycast
