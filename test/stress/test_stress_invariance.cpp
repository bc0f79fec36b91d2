// Stress case 7: invariance under vertex order. A triangle's three cyclic permutations and three
// reversed windings describe the same set of points, so they must get the same hit decision (with
// back-face culling off), including rays exactly on an edge or a vertex: the watertight tie-break
// orients each edge as a front-facing triangle traverses it, so it does not depend on the winding.
// t may differ by the rounding of a sum taken in another order: a few ulps of the vertices'
// distances along the ray.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "laser_raycast/core/bvh.h"
#include "random.h"
#include "stress_report.h"

namespace laser_raycast_test {
namespace {

using core::Vec3;
using Eigen::Vector3d;

// Identity, the two cyclic permutations, and the three reversals.
const int kOrders[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};

struct InvarianceTally {
  long rays = 0, mismatches = 0, beyond = 0;
  double max_ulps = 0;  // of t
};

template <typename T>
double ulpsApart(T a, T b) {
  const T ulp = std::nextafter(std::abs(a), std::numeric_limits<T>::infinity()) - std::abs(a);
  return double(std::abs(a - b) / ulp);
}

// The bound on the spread of t: 8 u sqrt(3) S / |d|, S the farthest vertex from the origin (t is
// a weighted mean of the vertices' distances along the ray, each at most sqrt(3) S / |d| in the
// watertight frame, summed in three roundings).
template <typename T>
double spreadBound(const Vec3<T>* v, const core::RayT<T>& ray) {
  double s = 0;
  for (int k = 0; k < 3; ++k) s = std::max(s, double((v[k] - ray.origin).norm()));
  return 8 * unitRoundoff<T>() * std::sqrt(3.0) * s / double(ray.dir.norm());
}

// Casts the ray at the six orderings of v and compares them with the first.
template <TriangleMethod M, typename T>
void compareOrders(const Vec3<T>* v, const core::RayT<T>& ray, InvarianceTally* tally) {
  std::optional<core::TriangleHitT<T>> hit[6];
  for (int o = 0; o < 6; ++o) {
    hit[o] = core::intersectTriangle<M>(ray, v[kOrders[o][0]], v[kOrders[o][1]], v[kOrders[o][2]]);
  }
  ++tally->rays;
  bool same = true, all_hit = true;
  for (int o = 1; o < 6; ++o) same = same && hit[o].has_value() == hit[0].has_value();
  for (int o = 0; o < 6; ++o) all_hit = all_hit && hit[o].has_value();
  tally->mismatches += !same;
  if (!all_hit) return;
  const double bound = spreadBound(v, ray);
  for (int o = 1; o < 6; ++o) {
    tally->max_ulps = std::max(tally->max_ulps, ulpsApart(hit[0]->t, hit[o]->t));
    tally->beyond += std::abs(double(hit[o]->t) - double(hit[0]->t)) > bound;
  }
}

// Random triangles: rays at an interior point, a point of an edge, a vertex, and a point outside.
template <TriangleMethod M, typename T>
void randomSet(Rng& rng, InvarianceTally* tally) {
  for (int n = 0; n < 2000; ++n) {
    Vec3<T> v[3];
    for (auto& p : v) p = uniformInCube(rng, 1.0).cast<T>();
    const Vec3<T> targets[4] = {
        v[0] + T(0.3) * (v[1] - v[0]) + T(0.3) * (v[2] - v[0]),
        v[0] + T(uniform(rng, 0, 1)) * (v[1] - v[0]),
        v[2],
        v[0] + T(-0.2) * (v[1] - v[0]) + T(0.5) * (v[2] - v[0]),
    };
    for (const Vec3<T>& target : targets) {
      core::RayT<T> ray;
      ray.origin = target + (uniform(rng, 1, 3) * randomUnitVector(rng)).cast<T>();
      ray.dir = target - ray.origin;
      compareOrders<M>(v, ray, tally);
    }
  }
}

// Small-integer triangles and directions with components in {-2..2}: the watertight shear factors
// are 0, +-1/2 or +-1, so every step is exact and rays aimed at a vertex or a dyadic point of an
// edge lie exactly on it (edge functions exactly 0: the tie-break decides).
template <TriangleMethod M, typename T>
void exactSet(Rng& rng, InvarianceTally* tally) {
  std::uniform_int_distribution<int> coord(-4, 4), dir(-2, 2), eighth(0, 8), quarter(0, 4),
      along(1, 3), corner(0, 2);
  for (int n = 0; n < 1500; ++n) {
    Vec3<T> v[3];
    for (auto& p : v) p = Vec3<T>(coord(rng), coord(rng), coord(rng));
    if (core::isDegenerateTriangle(v[0], v[1], v[2])) continue;
    for (int r = 0; r < 6; ++r) {
      Vec3<T> d;
      do {
        d = Vec3<T>(dir(rng), dir(rng), dir(rng));
      } while (d.isZero());
      Vec3<T> target;
      const int i = corner(rng), j = (i + 1) % 3, k = (i + 2) % 3;
      if (r < 2) {
        target = v[i];
      } else if (r < 4) {
        target = v[i] + T(quarter(rng) / 4.0) * (v[j] - v[i]);
      } else {
        const T a = T(eighth(rng) / 8.0), b = T(eighth(rng) / 8.0);
        target = v[i] + a * (v[j] - v[i]) + b * (v[k] - v[i]);
      }
      core::RayT<T> ray;
      ray.origin = target - T(along(rng)) * d;
      ray.dir = d;
      compareOrders<M>(v, ray, tally);
    }
  }
}

// A closed icosphere whose every triangle is rotated (b, c, a) or reversed (a, c, b): through the
// BVH, the closest hit must be the same triangle (its index is kept) at the same t.
template <TriangleMethod M, typename T>
void bvhSet(const std::vector<TriMesh>& versions, const std::vector<Vector3d>& origins, Rng& rng,
            InvarianceTally* tally) {
  std::vector<core::BvhT<T>> bvhs;
  for (const auto& m : versions) bvhs.push_back(core::BvhT<T>::build(m.vertices, m.triangles));
  const auto v = castVertices<T>(versions[0].vertices);
  const auto edges = uniqueEdges(versions[0]);
  for (const Vector3d& o : origins) {
    double s = 0;  // the farthest vertex, for the spread bound
    for (const auto& p : v) s = std::max(s, double((p - o.cast<T>()).norm()));
    std::vector<Vec3<T>> targets(v.begin(), v.end());
    for (const auto& e : edges) {
      targets.push_back(v[e[0]] + T(0.5) * (v[e[1]] - v[e[0]]));
      targets.push_back(v[e[0]] + T(uniform(rng, 0, 1)) * (v[e[1]] - v[e[0]]));
    }
    for (const Vec3<T>& target : targets) {
      core::RayT<T> ray;
      ray.origin = o.cast<T>();
      ray.dir = target - ray.origin;
      const auto h0 = bvhs[0].template closestHit<M>(ray);
      ++tally->rays;
      bool same = true;
      for (std::size_t k = 1; k < bvhs.size(); ++k) {
        const auto hk = bvhs[k].template closestHit<M>(ray);
        same = same && hk.has_value() == h0.has_value() && (!h0 || hk->triangle == h0->triangle);
        if (!h0 || !hk) continue;
        tally->max_ulps = std::max(tally->max_ulps, ulpsApart(h0->t, hk->t));
        tally->beyond += std::abs(double(hk->t) - double(h0->t)) >
                         8 * unitRoundoff<T>() * std::sqrt(3.0) * s / double(ray.dir.norm());
      }
      tally->mismatches += !same;
    }
  }
}

TEST(StressInvariance, VertexOrderDoesNotChangeDecisions) {
  Rng rng(7001);
  const TriMesh sphere = transformed(makeIcosphere(2), 1.5, randomPose(rng, 2.0));
  std::vector<TriMesh> versions(3, sphere);
  for (auto& tri : versions[1].triangles) tri = {tri[1], tri[2], tri[0]};
  for (auto& tri : versions[2].triangles) std::swap(tri[1], tri[2]);
  core::Aabb box;
  for (const Vector3d& p : sphere.vertices) box.grow(p);
  std::vector<Vector3d> origins = {box.center()};
  for (int k = 0; k < 2; ++k) origins.push_back(box.center() + 0.5 * randomUnitVector(rng));

  std::vector<InvarianceTally> random(variants().size()), exact(variants().size()),
      bvh(variants().size());
  for (std::size_t vi = 0; vi < variants().size(); ++vi) {
    // The same geometry and rays for every variant.
    Rng r1(7101), r2(7201), r3(7301);
    dispatchVariant(variants()[vi], [&](auto m, auto x) {
      constexpr TriangleMethod M = decltype(m)::value;
      using T = decltype(x);
      randomSet<M, T>(r1, &random[vi]);
      exactSet<M, T>(r2, &exact[vi]);
      bvhSet<M, T>(versions, origins, r3, &bvh[vi]);
    });
  }
  Table t{"7",
          "7. Invariance: decisions that change with the vertex order",
          "Each triangle in its 3 cyclic permutations and 3 reversed windings. Random: " +
              count(random[0].rays) +
              " rays at random triangles (an interior point, a point of an edge, a vertex, a point "
              "outside). Exact: " +
              count(exact[0].rays) +
              " rays at vertices, dyadic edge points and interior points of small-integer "
              "triangles, along small-integer directions (exactly on the edge or vertex in both "
              "precisions). BVH: " +
              count(bvh[0].rays) +
              " rays from inside an icosphere at its vertices and edges, with every triangle "
              "rotated or reversed; a mismatch is a different decision or triangle. Spread: the "
              "largest difference in t, in ulps of t. Asserted on production: 0 mismatches, and "
              "the spread of t within 8 u sqrt(3) S / |d| (S: farthest vertex).",
          {"method", "random: mismatches", "random: spread (ulps)", "exact: mismatches",
           "exact: spread (ulps)", "BVH: mismatches", "BVH: spread (ulps)"},
          {}};
  const auto ulps = [](double x) { return x < 1e4 ? fixed(x, 0) : sci(x); };
  for (std::size_t vi = 0; vi < variants().size(); ++vi) {
    t.addRow({variantName(variants()[vi]), count(random[vi].mismatches), ulps(random[vi].max_ulps),
              count(exact[vi].mismatches), ulps(exact[vi].max_ulps), count(bvh[vi].mismatches),
              ulps(bvh[vi].max_ulps)});
  }
  record(t);
  ASSERT_TRUE(isProduction(variants()[0]));
  EXPECT_EQ(random[0].mismatches, 0);
  EXPECT_EQ(exact[0].mismatches, 0);
  EXPECT_EQ(bvh[0].mismatches, 0);
  EXPECT_EQ(random[0].beyond, 0);
  EXPECT_EQ(exact[0].beyond, 0);
  EXPECT_EQ(bvh[0].beyond, 0);
  EXPECT_GT(exact[0].rays, 8000);
}

}  // namespace
}  // namespace laser_raycast_test
