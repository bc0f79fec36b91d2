// Geometry for the unit tests: closed indexed triangle meshes (an icosphere, a box room) whose
// neighbouring triangles share vertices by index. Eigen and the standard library only, so that any
// test (triangle, BVH, caster) can include it.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <utility>
#include <vector>

namespace laser_raycast_test {

// An indexed triangle mesh. The triangle type matches core::TriangleIndices, so the vectors can be
// passed to core::Mesh and core::Bvh as they are. Meshes made here are closed and wound so that
// (b - a) x (c - a) points out of the enclosed volume.
struct TriMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

// ---------------------------------------------------------------------------------------------------
// Meshes.

// Flips b and c wherever the normal points towards `center`, so that a mesh that is star-shaped
// around `center` ends up wound outwards.
inline void orientOutwards(TriMesh* mesh, const Eigen::Vector3d& center) {
  for (auto& tri : mesh->triangles) {
    const Eigen::Vector3d& a = mesh->vertices[tri[0]];
    const Eigen::Vector3d& b = mesh->vertices[tri[1]];
    const Eigen::Vector3d& c = mesh->vertices[tri[2]];
    const Eigen::Vector3d centroid = (a + b + c) / 3.0;
    if ((b - a).cross(c - a).dot(centroid - center) < 0) std::swap(tri[1], tri[2]);
  }
}

// The unit icosahedron subdivided `levels` times: every triangle is split into four at its edge
// midpoints, which are pushed out onto the unit sphere. Each midpoint is made once per edge and
// shared by both triangles of that edge, so the mesh stays closed. Level L has 20 * 4^L triangles
// and 10 * 4^L + 2 vertices.
inline TriMesh makeIcosphere(int levels) {
  const double p = (1.0 + std::sqrt(5.0)) / 2.0;
  TriMesh mesh;
  mesh.vertices = {{-1, p, 0},  {1, p, 0},  {-1, -p, 0}, {1, -p, 0}, {0, -1, p},  {0, 1, p},
                   {0, -1, -p}, {0, 1, -p}, {p, 0, -1},  {p, 0, 1},  {-p, 0, -1}, {-p, 0, 1}};
  for (auto& v : mesh.vertices) v.normalize();
  mesh.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  orientOutwards(&mesh, Eigen::Vector3d::Zero());

  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoint_of_edge;
    auto midpoint = [&](std::uint32_t i, std::uint32_t j) {
      const auto key = std::minmax(i, j);
      const auto found = midpoint_of_edge.find(key);
      if (found != midpoint_of_edge.end()) return found->second;
      mesh.vertices.push_back((mesh.vertices[i] + mesh.vertices[j]).normalized());
      const auto index = static_cast<std::uint32_t>(mesh.vertices.size() - 1);
      midpoint_of_edge.emplace(key, index);
      return index;
    };
    std::vector<std::array<std::uint32_t, 3>> finer;
    finer.reserve(mesh.triangles.size() * 4);
    for (const auto& tri : mesh.triangles) {
      const std::uint32_t ab = midpoint(tri[0], tri[1]);
      const std::uint32_t bc = midpoint(tri[1], tri[2]);
      const std::uint32_t ca = midpoint(tri[2], tri[0]);
      // Same winding as the parent.
      finer.push_back({tri[0], ab, ca});
      finer.push_back({tri[1], bc, ab});
      finer.push_back({tri[2], ca, bc});
      finer.push_back({ab, bc, ca});
    }
    mesh.triangles = std::move(finer);
  }
  return mesh;
}

// The surface of the box [-size/2, size/2], each of the six walls a cells x cells grid of quads
// split into two triangles (the diagonal alternates like a checkerboard, so vertex valences vary).
// Vertices are the boundary points of one (cells + 1)^3 lattice, each computed once, so walls share
// their border vertices exactly. Wound outwards; a "room" seen from inside sees the back faces.
inline TriMesh makeBoxRoom(const Eigen::Vector3d& size, int cells) {
  TriMesh mesh;
  std::map<std::array<int, 3>, std::uint32_t> index_of;
  auto vertex = [&](const std::array<int, 3>& ijk) {
    const auto found = index_of.find(ijk);
    if (found != index_of.end()) return found->second;
    Eigen::Vector3d p;
    for (int k = 0; k < 3; ++k) p[k] = size[k] * (static_cast<double>(ijk[k]) / cells - 0.5);
    mesh.vertices.push_back(p);
    const auto index = static_cast<std::uint32_t>(mesh.vertices.size() - 1);
    index_of.emplace(ijk, index);
    return index;
  };
  for (int axis = 0; axis < 3; ++axis) {
    // (axis, u_axis, v_axis) is a cyclic permutation, so e_u x e_v = +e_axis.
    const int u_axis = (axis + 1) % 3, v_axis = (axis + 2) % 3;
    for (const int side : {0, cells}) {
      for (int i = 0; i < cells; ++i) {
        for (int j = 0; j < cells; ++j) {
          auto corner = [&](int di, int dj) {
            std::array<int, 3> ijk{};
            ijk[axis] = side;
            ijk[u_axis] = i + di;
            ijk[v_axis] = j + dj;
            return vertex(ijk);
          };
          const std::uint32_t p00 = corner(0, 0), p10 = corner(1, 0), p11 = corner(1, 1),
                              p01 = corner(0, 1);
          std::array<std::uint32_t, 3> t0, t1;
          if ((i + j) % 2 == 0) {
            t0 = {p00, p10, p11};
            t1 = {p00, p11, p01};
          } else {
            t0 = {p00, p10, p01};
            t1 = {p10, p11, p01};
          }
          // Counter-clockwise in (u, v) has normal +e_axis: outward on the far wall only.
          if (side == 0) {
            std::swap(t0[1], t0[2]);
            std::swap(t1[1], t1[2]);
          }
          mesh.triangles.push_back(t0);
          mesh.triangles.push_back(t1);
        }
      }
    }
  }
  return mesh;
}

