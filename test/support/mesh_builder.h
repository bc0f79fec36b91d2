// Meshes for the Caster tests, built as core::Mesh: boxes whose faces are grids over chosen
// coordinates, prisms over star-shaped polygons, lat-long spheres and random soups. Neighbouring
// faces share their vertices, so the closed ones are watertight by construction.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <utility>
#include <vector>

#include "laser_raycast/core/mesh.h"
#include "random.h"
#include "test_geometry.h"

namespace laser_raycast_test {

namespace core = laser_raycast::core;

// Adds vertices and triangles, each triangle wound so that its front face looks a given way.
class MeshBuilder {
 public:
  std::uint32_t vertex(const Eigen::Vector3d& p) {
    vertices_.push_back(p);
    return static_cast<std::uint32_t>(vertices_.size() - 1);
  }
  // A triangle wound so that its front face looks along `front` (outward or inward).
  void triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c, const Eigen::Vector3d& front) {
    const Eigen::Vector3d n = (vertices_[b] - vertices_[a]).cross(vertices_[c] - vertices_[a]);
    if (n.dot(front) >= 0) {
      triangles_.push_back({a, b, c});
    } else {
      triangles_.push_back({a, c, b});
    }
  }
  void quad(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d,
            const Eigen::Vector3d& front) {
    triangle(a, b, c, front);
    triangle(a, c, d, front);
  }
  std::shared_ptr<const core::Mesh> build() const {
    return std::make_shared<const core::Mesh>(vertices_, triangles_);
  }
  const std::vector<Eigen::Vector3d>& vertices() const { return vertices_; }

 private:
  std::vector<Eigen::Vector3d> vertices_;
  std::vector<core::TriangleIndices> triangles_;
};

// The surface of the box [lo, hi], each face a grid over the given coordinates (which must start at
// lo and end at hi on their axis), so that vertex rows lie exactly at chosen heights. Neighbouring
// faces use the same coordinates, so every edge is shared exactly. Front faces point inward
// (a room) or outward (an object).
inline std::shared_ptr<const core::Mesh> gridBox(const std::vector<double>& xs,
                                                 const std::vector<double>& ys,
                                                 const std::vector<double>& zs, bool inward) {
  MeshBuilder m;
  const std::vector<double>* coords[3] = {&xs, &ys, &zs};
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (const bool high : {false, true}) {
      const double w = high ? coords[axis]->back() : coords[axis]->front();
      Eigen::Vector3d out = Eigen::Vector3d::Zero();
      out[axis] = high ? 1 : -1;
      const Eigen::Vector3d front = inward ? -out : out;
      const auto& us = *coords[u];
      const auto& vs = *coords[v];
      std::vector<std::uint32_t> ids(us.size() * vs.size());
      for (std::size_t i = 0; i < us.size(); ++i) {
        for (std::size_t j = 0; j < vs.size(); ++j) {
          Eigen::Vector3d p;
          p[axis] = w;
          p[u] = us[i];
          p[v] = vs[j];
          ids[i * vs.size() + j] = m.vertex(p);
        }
      }
      for (std::size_t i = 0; i + 1 < us.size(); ++i) {
        for (std::size_t j = 0; j + 1 < vs.size(); ++j) {
          m.quad(ids[i * vs.size() + j], ids[(i + 1) * vs.size() + j],
                 ids[(i + 1) * vs.size() + j + 1], ids[i * vs.size() + j + 1], front);
        }
      }
    }
  }
  return m.build();
}

inline std::vector<double> steps(double lo, double hi, int n) {
  std::vector<double> out;
  for (int i = 0; i <= n; ++i) out.push_back(i == n ? hi : lo + (hi - lo) * i / n);
  return out;
}

// makePrism as a core::Mesh, its front faces outward or, for a room, inward.
inline std::shared_ptr<const core::Mesh> prism(const std::vector<Eigen::Vector2d>& polygon,
                                               const std::vector<double>& zs, bool inward) {
  TriMesh mesh = makePrism(polygon, zs);
  if (inward) {
    for (auto& triangle : mesh.triangles) std::swap(triangle[1], triangle[2]);
  }
  return std::make_shared<const core::Mesh>(mesh.vertices, mesh.triangles);
}

inline std::vector<Eigen::Vector2d> circle(int n, double radius, double phase = 0) {
  std::vector<Eigen::Vector2d> out;
  for (int i = 0; i < n; ++i) {
    const double a = phase + 2 * M_PI * i / n;
    out.emplace_back(radius * std::cos(a), radius * std::sin(a));
  }
  return out;
}

// A lat-long sphere (closed, outward), for random scenes.
inline std::shared_ptr<const core::Mesh> uvSphere(double radius, int rings, int segments) {
  MeshBuilder m;
  const std::uint32_t south = m.vertex(Eigen::Vector3d(0, 0, -radius));
  const std::uint32_t north = m.vertex(Eigen::Vector3d(0, 0, radius));
  std::vector<std::vector<std::uint32_t>> row(rings - 1);
  for (int r = 1; r < rings; ++r) {
    const double phi = -M_PI / 2 + M_PI * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double th = 2 * M_PI * s / segments;
      row[r - 1].push_back(
          m.vertex(radius * Eigen::Vector3d(std::cos(phi) * std::cos(th),
                                            std::cos(phi) * std::sin(th), std::sin(phi))));
    }
  }
  auto out = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    return (m.vertices()[a] + m.vertices()[b] + m.vertices()[c]).eval();
  };
  for (int s = 0; s < segments; ++s) {
    const int t = (s + 1) % segments;
    m.triangle(south, row[0][s], row[0][t], out(south, row[0][s], row[0][t]));
    m.triangle(north, row.back()[s], row.back()[t], out(north, row.back()[s], row.back()[t]));
    for (int r = 0; r + 1 < rings - 1; ++r) {
      m.quad(row[r][s], row[r][t], row[r + 1][t], row[r + 1][s],
             out(row[r][s], row[r][t], row[r + 1][t]));
    }
  }
  return m.build();
}

inline std::shared_ptr<const core::Mesh> randomSoup(Rng& rng, int n, double spread, double size) {
  MeshBuilder m;
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d c(spread * u(rng), spread * u(rng), spread * u(rng));
    const auto a = m.vertex(c + size * Eigen::Vector3d(u(rng), u(rng), u(rng)));
    const auto b = m.vertex(c + size * Eigen::Vector3d(u(rng), u(rng), u(rng)));
    const auto d = m.vertex(c + size * Eigen::Vector3d(u(rng), u(rng), u(rng)));
    m.triangle(a, b, d, Eigen::Vector3d(u(rng), u(rng), u(rng)));
  }
  return m.build();
}

}  // namespace laser_raycast_test
