#include "laser_raycast/core/mesh.h"

#include <sstream>
#include <stdexcept>

namespace laser_raycast {
namespace core {

Mesh::Mesh(std::vector<Eigen::Vector3d> vertices, std::vector<TriangleIndices> triangles,
           const BvhConfig& bvh_config)
    : vertices_(std::move(vertices)), triangles_(std::move(triangles)) {
  if (triangles_.empty()) throw std::invalid_argument("mesh has no triangles");
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    if (!vertices_[i].allFinite()) {
      std::ostringstream msg;
      msg << "mesh vertex " << i << " is not finite (" << vertices_[i].transpose() << ")";
      throw std::invalid_argument(msg.str());
    }
  }
  for (std::size_t i = 0; i < triangles_.size(); ++i) {
    for (const std::uint32_t v : triangles_[i]) {
      if (v >= vertices_.size()) {
        std::ostringstream msg;
        msg << "mesh triangle " << i << " refers to vertex " << v << " but there are only "
            << vertices_.size() << " vertices";
        throw std::invalid_argument(msg.str());
      }
    }
  }
  bvh_ = Bvh::build(vertices_, triangles_, bvh_config);
  if (bvh_.empty()) {
    std::ostringstream msg;
    msg << "mesh has " << triangles_.size() << " triangles but all of them have zero area";
    throw std::invalid_argument(msg.str());
  }
  // Bounds and sphere over the vertices that triangles use.
  for (const TriangleIndices& tri : triangles_) {
    for (const std::uint32_t v : tri) bounds_.grow(vertices_[v]);
  }
  sphere_center_ = bounds_.center();
  double r2 = 0;
  for (const TriangleIndices& tri : triangles_) {
    for (const std::uint32_t v : tri)
      r2 = std::max(r2, (vertices_[v] - sphere_center_).squaredNorm());
  }
  // Rounding of the squared norm and sqrt could put the farthest vertex just outside; widen by a
  // few ulps.
  sphere_radius_ = std::sqrt(r2) * (1 + 4 * std::numeric_limits<double>::epsilon());
}

Eigen::Vector3d Mesh::normal(std::uint32_t triangle) const {
  const TriangleIndices& t = triangles_[triangle];
  return (vertices_[t[1]] - vertices_[t[0]]).cross(vertices_[t[2]] - vertices_[t[0]]).normalized();
}

}  // namespace core
}  // namespace laser_raycast
