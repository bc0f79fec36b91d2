// The triangle methods in double and float: names, and random cases against constructed truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <iomanip>
#include <iostream>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "laser_raycast/core/triangle.h"
#include "random.h"
#include "triangle_cases.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;
using Eigen::Vector3d;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// ---------------------------------------------------------------------------------------------------
// Names.

TEST(TriangleMethodName, RoundTripsAndRejectsUnknownNames) {
  const char* const expected[] = {"seed_plane", "seed_uv", "cramer", "moller_trumbore",
                                  "watertight"};
  ASSERT_EQ(kAllTriangleMethods.size(), 5u);
  for (std::size_t i = 0; i < kAllTriangleMethods.size(); ++i) {
    const TriangleMethod m = kAllTriangleMethods[i];
    EXPECT_STREQ(toString(m), expected[i]);
    TriangleMethod parsed =
        m == TriangleMethod::kCramer ? TriangleMethod::kWatertight : TriangleMethod::kCramer;
    ASSERT_TRUE(parseTriangleMethod(toString(m), &parsed)) << toString(m);
    EXPECT_EQ(parsed, m);
  }
  // Near misses of real names are rejected and leave the output untouched.
  for (const char* bad : {"", "unknown", "Watertight", "WATERTIGHT", "watertight ", " cramer",
                          "moller-trumbore", "moller", "seed", "seed_plane\n", "möller_trumbore"}) {
    TriangleMethod m = TriangleMethod::kSeedUv;
    EXPECT_FALSE(parseTriangleMethod(bad, &m)) << '"' << bad << '"';
    EXPECT_EQ(m, TriangleMethod::kSeedUv) << '"' << bad << '"';
  }
}

// ---------------------------------------------------------------------------------------------------
// Random property tests, once per precision.

template <typename T>
class TriangleRandom : public ::testing::Test {};
TYPED_TEST_SUITE(TriangleRandom, Precisions, PrecisionNames);

// Rays aimed inside the triangle hit it at the constructed t, u, v, in every method. With culling,
// exactly the front-face hits remain and are unchanged.
TYPED_TEST(TriangleRandom, HitsMatchConstructedTruth) {
  using T = TypeParam;
  Rng rng(20240601);
  constexpr int kCases = 4000;
  std::vector<double> worst_t(kAllTriangleMethods.size(), 0.0);
  std::vector<double> worst_uv(kAllTriangleMethods.size(), 0.0);
  int front_count = 0;
  for (int i = 0; i < kCases; ++i) {
    const AimedCase k = makeAimedCase(rng, randomInsideBarycentrics(rng, Tolerance<T>::kMargin));
    front_count += k.front;
    const RayT<T> ray = makeRay<T>(k.origin, k.dir);
    for (std::size_t mi = 0; mi < kAllTriangleMethods.size(); ++mi) {
      const TriangleMethod m = kAllTriangleMethods[mi];
      const std::string where = std::string(toString(m)) + " case " + std::to_string(i) + " " +
                                describe("hit", k.a, k.b, k.c, k.origin, k.dir);
      const auto hit = hitTriangle<T>(m, ray, k.a, k.b, k.c);
      ASSERT_TRUE(hit) << where;
      EXPECT_NEAR(hit->t, k.t, Tolerance<T>::kT * k.t) << where;
      EXPECT_NEAR(hit->u, k.u, Tolerance<T>::kUv) << where;
      EXPECT_NEAR(hit->v, k.v, Tolerance<T>::kUv) << where;
      worst_t[mi] = std::max(worst_t[mi], std::abs(hit->t - k.t) / k.t);
      worst_uv[mi] =
          std::max({worst_uv[mi], std::abs(hit->u - k.u), std::abs(double(hit->v) - k.v)});

      const auto culled = hitTriangle<T>(m, ray, k.a, k.b, k.c, /*cull=*/true);
      EXPECT_EQ(culled.has_value(), k.front) << "cull " << where;
      if (culled) {
        // Culling only rejects; the arithmetic of an accepted hit is the same.
        EXPECT_EQ(culled->t, hit->t) << where;
        EXPECT_EQ(culled->u, hit->u) << where;
        EXPECT_EQ(culled->v, hit->v) << where;
      }
      if (::testing::Test::HasFailure()) return;
    }
  }
  // Both faces were exercised.
  EXPECT_GT(front_count, kCases / 4);
  EXPECT_LT(front_count, 3 * kCases / 4);
  std::cout << "worst relative t error / absolute u,v error (" << precisionName<T>() << "):\n";
  for (std::size_t mi = 0; mi < kAllTriangleMethods.size(); ++mi) {
    std::cout << "  " << std::setw(16) << toString(kAllTriangleMethods[mi]) << "  " << worst_t[mi]
              << "  " << worst_uv[mi] << "\n";
  }
}

