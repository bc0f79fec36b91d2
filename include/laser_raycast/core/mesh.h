// A triangle mesh in its own (link-local) frame, with its BVH and bounds, built once and shared by
// every body that instances it.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <vector>

#include "laser_raycast/core/bvh.h"

namespace laser_raycast {
namespace core {

class Mesh {
 public:
  // Throws std::invalid_argument naming the problem: no triangles, a non-finite vertex (with its
  // index and value), or a triangle index out of range. Degenerate triangles are kept in
  // triangles() but left out of the BVH; a mesh whose triangles are all degenerate is rejected.
  Mesh(std::vector<Eigen::Vector3d> vertices, std::vector<TriangleIndices> triangles,
       const BvhConfig& bvh_config = {});

  const std::vector<Eigen::Vector3d>& vertices() const { return vertices_; }
  const std::vector<TriangleIndices>& triangles() const { return triangles_; }
  const Bvh& bvh() const { return bvh_; }
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
  std::vector<Eigen::Vector3d> vertices_;
  std::vector<TriangleIndices> triangles_;
  Aabb bounds_;
  Eigen::Vector3d sphere_center_;
  double sphere_radius_ = 0;
  Bvh bvh_;
};

}  // namespace core
}  // namespace laser_raycast
