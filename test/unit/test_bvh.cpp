// BVH: it must return exactly what testing every triangle returns, for both
// precisions and every triangle method, including the rays that stress a slab test (zero and -0.0
// direction components, rays lying in box faces, rays starting on faces).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bvh_agreement.h"
#include "expect_invalid.h"
#include "laser_raycast/core/bvh.h"
#include "laser_raycast/core/mesh.h"
#include "random.h"
#include "triangle_soup.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

constexpr double kInf = std::numeric_limits<double>::infinity();

// Unit squares (two triangles each) on an integer lattice: a floor in z = 0 and walls x = k, y = k
// with z in [0, 1]. Leaf boxes then have faces exactly in the planes z = 0, z = 1, x = k, y = k.
Soup gridSoup() {
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
template <typename T, TriangleMethod M>
std::optional<MeshHitT<T>> oracle(const Soup& s, const RayT<T>& ray, bool cull) {
  std::optional<MeshHitT<T>> best;
  for (std::size_t i = 0; i < s.triangles.size(); ++i) {
    const auto& tri = s.triangles[i];
    const Vec3<T> a = s.vertices[tri[0]].cast<T>(), b = s.vertices[tri[1]].cast<T>(),
                  c = s.vertices[tri[2]].cast<T>();
    const auto hit = intersectTriangle<M>(ray, a, b, c, cull);
    if (hit && (!best || hit->t < best->t)) {
      best = MeshHitT<T>{hit->t, hit->u, hit->v, static_cast<std::uint32_t>(i)};
    }
  }
  return best;
}

template <typename T>
std::string describe(const RayT<T>& ray) {
  std::ostringstream out;
  out.precision(17);
  out << "ray origin (" << ray.origin.transpose() << ") dir (" << ray.dir.transpose() << ") t in ["
      << ray.tmin << ", " << ray.tmax << "]";
  return out.str();
}

// Rays where a reference method's hit lies outside its triangle's box and the BVH was allowed to
// disagree (see sameHit); counted so that a test can bound how often that happens.
int g_exemptions = 0;
int g_comparisons = 0;

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
template <typename T, TriangleMethod M>
testing::AssertionResult sameHit(const char* what, const Soup& s, const RayT<T>& ray, bool cull,
                                 const std::optional<MeshHitT<T>>& hit,
                                 const std::optional<MeshHitT<T>>& expected,
                                 bool bvh_vs_reference = false) {
  auto fail = [&]() {
    auto r = testing::AssertionFailure();
    r << what << " " << toString(M) << (sizeof(T) == 4 ? " float" : " double")
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
  const TriangleIndices& tri = s.triangles[hit->triangle];
  const Vec3<T> a = s.vertices[tri[0]].cast<T>(), b = s.vertices[tri[1]].cast<T>(),
                c = s.vertices[tri[2]].cast<T>();
  const auto alone = intersectTriangle<M>(ray, a, b, c, cull);
  if (!alone || alone->t != hit->t)
    return fail() << "triangle " << hit->triangle << " is not a tie";
  return testing::AssertionSuccess();
}

// Closest hit and any hit of the BVH against the test's oracle and the library's brute force.
template <typename T>
void checkRay(const BvhT<T>& bvh, const Soup& s, const RayT<T>& ray, bool cull,
              const std::vector<TriangleMethod>& methods) {
  for (const TriangleMethod method : methods) {
    ++g_comparisons;
    dispatchTriangleMethod(method, [&](auto m) {
      constexpr TriangleMethod M = decltype(m)::value;
      const bool reference = M != TriangleMethod::kWatertight;
      const auto expected = oracle<T, M>(s, ray, cull);
      const auto hit = bvh.template closestHit<M>(ray, cull);
      const int exemptions = g_exemptions;
      ASSERT_TRUE((sameHit<T, M>("BVH", s, ray, cull, hit, expected, reference)));
      const bool any = bvh.template anyHit<M>(ray, cull);
      ASSERT_EQ(any, hit.has_value()) << "anyHit " << toString(M) << " " << describe(ray);
      if (exemptions == g_exemptions) {
        ASSERT_EQ(any, expected.has_value()) << "anyHit " << toString(M) << " " << describe(ray);
      }
      const auto brute = bruteForceClosestHit(M, s.vertices, s.triangles, ray, cull);
      ASSERT_TRUE((sameHit<T, M>("bruteForceClosestHit", s, ray, cull, brute, expected)));
    });
    if (testing::Test::HasFatalFailure()) return;
  }
}

const std::vector<TriangleMethod> kEveryMethod(kAllTriangleMethods.begin(),
                                               kAllTriangleMethods.end());

void checkRayBothPrecisions(const Bvh& bvh, const BvhF& bvhf, const Soup& s, const Ray& ray,
                            const std::vector<TriangleMethod>& methods = kEveryMethod) {
  for (const bool cull : {false, true}) {
    checkRay(bvh, s, ray, cull, methods);
    if (testing::Test::HasFatalFailure()) return;
    checkRay(bvhf, s, toFloat(ray), cull, methods);
    if (testing::Test::HasFatalFailure()) return;
  }
}

// A random ray of one of several kinds, aimed at or through the box.
Ray randomRay(Rng& rng, const Aabb& box, const Soup& s) {
  const Eigen::Vector3d pad = 0.5 * box.extent() + Eigen::Vector3d::Constant(0.1);
  Ray ray;
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

// The core property: random soups from 1 to 5000 triangles, spread and clustered, every method and
// precision, against brute force.
TEST(Bvh, MatchesBruteForceOnRandomSoups) {
  const ExemptionBudget budget;
  Rng rng(20240601);
  for (const int n : {1, 2, 3, 10, 100, 1000, 5000}) {
    for (const bool clustered : {false, true}) {
      const Soup s = clustered ? clusteredSoup(rng, n) : spreadSoup(rng, n);
      const Bvh bvh = Bvh::build(s.vertices, s.triangles);
      const BvhF bvhf = BvhF::build(s.vertices, s.triangles);
      ASSERT_EQ(bvh.triangleIds().size(), s.triangles.size());
      const int rays = n >= 5000 ? 60 : n >= 1000 ? 150 : 300;
      for (int i = 0; i < rays; ++i) {
        SCOPED_TRACE(testing::Message() << "n " << n << (clustered ? " clustered" : " spread"));
        checkRayBothPrecisions(bvh, bvhf, s, randomRay(rng, s.bounds(), s));
        if (HasFatalFailure()) return;
      }
    }
  }
}

// Tree shape must not change answers: one triangle per leaf, huge leaves, 2 bins, depth cap 2.
TEST(Bvh, MatchesBruteForceForEveryConfig) {
  const ExemptionBudget budget;
  Rng rng(77);
  const Soup s = clusteredSoup(rng, 400);
  std::vector<BvhConfig> configs(5);
  configs[0].max_leaf_size = 1;
  configs[1].max_leaf_size = 64;
  configs[2].bins = 2;
  configs[3].max_depth = 2;
  configs[4].traversal_cost = 0;
  for (const BvhConfig& config : configs) {
    const Bvh bvh = Bvh::build(s.vertices, s.triangles, config);
    const BvhF bvhf = BvhF::build(s.vertices, s.triangles, config);
    EXPECT_LE(bvh.depth(), config.max_depth);
    for (int i = 0; i < 100; ++i) {
      checkRayBothPrecisions(bvh, bvhf, s, randomRay(rng, s.bounds(), s));
      if (HasFatalFailure()) return;
    }
  }
}

// Rays lying exactly in the planes of leaf box faces (z = 0, z = 1, x = k), along lattice lines
// through shared edges, and starting on triangles: a slab test that turns 0 * inf into a miss
// loses the wall bottoms here.
TEST(Bvh, MatchesBruteForceOnLatticeWithRaysInBoxFaces) {
  const ExemptionBudget budget;
  const Soup s = gridSoup();
  Rng rng(5);
  for (const int leaf : {1, 2, 8}) {
    BvhConfig config;
    config.max_leaf_size = leaf;
    const Bvh bvh = Bvh::build(s.vertices, s.triangles, config);
    const BvhF bvhf = BvhF::build(s.vertices, s.triangles, config);
    auto coordinate = [&](double lo, double hi) {
      // Integers and halves half of the time: on lattice lines and box faces.
      if (std::uniform_int_distribution<int>(0, 1)(rng)) {
        return 0.5 * std::uniform_int_distribution<int>(static_cast<int>(2 * lo),
                                                        static_cast<int>(2 * hi))(rng);
      }
      return uniform(rng, lo, hi);
    };
    auto signedZero = [&]() { return std::uniform_int_distribution<int>(0, 1)(rng) ? 0.0 : -0.0; };
    for (int i = 0; i < 1500; ++i) {
      Ray ray;
      const int kind = i % 5;
      if (kind == 0) {
        // In the floor's plane z = 0 (also the bottom face of every wall's box).
        ray.origin = Eigen::Vector3d(coordinate(-1, 9), coordinate(-1, 9), 0.0);
        const double a = uniform(rng, -M_PI, M_PI);
        ray.dir = Eigen::Vector3d(std::cos(a), std::sin(a), signedZero());
      } else if (kind == 1) {
        // In z = 1, the top face of the walls' boxes.
        ray.origin = Eigen::Vector3d(coordinate(-1, 9), coordinate(-1, 9), 1.0);
        const double a = uniform(rng, -M_PI, M_PI);
        ray.dir = Eigen::Vector3d(std::cos(a), std::sin(a), signedZero());
      } else if (kind == 2) {
        // Axis-aligned from lattice points: along shared edges and box edges.
        ray.origin = Eigen::Vector3d(coordinate(-1, 9), coordinate(-1, 9), coordinate(-0.5, 1.5));
        ray.dir = Eigen::Vector3d(signedZero(), signedZero(), signedZero());
        ray.dir[std::uniform_int_distribution<int>(0, 2)(rng)] =
            std::uniform_int_distribution<int>(0, 1)(rng) ? 1.0 : -1.0;
      } else if (kind == 3) {
        // In a wall's plane x = k, in any direction within it.
        ray.origin = Eigen::Vector3d(2.0 * std::uniform_int_distribution<int>(0, 4)(rng),
                                     coordinate(-1, 9), coordinate(-0.5, 1.5));
        const double a = uniform(rng, -M_PI, M_PI);
        ray.dir = Eigen::Vector3d(signedZero(), std::cos(a), std::sin(a));
      } else {
        // Starting on a wall or the floor, leaving in a random direction.
        ray.origin = Eigen::Vector3d(coordinate(0, 8), coordinate(0, 8), coordinate(0, 1));
        ray.origin[std::uniform_int_distribution<int>(0, 2)(rng)] =
            2.0 * std::uniform_int_distribution<int>(0, 4)(rng) * (i % 2);
        ray.dir = randomUnitVector(rng);
      }
      checkRayBothPrecisions(bvh, bvhf, s, ray);
      if (HasFatalFailure()) return;
    }
  }
}

// Literal cases for the lattice: rays lying exactly in z = 0, the plane of the floor and of the
// walls' bottom edges, so in the faces of the flat leaf boxes there. The floor is coplanar with
// them and the walls' bottom edges are boundary edges they only graze: the watertight method may
// give such an edge to the wall or not (its fixed tie-break), but the BVH must answer exactly what
// brute force answers, -0.0 components included. Half a metre up, the same rays meet the walls'
// faces.
TEST(Bvh, RayInFloorPlaneAgreesWithBruteForce) {
  const Soup s = gridSoup();
  const Bvh bvh = Bvh::build(s.vertices, s.triangles);
  for (const double dz : {0.0, -0.0}) {
    for (const double dx : {1.0, -1.0}) {
      Ray ray;
      ray.origin = Eigen::Vector3d(0.5, 3.25, 0.0);
      ray.dir = Eigen::Vector3d(dx, -0.0, dz);
      const auto hit = bvh.closestHit<TriangleMethod::kWatertight>(ray);
      const auto brute =
          bruteForceClosestHit(TriangleMethod::kWatertight, s.vertices, s.triangles, ray);
      ASSERT_EQ(hit.has_value(), brute.has_value()) << "dx " << dx << " dz " << dz;
      if (hit) {
        EXPECT_EQ(hit->t, brute->t);
      }

      ray.origin.z() = 0.5;
      const auto up = bvh.closestHit<TriangleMethod::kWatertight>(ray);
      ASSERT_TRUE(up);
      EXPECT_EQ(up->t, dx > 0 ? 1.5 : 0.5);  // the walls x = 2 and x = 0
    }
  }
}

// tmax (or tmin) equal to the nearest hit's own t must still find it (the interval is inclusive),
// and one ulp inside must agree with brute force too. The walls are axis-aligned, so their leaf
// boxes are flat and the hit lies exactly in the box's entry face, where only rounding separates
// the box's entry from the triangle's t. Found 27% of such rays losing the hit at tmax = t (every
// method), before the traversal widened its box culling; see TmaxAtHitRegression.
TEST(Bvh, TminTmaxAtTheHitDistanceAreInclusive) {
  const ExemptionBudget budget;
  Rng rng(31);
  Soup s;
  for (int i = 0; i < 300; ++i) {
    const int axis = i % 3;
    const Eigen::Vector3d o =
        uniformInBox(rng, Eigen::Vector3d::Constant(-5), Eigen::Vector3d::Constant(5));
    // Mostly small walls; one in ten large, where t's rounding scales with the far vertices.
    const double size = i % 10 ? 2.0 : 40.0;
    Eigen::Vector3d e1 = Eigen::Vector3d::Zero(), e2 = Eigen::Vector3d::Zero();
    e1[(axis + 1) % 3] = uniform(rng, 0.2, size);
    e2[(axis + 2) % 3] = uniform(rng, 0.2, size);
    s.add(o - 0.5 * e1, o + 0.5 * e1, o + e2);
  }
  const Bvh bvh = Bvh::build(s.vertices, s.triangles);
  const BvhF bvhf = BvhF::build(s.vertices, s.triangles);
  int checked = 0;
  for (int i = 0; i < 1500; ++i) {
    Ray ray;
    ray.origin = uniformInBox(rng, Eigen::Vector3d::Constant(-7), Eigen::Vector3d::Constant(7));
    ray.dir = randomUnitVector(rng);
    for (const TriangleMethod method : kAllTriangleMethods) {
      const auto first = bruteForceClosestHit(method, s.vertices, s.triangles, ray);
      const auto first_f = bruteForceClosestHit(method, s.vertices, s.triangles, toFloat(ray));
      if (!first || !first_f) continue;
      ++checked;
      const double t = first->t;
      const float tf = first_f->t;
      for (const int side : {0, 1}) {
        // side 0: tmax at the hit and one ulp nearer; side 1: tmin at the hit and one ulp farther.
        for (const int ulp : {0, 1}) {
          Ray r = ray;
          RayF rf = toFloat(ray);
          if (side == 0) {
            r.tmax = ulp ? std::nextafter(t, 0.0) : t;
            rf.tmax = ulp ? std::nextafter(tf, 0.0f) : tf;
          } else {
            r.tmin = ulp ? std::nextafter(t, kInf) : t;
            rf.tmin = ulp ? std::nextafter(tf, std::numeric_limits<float>::infinity()) : tf;
          }
          for (const bool cull : {false, true}) {
            checkRay(bvh, s, r, cull, {method});
            checkRay(bvhf, s, rf, cull, {method});
            if (HasFatalFailure()) return;
          }
        }
      }
    }
  }
  EXPECT_GT(checked, 1000);
}

// Literal case from the test above: a wall in x = 3 whose box is flat, so the slab entry is exactly
// 0.625 while the watertight test rounds the same hit to 0.62499999999999989. With tmax set to that
// t, the box was culled and the hit lost.
TEST(Bvh, TmaxAtHitRegression) {
  const std::vector<Eigen::Vector3d> v = {Eigen::Vector3d(3, -1, -1), Eigen::Vector3d(3, 2, -1),
                                          Eigen::Vector3d(3, -1, 2)};
  const std::vector<TriangleIndices> tris = {{0, 1, 2}};
  const Bvh bvh = Bvh::build(v, tris);
  Ray ray;
  ray.origin = Eigen::Vector3d(2.375, -0.75, -0.5625);
  ray.dir = Eigen::Vector3d(1, 1, 1.1);
  const auto alone = intersectTriangle<TriangleMethod::kWatertight>(ray, v[0], v[1], v[2]);
  ASSERT_TRUE(alone);
  ASSERT_LT(alone->t, 0.625);  // the case needs t rounded below the box entry
  ray.tmax = alone->t;
  const auto hit = bvh.closestHit<TriangleMethod::kWatertight>(ray);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->t, alone->t);
  EXPECT_TRUE(bvh.anyHit<TriangleMethod::kWatertight>(ray));
}

// Every interval the API accepts, against brute force: tmin negative (down to -inf) so that the
// ray reaches behind its origin, tmin and tmax exactly 0 with the origin on a triangle (a hit at
// t = 0), tmax = +inf (the Ray default), empty and inverted intervals, -0.0.
TEST(Bvh, MatchesBruteForceForEveryInterval) {
  const ExemptionBudget budget;
  Rng rng(4711);
  for (const int n : {1, 10, 300}) {
    for (const bool clustered : {false, true}) {
      const Soup s = clustered ? clusteredSoup(rng, n) : spreadSoup(rng, n);
      const Bvh bvh = Bvh::build(s.vertices, s.triangles);
      const BvhF bvhf = BvhF::build(s.vertices, s.triangles);
      for (int i = 0; i < 200; ++i) {
        Ray ray = randomRay(rng, s.bounds(), s);
        if (i % 2 == 0) {
          // From a point on a triangle (its barycentric combination, rounded): hits at t = 0 or
          // within rounding of it, on either side.
          const auto& tri = s.triangles[std::uniform_int_distribution<std::size_t>(
              0, s.triangles.size() - 1)(rng)];
          const Eigen::Vector2d uv = randomBarycentrics(rng);
          ray.origin = (1 - uv.x() - uv.y()) * s.vertices[tri[0]] + uv.x() * s.vertices[tri[1]] +
                       uv.y() * s.vertices[tri[2]];
          ray.dir = randomUnitVector(rng);
        }
        const double reach = 2 * s.bounds().extent().norm() / ray.dir.norm();
        const double kIntervals[][2] = {{-kInf, kInf},
                                        {-reach, kInf},
                                        {-uniform(rng, 0, reach), 0.0},
                                        {0.0, 0.0},
                                        {-0.0, 0.0},
                                        {0.0, kInf},
                                        {-0.0, kInf},
                                        {-kInf, 0.0},
                                        {-kInf, -uniform(rng, 0, reach)},
                                        {-reach, -0.5 * reach},
                                        {-uniform(rng, 0, reach), uniform(rng, 0, reach)},
                                        {0.0, -0.0},
                                        {1.0, -1.0},
                                        {kInf, kInf}};
        for (const auto& interval : kIntervals) {
          ray.tmin = interval[0];
          ray.tmax = interval[1];
          SCOPED_TRACE(testing::Message() << "n " << n << (clustered ? " clustered" : " spread"));
          checkRayBothPrecisions(bvh, bvhf, s, ray);
          if (HasFatalFailure()) return;
        }
      }
    }
  }
}

// Regression (found by test/fuzz/fuzz_core): a flat box behind the ray's origin, reached with a
// negative tmin, was culled: the slab test widened its far distance by multiplying it by 1 + 2
// gamma(3), which moves a negative distance away from the box. The wall x = 3 is hit at t = -2 from
// x = 5, for every method.
TEST(Bvh, FlatBoxBehindTheOriginRegression) {
  Soup s;
  s.add(Eigen::Vector3d(3, -1, -1), Eigen::Vector3d(3, 1, -1), Eigen::Vector3d(3, 0, 2));
  const Bvh bvh = Bvh::build(s.vertices, s.triangles);
  const BvhF bvhf = BvhF::build(s.vertices, s.triangles);
  Ray ray;
  ray.origin = Eigen::Vector3d(5, 0, 0);
  ray.dir = Eigen::Vector3d::UnitX();
  for (const double tmin : {-kInf, -10.0, -2.0}) {
    ray.tmin = tmin;
    for (const TriangleMethod method : kAllTriangleMethods) {
      dispatchTriangleMethod(method, [&](auto m) {
        constexpr TriangleMethod M = decltype(m)::value;
        const auto hit = bvh.closestHit<M>(ray);
        ASSERT_TRUE(hit) << toString(M) << " tmin " << tmin;
        EXPECT_EQ(hit->t, -2.0) << toString(M);
        EXPECT_TRUE(bvh.anyHit<M>(ray)) << toString(M);
        const auto hitf = bvhf.closestHit<M>(toFloat(ray));
        ASSERT_TRUE(hitf) << toString(M) << " float, tmin " << tmin;
        EXPECT_EQ(hitf->t, -2.0f) << toString(M);
      });
    }
  }
}

// Regression (found by test/fuzz/fuzz_core): a direction component below the smallest normal
// number times the largest (1e-160 against 5e307) underflows in the watertight test's shear, which
// then tests a ray lying in the plane y = 0 and hits the triangle's edge there; the BVH culled the
// triangle's box (y <= 0), which the exact ray leaves at once. The slab test now ignores such an
// axis, and the BVH answers as every triangle tested does.
TEST(Bvh, DirectionComponentBelowTheNormalRangeRegression) {
  Soup s;
  s.add(Eigen::Vector3d(-0.5, -0.5, -0.5), Eigen::Vector3d(0, 0, -1.5),
        Eigen::Vector3d(-9.9999999068677425, 0, 0));
  const Bvh bvh = Bvh::build(s.vertices, s.triangles);
  Ray ray;
  ray.origin = Eigen::Vector3d(-4, 0, -7.4214818095454849);
  ray.dir = Eigen::Vector3d(1, 1e-160, 5.133768998453546e+307);
  const auto brute =
      bruteForceClosestHit(TriangleMethod::kWatertight, s.vertices, s.triangles, ray);
  ASSERT_TRUE(brute);
  const auto hit = bvh.closestHit<TriangleMethod::kWatertight>(ray);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->t, brute->t);
  checkRayBothPrecisions(bvh, BvhF::build(s.vertices, s.triangles), s, ray);
}

// Literal tmin/tmax cases on one wall at x = 3 (t is a distance: unit direction).
TEST(Bvh, TminTmaxLimits) {
  Soup s;
  s.add(Eigen::Vector3d(3, -1, -1), Eigen::Vector3d(3, 1, -1), Eigen::Vector3d(3, 0, 2));
  s.add(Eigen::Vector3d(5, -1, -1), Eigen::Vector3d(5, 1, -1), Eigen::Vector3d(5, 0, 2));
  const Bvh bvh = Bvh::build(s.vertices, s.triangles);
  Ray ray;
  ray.dir = Eigen::Vector3d::UnitX();
  for (const TriangleMethod method : kAllTriangleMethods) {
    dispatchTriangleMethod(method, [&](auto m) {
      constexpr TriangleMethod M = decltype(m)::value;
      auto t = [&](double tmin, double tmax) {
        ray.tmin = tmin;
        ray.tmax = tmax;
        const auto hit = bvh.closestHit<M>(ray);
        EXPECT_EQ(bvh.anyHit<M>(ray), hit.has_value());
        return hit ? hit->t : kInf;
      };
      EXPECT_EQ(t(0, kInf), 3.0) << toString(M);
      EXPECT_EQ(t(0, 3.0), 3.0) << toString(M);    // tmax inclusive
      EXPECT_EQ(t(3.0, 4.0), 3.0) << toString(M);  // tmin inclusive
      EXPECT_EQ(t(0, 2.999), kInf) << toString(M);
      EXPECT_EQ(t(3.001, kInf), 5.0) << toString(M);  // the nearer wall is before tmin
      EXPECT_EQ(t(5.001, kInf), kInf) << toString(M);
      EXPECT_EQ(t(3.5, 4.5), kInf) << toString(M);  // between the walls
    });
  }
}

// A hit is finite through the BVH too: a wall 1e300 away along a direction of length 1e-10 lies at
// t = 1e310, beyond the largest double. Every method used to report t = +Inf with tmax = +Inf.
TEST(Bvh, HitBeyondTheLargestFiniteTIsNoHitRegression) {
  Soup s;
  s.add(Eigen::Vector3d(1e300, -1, -1), Eigen::Vector3d(1e300, 1, -1),
        Eigen::Vector3d(1e300, 0, 2));
  const Bvh bvh = Bvh::build(s.vertices, s.triangles);
  Ray ray;
  ray.dir = Eigen::Vector3d(1e-10, 0, 0);
  for (const TriangleMethod method : kAllTriangleMethods) {
    dispatchTriangleMethod(method, [&](auto m) {
      constexpr TriangleMethod M = decltype(m)::value;
      EXPECT_FALSE(bvh.closestHit<M>(ray)) << toString(M);
      EXPECT_FALSE(bvh.anyHit<M>(ray)) << toString(M);
      EXPECT_FALSE(bruteForceClosestHit(M, s.vertices, s.triangles, ray)) << toString(M);
    });
  }
}

// Regression (found by test/fuzz/fuzz_core): vertices near the largest double made the binned
// build's centroid extent overflow, and a bin index was computed by converting NaN to int
// (undefined; the sanitizer build stops there). The tree must still answer as brute force does.
TEST(Bvh, CoordinatesNearTheLargestDoubleRegression) {
  const ExemptionBudget budget;
  constexpr double kMax = std::numeric_limits<double>::max();
  Soup s;
  for (const double x : {kMax, -kMax, 0.5 * kMax}) {
    s.add(Eigen::Vector3d(x, 0, 0), Eigen::Vector3d(x, 1, 0), Eigen::Vector3d(x, 0, 1));
  }
  Rng rng(9);
  const Soup near = spreadSoup(rng, 20);
  for (std::size_t t = 0; t < near.triangles.size(); ++t) {
    s.add(near.vertices[near.triangles[t][0]], near.vertices[near.triangles[t][1]],
          near.vertices[near.triangles[t][2]]);
  }
  const Bvh bvh = Bvh::build(s.vertices, s.triangles);
  const BvhF bvhf = BvhF::build(s.vertices, s.triangles);
  for (int i = 0; i < 50; ++i) {
    checkRayBothPrecisions(bvh, bvhf, s, randomRay(rng, near.bounds(), near));
    if (HasFatalFailure()) return;
  }
  Ray along;
  along.origin = Eigen::Vector3d(0, 0.25, 0.25);
  along.dir = Eigen::Vector3d(1, 0, 0);
  ASSERT_TRUE(bvh.closestHit<TriangleMethod::kWatertight>(along));
  EXPECT_EQ(bvh.closestHit<TriangleMethod::kWatertight>(along)->t, 0.5 * kMax);
}

// Many copies of one triangle (and same-centre triangles of different sizes): no SAH plane can
// separate them; the build must terminate within max_depth and still answer correctly.
TEST(Bvh, AllCentroidsEqual) {
  const ExemptionBudget budget;
  Soup copies, nested;
  for (int i = 0; i < 1000; ++i) {
    copies.add(Eigen::Vector3d(-1, -1, 2), Eigen::Vector3d(1, -1, 2), Eigen::Vector3d(0, 1, 2));
    // Bounds centre (0, 0, z) for every size.
    const double h = 0.01 * (i + 1);
    nested.add(Eigen::Vector3d(-h, -h, 2 + 0.001 * (i % 7)), Eigen::Vector3d(h, -h, 2),
               Eigen::Vector3d(0, h, 2 - 0.001 * (i % 7)));
  }
  for (const Soup* s : {&copies, &nested}) {
    for (const int max_depth : {1, 3, 60}) {
      BvhConfig config;
      config.max_depth = max_depth;
      const Bvh bvh = Bvh::build(s->vertices, s->triangles, config);
      const BvhF bvhf = BvhF::build(s->vertices, s->triangles, config);
      EXPECT_LE(bvh.depth(), max_depth);
      EXPECT_LE(bvhf.depth(), max_depth);
      EXPECT_EQ(bvh.triangleIds().size(), s->triangles.size());
      Ray ray;
      ray.origin = Eigen::Vector3d(0.001, 0.002, 0);
      ray.dir = Eigen::Vector3d::UnitZ();
      const auto hit = bvh.closestHit<TriangleMethod::kWatertight>(ray);
      ASSERT_TRUE(hit);
      checkRayBothPrecisions(bvh, bvhf, *s, ray);
      Rng rng(max_depth);
      for (int i = 0; i < 20; ++i)
        checkRayBothPrecisions(bvh, bvhf, *s, randomRay(rng, s->bounds(), *s));
    }
  }
}

// The tree's own invariants, checked from nodes(): each node contains its children (or its
// triangles' vertices), every non-degenerate triangle sits in exactly one leaf slot, and the copied
// vertices are the mesh's (rounded to float for BvhF).
template <typename T>
void checkStructure(const BvhT<T>& bvh, const Soup& s) {
  using Child = typename BvhT<T>::Child;
  std::vector<int> seen(s.triangles.size(), 0);
  auto contains = [](const AabbT<T>& outer, const Vec3<T>& p) {
    return (outer.lo.array() <= p.array()).all() && (p.array() <= outer.hi.array()).all();
  };
  // Walk from the root with each subtree's box (the exact bounds at the root, then the float boxes
  // stored in the parents): every vertex must lie in the box of the leaf holding it.
  std::vector<std::pair<Child, AabbT<T>>> todo{{bvh.root(), bvh.bounds()}};
  std::size_t inner = 0;
  while (!todo.empty()) {
    const auto [child, box] = todo.back();
    todo.pop_back();
    if (child.isLeaf()) {
      for (std::uint32_t slot = child.index; slot < child.index + child.count; ++slot) {
        const std::uint32_t id = bvh.triangleIds()[slot];
        ++seen[id];
        for (int k = 0; k < 3; ++k) {
          const Vec3<T> v = s.vertices[s.triangles[id][k]].cast<T>();
          EXPECT_EQ(bvh.triangleVertices()[slot][k], v);
          EXPECT_TRUE(contains(box, v));
        }
      }
      continue;
    }
    ASSERT_LT(child.index, bvh.nodes().size());
    ++inner;
    const auto& node = bvh.nodes()[child.index];
    for (int k = 0; k < 2; ++k) todo.emplace_back(node.child[k], node.box(k));
  }
  EXPECT_EQ(inner, bvh.nodes().size());  // every inner node is reached exactly once
  for (std::size_t i = 0; i < s.triangles.size(); ++i) {
    const auto& tri = s.triangles[i];
    const bool degenerate = isDegenerateTriangle<T>(
        s.vertices[tri[0]].cast<T>(), s.vertices[tri[1]].cast<T>(), s.vertices[tri[2]].cast<T>());
    EXPECT_EQ(seen[i], degenerate ? 0 : 1) << "triangle " << i;
  }
}

TEST(Bvh, StructureInvariants) {
  Rng rng(3);
  for (const int n : {1, 5, 300, 3000}) {
    const Soup s = n % 2 ? spreadSoup(rng, n) : clusteredSoup(rng, n);
    checkStructure(Bvh::build(s.vertices, s.triangles), s);
    checkStructure(BvhF::build(s.vertices, s.triangles), s);
  }
  checkStructure(Bvh::build(gridSoup().vertices, gridSoup().triangles), gridSoup());
}

// Degenerate triangles (repeated vertex, collinear, a sliver that is collinear only once rounded to
// float) are left out of the BVH, counted by Mesh, and never hit.
TEST(Bvh, DegenerateTrianglesAreExcluded) {
  const ExemptionBudget budget;
  Rng rng(11);
  Soup s = spreadSoup(rng, 200);
  const auto n0 = static_cast<std::uint32_t>(s.vertices.size());
  s.vertices.push_back(Eigen::Vector3d(0, 0, 0));
  s.vertices.push_back(Eigen::Vector3d(1, 1, 1));
  s.vertices.push_back(Eigen::Vector3d(2, 2, 2));        // collinear with the two above
  s.vertices.push_back(Eigen::Vector3d(0.5, 1e-50, 0));  // off the x axis only in double
  s.vertices.push_back(Eigen::Vector3d(1, 0, 0));
  s.triangles.push_back({n0, n0, n0 + 1});          // repeated vertex
  s.triangles.push_back({n0, n0 + 1, n0 + 2});      // collinear
  s.triangles.push_back({n0 + 2, n0 + 1, n0 + 1});  // repeated vertex again
  s.triangles.push_back({n0, n0 + 4, n0 + 3});      // a sliver, degenerate in float only
  // Shuffle them into the middle so that indices past them are checked too.
  std::swap(s.triangles[10], s.triangles[s.triangles.size() - 1]);
  std::swap(s.triangles[20], s.triangles[s.triangles.size() - 2]);

  const Mesh mesh(s.vertices, s.triangles);
  EXPECT_EQ(mesh.degenerateTriangleCount(), 3u);
  EXPECT_EQ(mesh.triangles().size(), s.triangles.size());
  const Bvh& bvh = mesh.bvh();
  const BvhF bvhf = BvhF::build(s.vertices, s.triangles);
  EXPECT_EQ(bvh.triangleIds().size(), s.triangles.size() - 3);
  EXPECT_EQ(bvhf.triangleIds().size(), s.triangles.size() - 4);
  checkStructure(bvh, s);
  checkStructure(bvhf, s);
  for (int i = 0; i < 300; ++i) {
    Ray ray = randomRay(rng, s.bounds(), s);
    if (i % 3 == 0) {
      // Straight through the degenerate ones' line and the sliver.
      ray.origin = Eigen::Vector3d(0.25, 1e-60, -1);
      ray.dir = Eigen::Vector3d(0.3 * (i % 7), 0, 1);
    }
    checkRayBothPrecisions(bvh, bvhf, s, ray);
    if (HasFatalFailure()) return;
  }
}

// No triangles, or only degenerate ones: an empty BVH that hits nothing.
TEST(Bvh, EmptyBuildHitsNothing) {
  const std::vector<Eigen::Vector3d> v = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0)};
  for (const auto& tris :
       {std::vector<TriangleIndices>{}, std::vector<TriangleIndices>{{0, 1, 1}, {0, 0, 0}}}) {
    const Bvh bvh = Bvh::build(v, tris);
    EXPECT_TRUE(bvh.empty());
    EXPECT_TRUE(bvh.bounds().empty());
    Ray ray;
    EXPECT_FALSE(bvh.closestHit<TriangleMethod::kWatertight>(ray));
    EXPECT_FALSE(bvh.anyHit<TriangleMethod::kWatertight>(ray));
    int visited = 0;
    bvh.visit([](const Aabb&) { return true; }, [&](std::uint32_t) { ++visited; });
    EXPECT_EQ(visited, 0);
  }
}