// A closed prism over a polygon star-shaped about the z axis: a row of vertices at each of zs, two
// triangles per side quad, and caps fanned to a vertex on the axis. Wound outwards.
inline TriMesh makePrism(const std::vector<Eigen::Vector2d>& polygon,
                         const std::vector<double>& zs) {
  TriMesh m;
  const auto n = static_cast<std::uint32_t>(polygon.size());
  for (const double z : zs) {
    for (const auto& p : polygon) m.vertices.emplace_back(p.x(), p.y(), z);
  }
  auto at = [n](std::size_t row, std::uint32_t i) {
    return static_cast<std::uint32_t>(row * n + i % n);
  };
  for (std::size_t r = 0; r + 1 < zs.size(); ++r) {
    for (std::uint32_t i = 0; i < n; ++i) {
      m.triangles.push_back({at(r, i), at(r, i + 1), at(r + 1, i + 1)});
      m.triangles.push_back({at(r, i), at(r + 1, i + 1), at(r + 1, i)});
    }
  }
  for (const std::size_t row : {std::size_t(0), zs.size() - 1}) {
    m.vertices.emplace_back(0, 0, zs[row]);
    const auto c = static_cast<std::uint32_t>(m.vertices.size() - 1);
    for (std::uint32_t i = 0; i < n; ++i) m.triangles.push_back({c, at(row, i + 1), at(row, i)});
  }
  orientOutwards(&m, Eigen::Vector3d(0, 0, 0.5 * (zs.front() + zs.back())));
  return m;
}

// Every vertex v becomes pose * (scale * v). Shared vertices stay shared (one transformed copy
// each).
inline TriMesh transformed(const TriMesh& mesh, double scale, const Eigen::Isometry3d& pose) {
  TriMesh out = mesh;
  for (auto& v : out.vertices) v = pose * (scale * v);
  return out;
}

// Each undirected edge once, as (lower index, higher index), in a fixed order.
inline std::vector<std::array<std::uint32_t, 2>> uniqueEdges(const TriMesh& mesh) {
  std::vector<std::array<std::uint32_t, 2>> edges;
  for (const auto& tri : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const auto e = std::minmax(tri[k], tri[(k + 1) % 3]);
      edges.push_back({e.first, e.second});
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

// True if every directed edge i -> j occurs in exactly one triangle and j -> i in exactly one
// other: a closed, consistently wound 2-manifold.
inline bool isClosedAndConsistentlyWound(const TriMesh& mesh) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> count;
  for (const auto& tri : mesh.triangles) {
    for (int k = 0; k < 3; ++k) ++count[{tri[k], tri[(k + 1) % 3]}];
  }
  for (const auto& entry : count) {
    if (entry.second != 1) return false;
    const auto reverse = count.find({entry.first.second, entry.first.first});
    if (reverse == count.end() || reverse->second != 1) return false;
  }
  return true;
}

// The enclosed volume by the divergence theorem: positive when the mesh is wound outwards.
inline double signedVolume(const TriMesh& mesh) {
  double volume = 0;
  for (const auto& tri : mesh.triangles) {
    volume += mesh.vertices[tri[0]].dot(mesh.vertices[tri[1]].cross(mesh.vertices[tri[2]]));
  }
  return volume / 6.0;
}

// The largest distance by which a vertex lies outside the plane of a triangle (relative to the
// triangle's own normal): <= 0, up to rounding, for a convex mesh wound outwards.
inline double maxConvexityViolation(const TriMesh& mesh) {
  double worst = -std::numeric_limits<double>::infinity();
  for (const auto& tri : mesh.triangles) {
    const Eigen::Vector3d& a = mesh.vertices[tri[0]];
    const Eigen::Vector3d n =
        (mesh.vertices[tri[1]] - a).cross(mesh.vertices[tri[2]] - a).normalized();
    for (const auto& v : mesh.vertices) worst = std::max(worst, n.dot(v - a));
  }
  return worst;
}

}  // namespace laser_raycast_test
