// Closed components (Mesh::slotFacing) and the back faces a sensor outside them never sees first
// (hiddenBackFace): which components count as closed, and, against brute force over every
// triangle, that leaving the hidden back faces out never changes a beam's nearest distance.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <utility>
#include <optional>
#include <vector>

#include "laser_raycast/core/mesh.h"
#include "laser_raycast/core/triangle.h"
#include "mesh_builder.h"
#include "random.h"
#include "test_geometry.h"

namespace laser_raycast_test {
namespace {

namespace core = laser_raycast::core;

// Several closed solids in one mesh: icospheres and prisms, some wound inwards, placed apart.
TriMesh solids(Rng& rng, int count, bool some_inward) {
  TriMesh out;
  for (int k = 0; k < count; ++k) {
    TriMesh m = k % 2 ? makeIcosphere(1)
                      : makePrism(circle(3 + k % 7, uniform(rng, 0.2, 0.8), uniform(rng, 0, 1)),
                                  {-0.5, 0.1, 0.7});
    if (some_inward && k % 3 == 0) {
      for (auto& t : m.triangles) std::swap(t[1], t[2]);
    }
    const Eigen::Vector3d at(uniform(rng, -6, 6), uniform(rng, -6, 6), uniform(rng, -1, 1));
    const auto base = static_cast<std::uint32_t>(out.vertices.size());
    for (const auto& v : m.vertices) out.vertices.push_back(v * uniform(rng, 0.3, 1.2) + at);
    for (const auto& t : m.triangles)
      out.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  return out;
}

TEST(MeshClosed, ClosedComponentsAndTheirWinding) {
  Rng rng(71);
  const TriMesh m = solids(rng, 9, true);
  const core::Mesh mesh(m.vertices, m.triangles);
  ASSERT_TRUE(mesh.hasClosedComponents());
  const auto& ids = mesh.bvh().triangleIds();
  const std::vector<std::uint32_t> components = mesh.components();
  for (std::size_t slot = 0; slot < ids.size(); ++slot) {
    // Components are numbered in order of their first triangle, as they were appended.
    const std::uint32_t component = components[ids[slot]];
    EXPECT_EQ(mesh.slotFacing(slot), component % 3 == 0 ? -1 : 1) << "slot " << slot;
  }
  // Open: one triangle of each solid taken away; and two boxes sharing an edge's vertex indices
  // four times are not a closed surface either.
  TriMesh open = m;
  open.triangles.erase(open.triangles.begin());
  const core::Mesh open_mesh(open.vertices, open.triangles);
  EXPECT_EQ(open_mesh.slotFacing(0) != 0, true);  // the other solids stay closed
  int open_slots = 0;
  for (std::uint32_t slot = 0; slot < open_mesh.bvh().triangleIds().size(); ++slot) {
    open_slots += open_mesh.slotFacing(slot) == 0;
  }
  EXPECT_GT(open_slots, 0);
  const TriMesh sheet{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}};
  EXPECT_FALSE(core::Mesh(sheet.vertices, sheet.triangles).hasClosedComponents());
}

// Which components count as closed, against counting every directed edge of each component in a
// map: a component is closed when it has no triangle with a repeated vertex and each of its
// directed edges is used exactly once, as is its reverse. The solids are damaged at random: a
// triangle taken away, repeated, turned around, collapsed onto an edge, or a fin added on an edge
// (three triangles on it).
TEST(MeshClosed, ClosedAsCountingEveryEdgeSays) {
  Rng rng(83);
  int closed_seen = 0, open_seen = 0;
  for (int scene = 0; scene < 40; ++scene) {
    TriMesh m = solids(rng, 8, scene % 2 == 1);
    const int damage = static_cast<int>(rng() % 6);
    for (int d = 0; d < damage; ++d) {
      const std::size_t t = rng() % m.triangles.size();
      auto tri = m.triangles[t];
      switch (rng() % 5) {
        case 0:
          m.triangles.erase(m.triangles.begin() + static_cast<long>(t));
          break;
        case 1:
          m.triangles.push_back(tri);
          break;
        case 2:
          std::swap(m.triangles[t][1], m.triangles[t][2]);
          break;
        case 3:
          m.triangles[t][2] = tri[0];
          break;
        default: {
          // A new vertex off the edge tri[0]-tri[1], joined to it: a third triangle on that edge.
          m.vertices.push_back(m.vertices[tri[2]] + Eigen::Vector3d(0.01, 0.02, 0.03));
          m.triangles.push_back({tri[0], tri[1], static_cast<std::uint32_t>(m.vertices.size() - 1)});
          break;
        }
      }
    }
    const core::Mesh mesh(m.vertices, m.triangles);
    std::map<std::uint32_t, std::map<std::pair<std::uint32_t, std::uint32_t>, int>> uses;
    std::set<std::uint32_t> collapsed;
    const std::vector<std::uint32_t> components = mesh.components();
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
      const std::uint32_t c = components[t];
      auto& edges = uses[c];
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t from = m.triangles[t][k], to = m.triangles[t][(k + 1) % 3];
        if (from == to) collapsed.insert(c);
        ++edges[{from, to}];
      }
    }
    std::map<std::uint32_t, bool> closed;
    for (const auto& [c, edges] : uses) {
      bool ok = collapsed.count(c) == 0;
      for (const auto& [edge, n] : edges) {
        const auto reverse = edges.find({edge.second, edge.first});
        ok = ok && n == 1 && reverse != edges.end() && reverse->second == 1;
      }
      closed[c] = ok;
    }
    const auto& ids = mesh.bvh().triangleIds();
    for (std::size_t slot = 0; slot < ids.size(); ++slot) {
      const std::uint32_t c = components[ids[slot]];
      ASSERT_EQ(mesh.slotFacing(slot) != 0, closed[c])
          << "scene " << scene << " slot " << slot << " component " << c;
    }
    for (const auto& [c, ok] : closed) (ok ? closed_seen : open_seen)++;
  }
  EXPECT_GT(closed_seen, 100);
  EXPECT_GT(open_seen, 20);
}

