// The BVH tests' oracle and checks: every triangle tested through the free function, the BVH's
// answers (closest and any hit, both precisions, both culling modes) compared with it, a budget for
// the one documented exemption (bvh_agreement.h), and the rays and lattice that stress a slab test.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "bvh_agreement.h"
#include "laser_raycast/core/bvh.h"
#include "random.h"
#include "triangle_soup.h"

namespace laser_raycast_test {

namespace core = laser_raycast::core;

// Unit squares (two triangles each) on an integer lattice: a floor in z = 0 and walls x = k, y = k
// with z in [0, 1]. Leaf boxes then have faces exactly in the planes z = 0, z = 1, x = k, y = k.
inline Soup gridSoup() {
  Soup s;
  auto square = [&](const Eigen::Vector3d& o, const Eigen::Vector3d& e1,
                    const Eigen::Vector3d& e2) {
    s.add(o, o + e1, o + e1 + e2);
    s.add(o, o + e1 + e2, o + e2);
  };
  const Eigen::Vector3d ex = Eigen::Vector3d::UnitX(), ey = Eigen::Vector3d::UnitY(),
                        ez = Eigen::Vector3d::UnitZ();
  for (int i = 0; i < 8; ++i) {
    for (int j = 0; j < 8; ++j) square(Eigen::Vector3d(i, j, 0), ex, ey);
  }
  for (int k = 0; k <= 8; k += 2) {
    for (int j = 0; j < 8; ++j) {
      square(Eigen::Vector3d(k, j, 0), ey, ez);
      square(Eigen::Vector3d(j, k, 0), ez, ex);  // opposite winding to the x walls
    }
  }
  return s;
}

// The test's own oracle: every triangle through the free function, nearest kept (first on ties).
template <typename T, core::TriangleMethod M>
std::optional<core::MeshHitT<T>> oracle(const Soup& s, const core::RayT<T>& ray, bool cull) {
  std::optional<core::MeshHitT<T>> best;
  for (std::size_t i = 0; i < s.triangles.size(); ++i) {
    const auto& tri = s.triangles[i];
    const core::Vec3<T> a = s.vertices[tri[0]].cast<T>(), b = s.vertices[tri[1]].cast<T>(),
                        c = s.vertices[tri[2]].cast<T>();
    const auto hit = core::intersectTriangle<M>(ray, a, b, c, cull);
    if (hit && (!best || hit->t < best->t)) {
      best = core::MeshHitT<T>{hit->t, hit->u, hit->v, static_cast<std::uint32_t>(i)};
    }
  }
  return best;
}

template <typename T>
std::string describe(const core::RayT<T>& ray) {
  std::ostringstream out;
  out.precision(17);
  out << "ray origin (" << ray.origin.transpose() << ") dir (" << ray.dir.transpose() << ") t in ["
      << ray.tmin << ", " << ray.tmax << "]";
  return out.str();
}

// Rays where a reference method's hit lies outside its triangle's box and the BVH was allowed to
// disagree (see sameHit); counted so that a test can bound how often that happens.
inline int g_exemptions = 0;
inline int g_comparisons = 0;

// Resets the counters; at the end of the test, checks that the exemption stayed rare, so that it
// cannot hide a systematic miss: at most 1 in 200 comparisons (seen over 13 seeds: at most 8 in
// 10^4, all rays aimed at a vertex; typically 0 to 6 in 7 x 10^4).
struct ExemptionBudget {
  ExemptionBudget() {
    g_exemptions = 0;
    g_comparisons = 0;
  }
  ~ExemptionBudget() {
    EXPECT_LE(g_exemptions * 200, g_comparisons)
        << g_exemptions << " exemptions in " << g_comparisons << " comparisons";
  }
};

// hit equals expected: same hit/miss and bit-identical t. Different triangles are accepted only if
// hit's triangle, tested alone, gives exactly the same t (a tie, e.g. on a shared edge).
//
// With bvh_vs_reference (the BVH with any method but the watertight one), one disagreement is
// accepted: the BVH misses the oracle's hit (or finds a farther one) when the exact ray is not in
// that triangle's bounding box at the oracle's t (bvh_agreement.h). A reference method can round a
// ray that passes just outside a vertex onto the triangle (seen: seed_plane, seed_uv and cramer in
// float, for rays aimed at a vertex from elsewhere), or underflow a distance; the BVH culls boxes
// geometrically and cannot see such a hit, brute force has no boxes. The watertight test is always
// held to exact agreement.
template <typename T, core::TriangleMethod M>
testing::AssertionResult sameHit(const char* what, const Soup& s, const core::RayT<T>& ray,
                                 bool cull, const std::optional<core::MeshHitT<T>>& hit,
                                 const std::optional<core::MeshHitT<T>>& expected,
                                 bool bvh_vs_reference = false) {
  auto fail = [&]() {
    auto r = testing::AssertionFailure();
    r << what << " " << core::toString(M) << (sizeof(T) == 4 ? " float" : " double")
      << (cull ? " cull" : "") << ", " << describe(ray) << ": ";
    return r;
  };
  if (bvh_vs_reference && expected && (!hit || hit->t > expected->t) &&
      hitOutsideExactTriangleBox(s, expected->triangle, ray, expected->t)) {
    ++g_exemptions;
    return testing::AssertionSuccess();
  }
  if (hit.has_value() != expected.has_value()) {
    return fail() << (hit ? "hit" : "miss") << " but the oracle says "
                  << (expected ? "hit at t = " + std::to_string(expected->t) : std::string("miss"));
  }
  if (!hit) return testing::AssertionSuccess();
  if (hit->t != expected->t) {
    return fail() << "t " << hit->t << " (triangle " << hit->triangle << ") vs oracle "
                  << expected->t << " (triangle " << expected->triangle << "), difference "
                  << hit->t - expected->t;
  }
  if (hit->triangle == expected->triangle) {
    if (hit->u != expected->u || hit->v != expected->v) return fail() << "barycentrics differ";
    return testing::AssertionSuccess();
  }
  const core::TriangleIndices& tri = s.triangles[hit->triangle];
  const core::Vec3<T> a = s.vertices[tri[0]].cast<T>(), b = s.vertices[tri[1]].cast<T>(),
                      c = s.vertices[tri[2]].cast<T>();
  const auto alone = core::intersectTriangle<M>(ray, a, b, c, cull);
  if (!alone || alone->t != hit->t)
    return fail() << "triangle " << hit->triangle << " is not a tie";
  return testing::AssertionSuccess();
}

// Closest hit and any hit of the BVH against the test's oracle and the library's brute force.
template <typename T>
void checkRay(const core::BvhT<T>& bvh, const Soup& s, const core::RayT<T>& ray, bool cull,
              const std::vector<core::TriangleMethod>& methods) {
  for (const core::TriangleMethod method : methods) {
    ++g_comparisons;
    core::dispatchTriangleMethod(method, [&](auto m) {
      constexpr core::TriangleMethod M = decltype(m)::value;
      const bool reference = M != core::TriangleMethod::kWatertight;
      const auto expected = oracle<T, M>(s, ray, cull);
      const auto hit = bvh.template closestHit<M>(ray, cull);
      const int exemptions = g_exemptions;
      ASSERT_TRUE((sameHit<T, M>("BVH", s, ray, cull, hit, expected, reference)));
      const bool any = bvh.template anyHit<M>(ray, cull);
      ASSERT_EQ(any, hit.has_value()) << "anyHit " << core::toString(M) << " " << describe(ray);
      if (exemptions == g_exemptions) {
        ASSERT_EQ(any, expected.has_value())
            << "anyHit " << core::toString(M) << " " << describe(ray);
      }
      const auto brute = core::bruteForceClosestHit(M, s.vertices, s.triangles, ray, cull);
      ASSERT_TRUE((sameHit<T, M>("bruteForceClosestHit", s, ray, cull, brute, expected)));
    });
    if (testing::Test::HasFatalFailure()) return;
  }
}

inline const std::vector<core::TriangleMethod> kEveryMethod(core::kAllTriangleMethods.begin(),
                                                            core::kAllTriangleMethods.end());

inline void checkRayBothPrecisions(
    const core::Bvh& bvh, const core::BvhF& bvhf, const Soup& s, const core::Ray& ray,
    const std::vector<core::TriangleMethod>& methods = kEveryMethod) {
  for (const bool cull : {false, true}) {
    checkRay(bvh, s, ray, cull, methods);
    if (testing::Test::HasFatalFailure()) return;
    checkRay(bvhf, s, core::toFloat(ray), cull, methods);
    if (testing::Test::HasFatalFailure()) return;
  }
}

// A random ray of one of several kinds, aimed at or through the box.
inline core::Ray randomRay(Rng& rng, const core::Aabb& box, const Soup& s) {
  const Eigen::Vector3d pad = 0.5 * box.extent() + Eigen::Vector3d::Constant(0.1);
  core::Ray ray;
  ray.origin = uniformInBox(rng, box.lo - pad, box.hi + pad);
  const int kind = std::uniform_int_distribution<int>(0, 4)(rng);
  if (kind == 0) {
    // Towards a point of the box, not normalised (t is then not a distance).
    ray.dir = uniformInBox(rng, box.lo, box.hi) - ray.origin;
  } else if (kind == 1) {
    ray.dir = randomUnitVector(rng);
  } else if (kind == 2) {
    // One or two exact zero components, sometimes -0.0: the slab test divides by them.
    ray.origin = uniformInBox(rng, box.lo, box.hi);
    ray.dir = randomUnitVector(rng);
    const int zeros = std::uniform_int_distribution<int>(1, 2)(rng);
    const int first = std::uniform_int_distribution<int>(0, 2)(rng);
    for (int k = 0; k < zeros; ++k) {
      ray.dir[(first + k) % 3] = std::uniform_int_distribution<int>(0, 1)(rng) ? 0.0 : -0.0;
    }
  } else if (kind == 3) {
    // From a vertex (on the face of some leaf's box) towards another triangle.
    const auto& v = s.vertices;
    ray.origin = v[std::uniform_int_distribution<std::size_t>(0, v.size() - 1)(rng)];
    ray.dir = v[std::uniform_int_distribution<std::size_t>(0, v.size() - 1)(rng)] - ray.origin;
    if (ray.dir.squaredNorm() == 0) ray.dir = randomUnitVector(rng);
  } else {
    // Starting in the plane of a vertex coordinate: on a box face, moving in any direction.
    const auto& v =
        s.vertices[std::uniform_int_distribution<std::size_t>(0, s.vertices.size() - 1)(rng)];
    const int axis = std::uniform_int_distribution<int>(0, 2)(rng);
    ray.origin[axis] = v[axis];
    ray.dir = randomUnitVector(rng);
  }
  // A quarter of the rays get a finite interval.
  if (std::uniform_int_distribution<int>(0, 3)(rng) == 0) {
    const double scale = box.extent().norm() / std::max(ray.dir.norm(), 1e-300);
    ray.tmin = uniform(rng, 0, 0.5 * scale);
    ray.tmax = ray.tmin + uniform(rng, 0, scale);
  }
  return ray;
}

}  // namespace laser_raycast_test
