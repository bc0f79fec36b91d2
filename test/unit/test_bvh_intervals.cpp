// BVH against brute force over [tmin, tmax]: inclusive limits, negative tmin, every interval.
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

constexpr double kInf = std::numeric_limits<double>::infinity();

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

}  // namespace
}  // namespace laser_raycast_test