// The hit point from the barycentrics is the ray point at t: the two outputs are consistent.
TYPED_TEST(TriangleRandom, BarycentricsReproduceTheRayPoint) {
  using T = TypeParam;
  Rng rng(7);
  for (int i = 0; i < 2000; ++i) {
    const AimedCase k = makeAimedCase(rng, randomInsideBarycentrics(rng, Tolerance<T>::kMargin));
    const RayT<T> ray = makeRay<T>(k.origin, k.dir);
    const double size = (k.b - k.a).norm() + (k.c - k.a).norm();
    for (const TriangleMethod m : kAllTriangleMethods) {
      const auto hit = hitTriangle<T>(m, ray, k.a, k.b, k.c);
      ASSERT_TRUE(hit) << toString(m) << " case " << i;
      const Vector3d on_ray = k.origin + double(hit->t) * k.dir;
      const Vector3d on_triangle =
          (1 - double(hit->u) - double(hit->v)) * k.a + double(hit->u) * k.b + double(hit->v) * k.c;
      EXPECT_LT((on_ray - on_triangle).norm(), 10 * Tolerance<T>::kUv * size)
          << toString(m) << " case " << i;
    }
    if (::testing::Test::HasFailure()) return;
  }
}

// Rays aimed at points of the plane clearly outside the triangle miss in every method, with or
// without culling.
TYPED_TEST(TriangleRandom, RaysAimedOutsideMiss) {
  using T = TypeParam;
  Rng rng(11);
  for (int i = 0; i < 4000; ++i) {
    const AimedCase k = makeAimedCase(rng, randomOutsideBarycentrics(rng, Tolerance<T>::kMargin));
    const RayT<T> ray = makeRay<T>(k.origin, k.dir);
    for (const TriangleMethod m : kAllTriangleMethods) {
      for (const bool cull : {false, true}) {
        EXPECT_FALSE(hitTriangle<T>(m, ray, k.a, k.b, k.c, cull))
            << toString(m) << " cull " << cull << " case " << i << " "
            << describe("outside", k.a, k.b, k.c, k.origin, k.dir);
      }
    }
    if (::testing::Test::HasFailure()) return;
  }
}

// The watertight test of a ray made from a kept shear of its direction (PreparedRay::shearOf, as
// BeamSet keeps a divergent beam's sub-rays') is the test of the ray prepared as usual, bit for bit:
// hits inside, near the edges and outside, directions along every axis of both signs (each
// permutation and swap), culling on and off.
TEST(WatertightShear, AKeptShearTestsAsTheRayPreparedFromItsDirection) {
  using Prepared = PreparedRay<double, TriangleMethod::kWatertight>;
  Rng rng(29);
  const std::array<Vector3d, 6> axes = {Vector3d::UnitX(),  -Vector3d::UnitX(), Vector3d::UnitY(),
                                        -Vector3d::UnitY(), Vector3d::UnitZ(),  -Vector3d::UnitZ()};
  int hits = 0;
  for (int i = 0; i < 6000; ++i) {
    const double margin = i % 3 == 2 ? 0.2 : 1e-9;  // near the edges, or well inside or outside
    AimedCase k = makeAimedCase(rng, i % 2 ? randomInsideBarycentrics(rng, margin)
                                           : randomOutsideBarycentrics(rng, margin));
    if (i % 10 == 0) {
      // Along an axis, at the triangle's centroid.
      k.dir = axes[(i / 10) % 6];
      k.origin = (k.a + k.b + k.c) / 3 - uniform(rng, 0.5, 5) * k.dir;
    }
    // The shear itself: z the direction's largest component, x and y the others in the order
    // that keeps the winding, and the shear mapping the direction to (0, 0, 1).
    const Prepared::Shear shear = Prepared::shearOf(k.dir);
    ASSERT_EQ(shear.kx + shear.ky + shear.kz, 3) << "case " << i;
    ASSERT_TRUE(shear.kx != shear.ky && shear.ky != shear.kz && shear.kx != shear.kz);
    EXPECT_EQ(std::abs(k.dir[shear.kz]), k.dir.cwiseAbs().maxCoeff()) << "case " << i;
    EXPECT_EQ((shear.ky - shear.kx + 3) % 3, k.dir[shear.kz] > 0 ? 1 : 2) << "case " << i;
    EXPECT_NEAR(shear.sz * k.dir[shear.kz], 1.0, 1e-15);
    EXPECT_NEAR(k.dir[shear.kx] - shear.sx * k.dir[shear.kz], 0.0, 1e-15 * k.dir.norm());
    EXPECT_NEAR(k.dir[shear.ky] - shear.sy * k.dir[shear.kz], 0.0, 1e-15 * k.dir.norm());
    for (const bool cull : {false, true}) {
      const RayT<double> ray = makeRay<double>(k.origin, k.dir);
      const Prepared usual(ray, cull);
      const Prepared kept(ray.origin, ray.tmin, cull, Prepared::shearOf(ray.dir));
      const auto a = usual.intersect(k.a, k.b, k.c, 100.0);
      const auto b = kept.intersect(k.a, k.b, k.c, 100.0);
      ASSERT_EQ(a.has_value(), b.has_value()) << "case " << i << " cull " << cull;
      if (!a) continue;
      ++hits;
      EXPECT_EQ(std::memcmp(&*a, &*b, sizeof *a), 0) << "case " << i << " cull " << cull;
    }
  }
  EXPECT_GT(hits, 3000);
}