// visit() calls leaf() for exactly the slots of the leaves whose box passes the predicate, once
// each. An overlap test is monotone (a child overlaps only if its parent does: the float boxes
// stored in the nodes nest, being outward roundings of nested boxes), so the expected set is read
// straight from nodes(), plus the root's exact box, which a child's rounded box may exceed by an
// ulp.
TEST(Bvh, VisitReachesExactlyTheLeavesThatPass) {
  Rng rng(8);
  const Soup s = spreadSoup(rng, 2000);
  const Bvh bvh = Bvh::build(s.vertices, s.triangles);
  for (int q = 0; q < 50; ++q) {
    const Eigen::Vector3d c =
        uniformInBox(rng, Eigen::Vector3d::Constant(-12), Eigen::Vector3d::Constant(12));
    const Eigen::Vector3d h =
        uniformInBox(rng, Eigen::Vector3d::Constant(0), Eigen::Vector3d::Constant(6));
    auto overlaps = [&](const Aabb& box) {
      return (box.lo.array() <= (c + h).array()).all() && (box.hi.array() >= (c - h).array()).all();
    };
    std::multiset<std::uint32_t> expected, visited;
    ASSERT_FALSE(bvh.root().isLeaf());
    for (const auto& node : bvh.nodes()) {
      for (int k = 0; k < 2; ++k) {
        const auto leaf = node.child[k];
        if (!leaf.isLeaf() || !overlaps(bvh.bounds()) || !overlaps(node.box(k))) continue;
        for (std::uint32_t slot = leaf.index; slot < leaf.index + leaf.count; ++slot) {
          expected.insert(slot);
        }
      }
    }
    int calls = 0;
    bvh.visit(
        [&](const Aabb& box) {
          ++calls;
          return overlaps(box);
        },
        [&](std::uint32_t slot) { visited.insert(slot); });
    EXPECT_EQ(visited, expected);
    EXPECT_GT(calls, 0);
  }
  // Everything / nothing.
  std::multiset<std::uint32_t> all;
  bvh.visit([](const Aabb&) { return true; }, [&](std::uint32_t slot) { all.insert(slot); });
  EXPECT_EQ(all.size(), s.triangles.size());
  EXPECT_EQ(std::set<std::uint32_t>(all.begin(), all.end()).size(), s.triangles.size());
  int none = 0;
  bvh.visit([](const Aabb&) { return false; }, [&](std::uint32_t) { ++none; });
  EXPECT_EQ(none, 0);
}

