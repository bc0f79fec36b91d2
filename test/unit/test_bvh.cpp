// BVH against brute force: random soups, tree configurations, rays in box faces, extreme values.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "bvh_checks.h"
#include "laser_raycast/core/bvh.h"
#include "random.h"
#include "triangle_soup.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

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
