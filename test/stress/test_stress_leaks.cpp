// Stress case 1, leaks in 3D: rays exactly at shared vertices and edges of closed meshes
// (test_stress_fans.cpp has the planar fans). A non-watertight test lets such a ray slip between
// neighbours (a miss) or gives the shared point to both (a double hit).
//
// The truth is topological, independent of any intersection code: a ray from inside a convex
// closed mesh crosses its surface exactly once; a ray from outside a closed mesh crosses it an even
// number of times (touching a silhouette counts 0 or 2). Hits are counted by brute force over every
// triangle (or, for the large real meshes, over the triangles whose BVH boxes the ray's line passes
// near, by a distance test written here).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "laser_raycast/core/mesh.h"
#include "random.h"
#include "stress_report.h"

namespace laser_raycast_test {
namespace {

using core::Vec3;
using Eigen::Vector3d;

// ---------------------------------------------------------------------------------------------------
// Aimed rays.

// A ray from origin at vertex i (i == j) or at the point (1 - s) v_i + s v_j of an edge. Built in
// each precision from that precision's vertices, so that it aims at the stored vertex or edge.
struct Aim {
  Vector3d origin;
  std::uint32_t i, j;
  double s;
};

template <typename T>
core::RayT<T> aimedRay(const Aim& aim, const std::vector<Vec3<T>>& v) {
  const Vec3<T> target =
      aim.i == aim.j ? v[aim.i] : Vec3<T>(v[aim.i] + T(aim.s) * (v[aim.j] - v[aim.i]));
  core::RayT<T> ray;
  ray.origin = aim.origin.cast<T>();
  ray.dir = target - ray.origin;
  return ray;
}

// From each origin: every stride-th vertex, and of every stride-th edge its midpoint plus
// (random_edge_points) random points.
std::vector<Aim> aimsAtVerticesAndEdges(const TriMesh& mesh, const std::vector<Vector3d>& origins,
                                        int random_edge_points, Rng& rng, std::size_t stride = 1) {
  std::vector<Aim> aims;
  const auto edges = uniqueEdges(mesh);
  for (const Vector3d& o : origins) {
    for (std::uint32_t v = 0; v < mesh.vertices.size(); v += stride) aims.push_back({o, v, v, 0.0});
    for (std::size_t k = 0; k < edges.size(); k += stride) {
      const auto& e = edges[k];
      aims.push_back({o, e[0], e[1], 0.5});
      for (int k = 0; k < random_edge_points; ++k) {
        aims.push_back({o, e[0], e[1], uniform(rng, 0.0, 1.0)});
      }
    }
  }
  return aims;
}

// Hits on the triangles of every BVH leaf whose box the ray's line passes within the box's
// bounding sphere (plus a relative slack): a conservative filter written here, so that a count
// does not depend on the BVH's own slab test.
template <TriangleMethod M, typename T>
int countHitsNearLine(const core::BvhT<T>& bvh, const core::RayT<T>& ray) {
  const Vector3d o = ray.origin.template cast<double>();
  const Vector3d d = ray.dir.template cast<double>().normalized();
  const core::PreparedRay<T, M> prepared(ray, false);
  int hits = 0;
  bvh.visit(
      [&](const core::AabbT<T>& box) {
        const Vector3d oc = box.center().template cast<double>() - o;
        const double radius = 0.5 * box.extent().template cast<double>().norm();
        return (oc - oc.dot(d) * d).norm() <= radius * (1 + 1e-6) + 1e-6 * oc.norm();
      },
      [&](std::uint32_t slot) {
        const auto& v = bvh.triangleVertices()[slot];
        if (prepared.intersect(v[0], v[1], v[2], ray.tmax)) ++hits;
      });
  return hits;
}

struct LeakTally {
  long rays = 0, misses = 0, double_hits = 0, bvh_misses = 0;
  long outside_rays = 0, odd = 0;
};

// Rays from inside a convex closed mesh: exactly one triangle must be hit, and the BVH's closest
// hit must exist.
template <TriangleMethod M, typename T>
void castFromInside(const TriMesh& mesh, const core::BvhT<T>& bvh, const std::vector<Aim>& aims,
                    LeakTally* tally) {
  const auto v = castVertices<T>(mesh.vertices);
  for (const Aim& aim : aims) {
    const core::RayT<T> ray = aimedRay<T>(aim, v);
    const int hits = countHits<M>(ray, v, mesh.triangles);
    ++tally->rays;
    tally->misses += hits == 0;
    tally->double_hits += hits > 1;
    tally->bvh_misses += !bvh.template closestHit<M>(ray).has_value();
  }
}

// Rays from outside a closed mesh: an odd crossing count is a leak or a double hit.
template <TriangleMethod M, typename T>
void castFromOutside(const TriMesh& mesh, const core::BvhT<T>& bvh, const std::vector<Aim>& aims,
                     LeakTally* tally) {
  const auto v = castVertices<T>(mesh.vertices);
  for (const Aim& aim : aims) {
    ++tally->outside_rays;
    tally->odd += countHitsNearLine<M>(bvh, aimedRay<T>(aim, v)) % 2;
  }
}

// A convex closed mesh with interior origins.
struct InsideCase {
  TriMesh mesh;
  std::vector<Vector3d> origins;
};

InsideCase icosphereCase(int level, double radius, const Eigen::Isometry3d& pose, int origins,
                         Rng& rng) {
  InsideCase c{transformed(makeIcosphere(level), radius, pose), {pose.translation()}};
  for (int k = 0; k < origins; ++k) {
    const double r = 0.7 * radius * std::cbrt(uniform(rng, 0, 1));
    c.origins.push_back(pose * (r * randomUnitVector(rng)));
  }
  return c;
}

InsideCase boxRoomCase(const Vector3d& size, int cells, const Eigen::Isometry3d& pose, int origins,
                       Rng& rng) {
  InsideCase c{transformed(makeBoxRoom(size, cells), 1.0, pose), {pose.translation()}};
  for (int k = 0; k < origins; ++k) {
    c.origins.push_back(pose * uniformInBox(rng, -0.45 * size, 0.45 * size));
  }
  return c;
}

std::vector<std::string> tallyRow(const Variant& v, const LeakTally& t, bool inside, bool outside) {
  std::vector<std::string> row = {variantName(v)};
  if (inside) {
    for (const long n : {t.rays, t.misses, t.double_hits, t.bvh_misses}) row.push_back(count(n));
  }
  if (outside) {
    row.push_back(count(t.outside_rays));
    row.push_back(count(t.odd));
  }
  return row;
}

// Runs every variant over the cases (inside and outside) and returns the tallies, in variants()
// order.
std::vector<LeakTally> runLeakCases(
    const std::vector<InsideCase>& inside,
    const std::vector<std::pair<TriMesh, std::vector<Aim>>>& outside, Rng& rng) {
  std::vector<LeakTally> tallies(variants().size());
  auto run_mesh = [&](const TriMesh& mesh, const std::vector<Aim>* inside_aims,
                      const std::vector<Aim>* outside_aims) {
    const core::Bvh bvh = core::Bvh::build(mesh.vertices, mesh.triangles);
    const core::BvhF bvh_f = core::BvhF::build(mesh.vertices, mesh.triangles);
    for (std::size_t k = 0; k < variants().size(); ++k) {
      dispatchVariant(variants()[k], [&](auto m, auto x) {
        constexpr TriangleMethod M = decltype(m)::value;
        using T = decltype(x);
        if (inside_aims)
          castFromInside<M, T>(mesh, pick(bvh, bvh_f, T{}), *inside_aims, &tallies[k]);
        if (outside_aims) {
          castFromOutside<M, T>(mesh, pick(bvh, bvh_f, T{}), *outside_aims, &tallies[k]);
        }
      });
    }
  };
  for (const InsideCase& c : inside) {
    EXPECT_TRUE(isClosedAndConsistentlyWound(c.mesh));
    const std::vector<Aim> aims = aimsAtVerticesAndEdges(c.mesh, c.origins, 1, rng);
    run_mesh(c.mesh, &aims, nullptr);
  }
  for (const auto& c : outside) run_mesh(c.first, nullptr, &c.second);
  return tallies;
}

void expectProductionTight(const std::vector<LeakTally>& tallies) {
  ASSERT_TRUE(isProduction(variants()[0]));
  const LeakTally& p = tallies[0];
  EXPECT_EQ(p.misses, 0) << "watertight (double) let rays out of a closed mesh";
  EXPECT_EQ(p.double_hits, 0) << "watertight (double) hit two triangles at one point";
  EXPECT_EQ(p.bvh_misses, 0) << "the BVH lost a hit that brute force finds";
  EXPECT_EQ(p.odd, 0) << "an odd crossing count from outside a closed mesh";
}

// 1a. Icospheres (their vertex and edge-midpoint coordinates include exact zeros) and box rooms
// (vertices on grid coordinates, walls in coordinate planes), at the origin and moved.
TEST(StressLeaks, ConvexClosedMeshesFromInside) {
  Rng rng(1001);
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  const std::vector<InsideCase> cases = {
      icosphereCase(1, 1.0, identity, 8, rng),
      icosphereCase(3, 1.0, identity, 2, rng),
      icosphereCase(2, 2.5, randomPose(rng, 3.0), 4, rng),
      boxRoomCase(Vector3d(4, 3, 2.5), 4, identity, 6, rng),
      boxRoomCase(Vector3d(1, 1, 1), 3, randomPose(rng, 2.0), 6, rng),
  };
  const auto tallies = runLeakCases(cases, {}, rng);
  Table t{"1a",
          "1a. Leaks: rays at shared vertices and edges of convex closed meshes, from inside",
          "Icospheres (levels 1-3, one moved and rotated) and box rooms; rays from interior "
          "origins at every vertex and at two points of every edge. A ray from inside crosses a "
          "convex closed surface exactly once. Asserted on production: 0 misses, 0 double hits, 0 "
          "BVH misses.",
          {"method", "rays", "misses", "double hits", "BVH misses"},
          {}};
  for (std::size_t k = 0; k < variants().size(); ++k) {
    t.addRow(tallyRow(variants()[k], tallies[k], true, false));
  }
  record(t);
  EXPECT_GT(tallies[0].rays, 20000);
  expectProductionTight(tallies);
}

// ---------------------------------------------------------------------------------------------------
// Real meshes from ../shared/data.

class StressRealMeshLeaks : public ::testing::Test {
 protected:
  void SetUp() override { REQUIRE_SHARED_DATA(); }
};

// Interior points of a convex mesh: random points of its bounds at least `margin` inside every
// face plane.
std::vector<Vector3d> convexInterior(const TriMesh& mesh, double margin, int n, Rng& rng) {
  core::Aabb box;
  for (const Vector3d& v : mesh.vertices) box.grow(v);
  const double orientation = signedVolume(mesh) > 0 ? 1.0 : -1.0;
  std::vector<Vector3d> out = {box.center()};
  while (static_cast<int>(out.size()) < n) {
    const Vector3d p = uniformInBox(rng, box.lo, box.hi);
    bool inside = true;
    for (const auto& tri : mesh.triangles) {
      const Vector3d& a = mesh.vertices[tri[0]];
      const Vector3d n_out =
          orientation * (mesh.vertices[tri[1]] - a).cross(mesh.vertices[tri[2]] - a).normalized();
      inside = inside && n_out.dot(p - a) < -margin;
    }
    if (inside) out.push_back(p);
  }
  return out;
}

// 1b. The TurtleBot3 meshes, as the loader reads them (Collada inches, URDF scales). The hexagon
// is a convex prism (rays from inside); the arena wall (a hexagonal ring), the base plate, the LDS
// and a tyre (non-convex, 14,566 and 21,672 triangles) are checked by parity from outside.
TEST_F(StressRealMeshLeaks, ClosedMeshesFromInsideAndOutside) {
  Rng rng(1101);
  InsideCase hexagon;
  hexagon.mesh = loadSharedMesh("hexagon.dae", 0.8);
  ASSERT_LT(maxConvexityViolation(hexagon.mesh), 1e-12);
  hexagon.origins = convexInterior(hexagon.mesh, 0.1, 12, rng);

  std::vector<std::pair<TriMesh, std::vector<Aim>>> outside;
  const std::vector<std::pair<std::string, double>> files = {{"wall.dae", 0.25},
                                                             {"waffle/waffle_base.dae", 0.001},
                                                             {"waffle/lds.stl", 0.001},
                                                             {"waffle/left_tire.stl", 0.001}};
  for (const auto& file : files) {
    TriMesh mesh = loadSharedMesh(file.first, file.second);
    core::Aabb box;
    for (const Vector3d& v : mesh.vertices) box.grow(v);
    // Outside the bounding sphere, so certainly outside the solid.
    const Vector3d origin = box.center() + 1.5 * box.extent().norm() * randomUnitVector(rng);
    // Every third vertex and edge of the two large meshes keeps the run short.
    const std::size_t stride = mesh.triangles.size() > 1000 ? 3 : 1;
    std::vector<Aim> aims = aimsAtVerticesAndEdges(mesh, {origin}, 0, rng, stride);
    outside.emplace_back(std::move(mesh), std::move(aims));
  }
  const auto tallies = runLeakCases({hexagon}, outside, rng);
  Table t{
      "1b",
      "1b. Leaks: real closed meshes (../shared/data/tb3_world_data)",
      "`hexagon.dae` (scale 0.8, convex): rays from 12 interior origins at every vertex and two "
      "points of every edge, exactly one hit each. `wall.dae`, `waffle_base.dae`, `lds.stl`, "
      "`left_tire.stl` (closed, mostly non-convex): rays from a point outside the bounding "
      "sphere at every vertex and every edge midpoint (every third of each for the LDS and the "
      "tyre); an odd number of hits is a leak or a "
      "double hit. Asserted on production: all figures 0.",
      {"method", "rays (inside)", "misses", "double hits", "BVH misses", "rays (outside)",
       "odd hit counts"},
      {}};
  for (std::size_t k = 0; k < variants().size(); ++k) {
    t.addRow(tallyRow(variants()[k], tallies[k], true, true));
  }
  record(t);
  EXPECT_GT(tallies[0].outside_rays, 20000);
  expectProductionTight(tallies);
}

}  // namespace
}  // namespace laser_raycast_test