// A triangle behind the origin (t < tmin = 0) is not hit: the same rays as above, reversed.
TYPED_TEST(TriangleRandom, TrianglesBehindTheOriginMiss) {
  using T = TypeParam;
  Rng rng(13);
  for (int i = 0; i < 3000; ++i) {
    const AimedCase k = makeAimedCase(rng, randomInsideBarycentrics(rng, Tolerance<T>::kMargin));
    const RayT<T> ray = makeRay<T>(k.origin, -k.dir);
    for (const TriangleMethod m : kAllTriangleMethods) {
      EXPECT_FALSE(hitTriangle<T>(m, ray, k.a, k.b, k.c))
          << toString(m) << " case " << i << " "
          << describe("behind", k.a, k.b, k.c, k.origin, -k.dir);
    }
    if (::testing::Test::HasFailure()) return;
  }
}

// [tmin, tmax] limits the hit: a window clearly before or after t misses, one around t hits, and
// the limits are inclusive (tmin = t or tmax = t exactly still hits, with the same t).
TYPED_TEST(TriangleRandom, TminTmaxLimitTheHit) {
  using T = TypeParam;
  // Well above the t tolerance, so that the verdict is not decided by rounding.
  const double margin = 100 * Tolerance<T>::kT;
  Rng rng(17);
  for (int i = 0; i < 2000; ++i) {
    const AimedCase k = makeAimedCase(rng, randomInsideBarycentrics(rng, Tolerance<T>::kMargin));
    for (const TriangleMethod m : kAllTriangleMethods) {
      const std::string where = std::string(toString(m)) + " case " + std::to_string(i);
      auto hits = [&](double tmin, double tmax) {
        return hitTriangle<T>(m, makeRay<T>(k.origin, k.dir, tmin, tmax), k.a, k.b, k.c);
      };
      EXPECT_FALSE(hits(0, k.t * (1 - margin))) << where;
      EXPECT_FALSE(hits(k.t * (1 + margin), kInf)) << where;
      EXPECT_TRUE(hits(k.t * (1 - margin), k.t * (1 + margin))) << where;
      const auto free_hit = hits(0, kInf);
      ASSERT_TRUE(free_hit) << where;
      const auto at_tmax = hits(0, free_hit->t);
      const auto at_tmin = hits(free_hit->t, free_hit->t);
      ASSERT_TRUE(at_tmax) << "tmax == t must hit, " << where;
      ASSERT_TRUE(at_tmin) << "tmin == tmax == t must hit, " << where;
      EXPECT_EQ(at_tmax->t, free_hit->t) << where;
      EXPECT_EQ(at_tmin->t, free_hit->t) << where;
    }
    if (::testing::Test::HasFailure()) return;
  }
}