// From outside every solid's bounds: the nearest hit over all triangles is the nearest over those
// that are not hidden back faces, for rays aimed at the solids (vertices and edges among them,
// where the rules for shared edges decide). To rounding: a ray exactly through a silhouette edge
// meets the front and the back face sharing it at one point, whose t each computes with its own
// rounding.
TEST(MeshClosed, HiddenBackFacesNeverHoldTheNearestHit) {
  Rng rng(73);
  long long hidden = 0, hits = 0;
  for (int scene = 0; scene < 20; ++scene) {
    const TriMesh m = solids(rng, 6, scene % 2 == 1);
    const core::Mesh mesh(m.vertices, m.triangles);
    const auto& slots = mesh.bvh().triangleVertices();
    for (int i = 0; i < 400; ++i) {
      const Eigen::Vector3d eye = uniformInCube(rng, 20);
      const auto& tri = slots[static_cast<std::size_t>(rng() % slots.size())];
      const Eigen::Vector3d target = i % 3 == 0 ? tri[0] : (tri[0] + tri[1]) * 0.5;
      core::Ray ray;
      ray.origin = eye;
      ray.dir = (i % 5 == 0 ? uniformInCube(rng, 8) : target) - eye;
      std::optional<double> all, visible;
      for (std::uint32_t slot = 0; slot < slots.size(); ++slot) {
        const auto& v = slots[slot];
        const auto hit =
            core::intersectTriangle<core::TriangleMethod::kWatertight>(ray, v[0], v[1], v[2]);
        const bool skip = core::hiddenBackFace(mesh, slot, eye, 0.0);
        hidden += skip;
        if (!hit) continue;
        if (!all || hit->t < *all) all = hit->t;
        if (!skip && (!visible || hit->t < *visible)) visible = hit->t;
      }
      ASSERT_EQ(all.has_value(), visible.has_value()) << "scene " << scene << " ray " << i;
      if (all) {
        ++hits;
        ASSERT_NEAR(*all, *visible, 1e-12 * *all) << "scene " << scene << " ray " << i;
      }
    }
  }
  EXPECT_GT(hits, 3000);
  EXPECT_GT(hidden, 100000);
}

// With a spread (a rotating sweep's block, every column's origin within that distance of the
// reference eye): a face hidden from the reference eye with the spread never holds the nearest hit
// of a ray from any eye within the spread, by brute force over every slot. Without the spread, the
// same rays meet faces hidden from the reference eye that they do hit first.
TEST(MeshClosed, HiddenWithASpreadFromEveryEyeWithinIt) {
  Rng rng(79);
  long long hidden = 0, hits = 0, wrong_without = 0;
  for (int scene = 0; scene < 12; ++scene) {
    const TriMesh m = solids(rng, 6, scene % 2 == 1);
    const core::Mesh mesh(m.vertices, m.triangles);
    const auto& slots = mesh.bvh().triangleVertices();
    for (int i = 0; i < 300; ++i) {
      // Eyes near the solids, where a spread of up to 0.5 m turns faces around.
      const Eigen::Vector3d reference = uniformInCube(rng, 8);
      const double spread = uniform(rng, 0.01, 0.5);
      const Eigen::Vector3d eye = reference + spread * uniform(rng, 0, 1) * randomUnitVector(rng);
      // Aimed at a face that turns around between the two eyes where there is one (the faces
      // the spread is for), else at a random one.
      std::size_t target = static_cast<std::size_t>(rng() % slots.size());
      for (std::size_t k = 0; k < slots.size(); ++k) {
        const auto& v = slots[(target + k) % slots.size()];
        const Eigen::Vector3d n = (v[1] - v[0]).cross(v[2] - v[0]);
        if (n.dot(v[0] - reference) * n.dot(v[0] - eye) < 0) {
          target = (target + k) % slots.size();
          break;
        }
      }
      const auto& tri = slots[target];
      core::Ray ray;
      ray.origin = eye;
      ray.dir = (tri[0] + tri[1] + tri[2]) / 3.0 - eye;
      std::optional<double> all, visible, visible_without;
      for (std::uint32_t slot = 0; slot < slots.size(); ++slot) {
        const auto& v = slots[slot];
        const auto hit =
            core::intersectTriangle<core::TriangleMethod::kWatertight>(ray, v[0], v[1], v[2]);
        const bool skip = core::hiddenBackFace(mesh, slot, reference, 0.0, spread);
        const bool skip_without = core::hiddenBackFace(mesh, slot, reference, 0.0);
        hidden += skip;
        if (!hit) continue;
        if (!all || hit->t < *all) all = hit->t;
        if (!skip && (!visible || hit->t < *visible)) visible = hit->t;
        if (!skip_without && (!visible_without || hit->t < *visible_without)) {
          visible_without = hit->t;
        }
      }
      ASSERT_EQ(all.has_value(), visible.has_value()) << "scene " << scene << " ray " << i;
      if (!all) continue;
      ++hits;
      ASSERT_NEAR(*all, *visible, 1e-12 * *all) << "scene " << scene << " ray " << i;
      wrong_without += !visible_without || std::abs(*visible_without - *all) > 1e-12 * *all;
    }
  }
  EXPECT_GT(hits, 2000);
  EXPECT_GT(hidden, 50000);
  EXPECT_GT(wrong_without, 0);  // the spread matters for these eyes
}

}  // namespace
}  // namespace laser_raycast_test