void expectInvalid(const BvhConfig& config, const std::string& field, const std::string& value) {
  expectMentions(invalidMessage([&] { config.validate(); }), {field, value});
  // build() validates too.
  const std::vector<Eigen::Vector3d> v = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0),
                                          Eigen::Vector3d(0, 1, 0)};
  EXPECT_THROW(Bvh::build(v, {{0, 1, 2}}, config), std::invalid_argument);
}

TEST(BvhConfig, ValidateNamesFieldAndValue) {
  BvhConfig ok;
  EXPECT_NO_THROW(ok.validate());
  BvhConfig c;
  c.max_leaf_size = 0;
  expectInvalid(c, "max_leaf_size", "0");
  c = BvhConfig{};
  c.max_leaf_size = -3;
  expectInvalid(c, "max_leaf_size", "-3");
  c = BvhConfig{};
  c.bins = 1;
  expectInvalid(c, "bins", "1");
  c.bins = 257;
  expectInvalid(c, "bins", "257");
  c = BvhConfig{};
  c.traversal_cost = -0.5;
  expectInvalid(c, "traversal_cost", "-0.5");
  c.traversal_cost = std::nan("");
  expectInvalid(c, "traversal_cost", "nan");
  c.traversal_cost = kInf;
  expectInvalid(c, "traversal_cost", "inf");
  c = BvhConfig{};
  c.max_depth = 0;
  expectInvalid(c, "max_depth", "0");
  c.max_depth = 63;
  expectInvalid(c, "max_depth", "63");
  // The boundaries are accepted.
  for (const int bins : {2, 256}) {
    c = BvhConfig{};
    c.bins = bins;
    EXPECT_NO_THROW(c.validate());
  }
  for (const int depth : {1, 62}) {
    c = BvhConfig{};
    c.max_depth = depth;
    EXPECT_NO_THROW(c.validate());
  }
  c = BvhConfig{};
  c.max_leaf_size = 1;
  c.traversal_cost = 0;
  EXPECT_NO_THROW(c.validate());
}

