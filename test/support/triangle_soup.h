// Triangle soups for the BVH and Mesh tests: unconnected triangles (three vertices each), random
// ones spread out or clustered.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <random>
#include <vector>

#include "laser_raycast/core/aabb.h"
#include "laser_raycast/core/bvh.h"
#include "random.h"

namespace laser_raycast_test {

// Each triangle has its own three vertices.
struct Soup {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<laser_raycast::core::TriangleIndices> triangles;

  void add(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
    const auto n = static_cast<std::uint32_t>(vertices.size());
    vertices.push_back(a);
    vertices.push_back(b);
    vertices.push_back(c);
    triangles.push_back({n, n + 1, n + 2});
  }
  laser_raycast::core::Aabb bounds() const {
    laser_raycast::core::Aabb box;
    for (const auto& v : vertices) box.grow(v);
    return box;
  }
};

// Triangles of random size and orientation, spread over a 20 m cube.
inline Soup spreadSoup(Rng& rng, int n) {
  Soup s;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d c =
        uniformInBox(rng, Eigen::Vector3d::Constant(-10), Eigen::Vector3d::Constant(10));
    const double size = uniform(rng, 0.05, 2.0);
    s.add(c + size * randomUnitVector(rng), c + size * randomUnitVector(rng),
          c + size * randomUnitVector(rng));
  }
  return s;
}

// Small triangles packed in a few tight clusters: deep trees, many overlapping boxes.
inline Soup clusteredSoup(Rng& rng, int n) {
  Soup s;
  std::vector<Eigen::Vector3d> centers;
  for (int k = 0; k < 5; ++k) {
    centers.push_back(
        uniformInBox(rng, Eigen::Vector3d::Constant(-10), Eigen::Vector3d::Constant(10)));
  }
  std::normal_distribution<double> g(0.0, 0.3);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d c = centers[static_cast<std::size_t>(i) % centers.size()] +
                              Eigen::Vector3d(g(rng), g(rng), g(rng));
    const double size = uniform(rng, 0.01, 0.3);
    s.add(c + size * randomUnitVector(rng), c + size * randomUnitVector(rng),
          c + size * randomUnitVector(rng));
  }
  return s;
}

}  // namespace laser_raycast_test