// Rays exactly parallel to the plane miss, including rays lying in the plane and crossing the
// triangle. The plane is a coordinate plane and the direction has an exact 0 along its normal, so
// the plane-based methods' denominators are exactly 0; watertight sees the triangle edge-on, with
// edge functions of mixed signs (or all zero, then det = 0).
TYPED_TEST(TriangleRandom, RaysParallelToThePlaneMiss) {
  using T = TypeParam;
  Rng rng(19);
  for (int i = 0; i < 3000; ++i) {
    const int axis = i % 3;
    const double scale = logUniform(rng, -3, 3);
    const double plane = uniform(rng, -2, 2) * scale;
    Vector3d a, b, c;
    randomWellShapedTriangle(rng, Vector3d::Zero(), scale, &a, &b, &c);
    a[axis] = b[axis] = c[axis] = plane;
    if (isDegenerateTriangle(a, b, c)) continue;
    const Eigen::Vector2d uv = randomInsideBarycentrics(rng, 0.01);
    const Vector3d target = (1 - uv[0] - uv[1]) * a + uv[0] * b + uv[1] * c;
    Vector3d dir = randomUnitVector(rng) * logUniform(rng, -2, 2);
    dir[axis] = 0;
    // In the plane, through the triangle; or off the plane by a random offset.
    const double offset = (i / 3) % 2 == 0 ? 0.0 : uniform(rng, -1, 1) * scale;
    Vector3d origin = target - uniform(rng, 0.5, 5) * dir;
    origin[axis] = plane + offset;
    const RayT<T> ray = makeRay<T>(origin, dir);
    ASSERT_EQ(ray.dir[axis], T(0));
    for (const TriangleMethod m : kAllTriangleMethods) {
      for (const bool cull : {false, true}) {
        EXPECT_FALSE(hitTriangle<T>(m, ray, a, b, c, cull))
            << toString(m) << " cull " << cull << " case " << i << " "
            << describe("parallel", a, b, c, origin, dir);
      }
    }
    if (::testing::Test::HasFailure()) return;
  }
}

// Every method gives the same hit/miss verdict as a long double evaluation of the exact inputs, for
// random rays (hits and misses both common) that are not within a small margin of an edge, not
// grazing the plane and not starting next to it.
TYPED_TEST(TriangleRandom, MethodsAgreeAwayFromEdges) {
  using T = TypeParam;
  using L = long double;
  using Vec3L = Eigen::Matrix<L, 3, 1>;
  Rng rng(23);
  int checked = 0, expected_hits = 0;
  constexpr int kCases = 20000;
  for (int i = 0; i < kCases; ++i) {
    const double scale = logUniform(rng, -3, 3);
    const Vector3d center = uniformInCube(rng, 2 * scale);
    Vector3d a, b, c;
    randomWellShapedTriangle(rng, center, scale, &a, &b, &c);
    // Aim near the triangle (about a third of the aimed points are inside it), off the plane by up
    // to a fifth of its size; reverse one ray in five so that the triangle is behind the origin.
    const Vector3d origin = center + uniformInCube(rng, 4 * scale);
    const double u_aim = uniform(rng, -0.3, 1), v_aim = uniform(rng, -0.3, 1);
    const Vector3d target =
        (1 - u_aim - v_aim) * a + u_aim * b + v_aim * c + uniformInCube(rng, 0.2 * scale);
    const double sign = i % 5 == 0 ? -1 : 1;
    const Vector3d dir = sign * (target - origin) * logUniform(rng, -2, 2);
    const RayT<T> ray = makeRay<T>(origin, dir);
    const Vec3<T> at = a.cast<T>(), bt = b.cast<T>(), ct = c.cast<T>();

    // The truth for the inputs as the method sees them (rounded to T), in long double.
    const Vec3L al = at.template cast<L>(), bl = bt.template cast<L>(), cl = ct.template cast<L>();
    const Vec3L ol = ray.origin.template cast<L>(), dl = ray.dir.template cast<L>();
    const Vec3L n = (bl - al).cross(cl - al);
    const L denom = n.dot(dl);
    if (std::abs(denom) < 0.05L * n.norm() * dl.norm()) continue;  // grazing
    const L t = n.dot(al - ol) / denom;
    const Vec3L p = ol + t * dl;
    const L u = n.dot((p - al).cross(cl - al)) / n.squaredNorm();
    const L v = n.dot((bl - al).cross(p - al)) / n.squaredNorm();
    const L w = 1 - u - v;
    const L margin = Tolerance<T>::kMargin;
    if (std::min({std::abs(u), std::abs(v), std::abs(w)}) < margin) continue;  // near an edge
    if (std::abs(t) * dl.norm() < margin * scale) continue;  // origin next to the plane
    const bool expected = t >= 0 && u >= 0 && v >= 0 && w >= 0;
    ++checked;
    expected_hits += expected;
    for (const TriangleMethod m : kAllTriangleMethods) {
      EXPECT_EQ(intersectTriangle(m, ray, at, bt, ct).has_value(), expected)
          << toString(m) << " case " << i << " " << describe("agree", a, b, c, origin, dir);
    }
    if (::testing::Test::HasFailure()) return;
  }
  EXPECT_GT(checked, kCases / 2);
  EXPECT_GT(expected_hits, checked / 10);
  EXPECT_LT(expected_hits, checked * 9 / 10);
}