// Deepest allowed tree with one triangle per leaf on a long chain of shrinking triangles: the
// traversal stack (64) must hold it.
TEST(Bvh, MaxDepthTreeTraversesCorrectly) {
  const ExemptionBudget budget;
  Soup s;
  for (int i = 0; i < 4000; ++i) {
    const double x = std::ldexp(1.0, -(i % 60)) + 1e-3 * i;  // spans many scales
    s.add(Eigen::Vector3d(x, -1, -1), Eigen::Vector3d(x, 1, -1), Eigen::Vector3d(x, 0, 1));
  }
  BvhConfig config;
  config.max_leaf_size = 1;
  config.max_depth = 62;
  const Bvh bvh = Bvh::build(s.vertices, s.triangles, config);
  const BvhF bvhf = BvhF::build(s.vertices, s.triangles, config);
  EXPECT_LE(bvh.depth(), 62);
  Rng rng(2);
  for (int i = 0; i < 50; ++i) {
    Ray ray;
    ray.origin =
        Eigen::Vector3d(uniform(rng, -1, 6), uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5));
    ray.dir = Eigen::Vector3d(i % 2 ? 1 : -1, 0, 0);
    checkRayBothPrecisions(bvh, bvhf, s, ray);
    if (HasFatalFailure()) return;
  }
}

}  // namespace
}  // namespace laser_raycast_test