// NaN or Inf in one coordinate of an otherwise hitting ray or triangle: no hit, for random
// geometry (the literal test below pins one configuration; here the zeros that turn Inf into NaN
// by luck are mostly absent).
TYPED_TEST(TriangleRandom, NonFiniteInputNeverHits) {
  using T = TypeParam;
  Rng rng(37);
  const double bad_values[] = {std::numeric_limits<double>::quiet_NaN(), kInf, -kInf};
  for (int i = 0; i < 300; ++i) {
    const AimedCase k = makeAimedCase(rng, randomInsideBarycentrics(rng, Tolerance<T>::kMargin));
    for (const double bad : bad_values) {
      for (int slot = 0; slot < 15; ++slot) {
        // slot / 3 picks a, b, c, origin or dir; slot % 3 the coordinate.
        Vector3d v[5] = {k.a, k.b, k.c, k.origin, k.dir};
        v[slot / 3][slot % 3] = bad;
        const RayT<T> ray = makeRay<T>(v[3], v[4]);
        for (const TriangleMethod m : kAllTriangleMethods) {
          for (const bool cull : {false, true}) {
            EXPECT_FALSE(hitTriangle<T>(m, ray, v[0], v[1], v[2], cull))
                << toString(m) << " cull " << cull << " case " << i << " value " << bad
                << " in slot " << slot;
          }
        }
      }
    }
    if (::testing::Test::HasFailure()) return;
  }
}

// The compile-time entry point intersectTriangle<M> and the run-time one give identical results.
TYPED_TEST(TriangleRandom, TemplateAndRuntimeEntryPointsAgree) {
  using T = TypeParam;
  Rng rng(29);
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector2d uv(uniform(rng, -0.5, 1.5), uniform(rng, -0.5, 1.5));
    const AimedCase k = makeAimedCase(rng, uv);
    const RayT<T> ray = makeRay<T>(k.origin, k.dir);
    const Vec3<T> a = k.a.cast<T>(), b = k.b.cast<T>(), c = k.c.cast<T>();
    for (const bool cull : {false, true}) {
      const std::optional<TriangleHitT<T>> by_template[] = {
          intersectTriangle<TriangleMethod::kSeedPlane>(ray, a, b, c, cull),
          intersectTriangle<TriangleMethod::kSeedUv>(ray, a, b, c, cull),
          intersectTriangle<TriangleMethod::kCramer>(ray, a, b, c, cull),
          intersectTriangle<TriangleMethod::kMollerTrumbore>(ray, a, b, c, cull),
          intersectTriangle<TriangleMethod::kWatertight>(ray, a, b, c, cull)};
      for (std::size_t mi = 0; mi < kAllTriangleMethods.size(); ++mi) {
        const auto by_runtime = intersectTriangle(kAllTriangleMethods[mi], ray, a, b, c, cull);
        ASSERT_EQ(by_runtime.has_value(), by_template[mi].has_value()) << mi << " case " << i;
        if (by_runtime) {
          EXPECT_EQ(by_runtime->t, by_template[mi]->t);
          EXPECT_EQ(by_runtime->u, by_template[mi]->u);
          EXPECT_EQ(by_runtime->v, by_template[mi]->v);
        }
      }
    }
  }
}

}  // namespace
}  // namespace laser_raycast_test
