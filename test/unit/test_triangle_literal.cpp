// The triangle methods on literal cases: limits, culling, bad input, regressions, worked examples.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
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

template <typename T>
class TriangleLiteral : public ::testing::Test {};
TYPED_TEST_SUITE(TriangleLiteral, Precisions, PrecisionNames);

// Integer geometry where every method computes t = 2 exactly, so the limits can be probed at the
// neighbouring representable values.
TYPED_TEST(TriangleLiteral, LimitsAreInclusiveToTheLastBit) {
  using T = TypeParam;
  const Vector3d a(0, 0, 0), b(4, 0, 0), c(0, 4, 0), origin(1, 1, -2), dir(0, 0, 1);
  const double below = std::nextafter(T(2), T(0)), above = std::nextafter(T(2), T(3));
  for (const TriangleMethod m : kAllTriangleMethods) {
    auto hit = [&](double tmin, double tmax) {
      return hitTriangle<T>(m, makeRay<T>(origin, dir, tmin, tmax), a, b, c);
    };
    ASSERT_TRUE(hit(0, kInf)) << toString(m);
    EXPECT_EQ(hit(0, kInf)->t, T(2)) << toString(m);
    EXPECT_EQ(hit(0, kInf)->u, T(0.25)) << toString(m);
    EXPECT_EQ(hit(0, kInf)->v, T(0.25)) << toString(m);
    EXPECT_TRUE(hit(0, 2)) << toString(m);
    EXPECT_TRUE(hit(2, 2)) << toString(m);
    EXPECT_TRUE(hit(2, kInf)) << toString(m);
    EXPECT_FALSE(hit(0, below)) << toString(m);
    EXPECT_FALSE(hit(above, kInf)) << toString(m);
  }
}

// The front face is the side (b - a) x (c - a) points to. Culling rejects the ray that sees the
// back (dir . n > 0) and keeps the one that sees the front; without culling both hit.
TYPED_TEST(TriangleLiteral, BackfaceCullingFollowsTheWinding) {
  using T = TypeParam;
  const Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);  // front normal +z
  const Vector3d below(0.25, 0.25, -1), above(0.25, 0.25, 1);
  for (const TriangleMethod m : kAllTriangleMethods) {
    const RayT<T> sees_back = makeRay<T>(below, Vector3d(0, 0, 1));
    const RayT<T> sees_front = makeRay<T>(above, Vector3d(0, 0, -1));
    EXPECT_TRUE(hitTriangle<T>(m, sees_back, a, b, c, false)) << toString(m);
    EXPECT_TRUE(hitTriangle<T>(m, sees_front, a, b, c, false)) << toString(m);
    EXPECT_FALSE(hitTriangle<T>(m, sees_back, a, b, c, true)) << toString(m);
    EXPECT_TRUE(hitTriangle<T>(m, sees_front, a, b, c, true)) << toString(m);
    // Reversing the winding swaps the faces.
    EXPECT_TRUE(hitTriangle<T>(m, sees_back, a, c, b, true)) << toString(m);
    EXPECT_FALSE(hitTriangle<T>(m, sees_front, a, c, b, true)) << toString(m);
    // Rotating the vertex order keeps them.
    EXPECT_FALSE(hitTriangle<T>(m, sees_back, b, c, a, true)) << toString(m);
    EXPECT_TRUE(hitTriangle<T>(m, sees_front, c, a, b, true)) << toString(m);
  }
}

// Zero-area triangles (a repeated vertex, or three exactly collinear points) never hit: not for
// rays through the segment, along it, or anywhere else, and without NaN or crash.
TYPED_TEST(TriangleLiteral, DegenerateTrianglesNeverHit) {
  using T = TypeParam;
  const std::vector<std::array<Vector3d, 3>> triangles = {
      {Vector3d(0, 0, 0), Vector3d(1, 1, 1), Vector3d(2, 2, 2)},
      {Vector3d(0, 0, 0), Vector3d(1, 2, 3), Vector3d(3, 6, 9)},
      {Vector3d(3, 6, 9), Vector3d(0, 0, 0), Vector3d(1, 2, 3)},
      // On an axis, the middle point first.
      {Vector3d(1, 0, 0), Vector3d(0, 0, 0), Vector3d(-2, 0, 0)},
      // A repeated vertex, in each position.
      {Vector3d(0, 0, 0), Vector3d(0, 0, 0), Vector3d(1, 1, 0)},
      {Vector3d(0, 0, 0), Vector3d(1, 1, 0), Vector3d(1, 1, 0)},
      {Vector3d(1, 1, 0), Vector3d(0, 0, 0), Vector3d(1, 1, 0)},
      // All three the same point.
      {Vector3d(0.5, 0.5, 0.5), Vector3d(0.5, 0.5, 0.5), Vector3d(0.5, 0.5, 0.5)},
  };
  Rng rng(31);
  for (const auto& tri : triangles) {
    const Vector3d &a = tri[0], &b = tri[1], &c = tri[2];
    ASSERT_TRUE(isDegenerateTriangle<T>(a.cast<T>(), b.cast<T>(), c.cast<T>()));
    // Targets on the segment (the vertices, midpoints, and random points between the extremes).
    std::vector<Vector3d> targets = {a, b, c, (a + b) / 2, (b + c) / 2, (a + c) / 2};
    for (int i = 0; i < 20; ++i) {
      const double s = uniform(rng, 0, 1);
      targets.push_back((1 - s) * a + s * c);
      targets.push_back((1 - s) * a + s * b);
    }
    std::vector<std::pair<Vector3d, Vector3d>> rays;  // origin, dir
    for (const Vector3d& target : targets) {
      for (int i = 0; i < 10; ++i) {
        const Vector3d dir = randomUnitVector(rng);
        rays.emplace_back(target - 3 * dir, dir);
      }
      rays.emplace_back(target - Vector3d(0, 0, 1), Vector3d(0, 0, 1));  // axis-aligned
      rays.emplace_back(target - Vector3d(1, 0, 0), Vector3d(1, 0, 0));
    }
    // Along the line of the segment, both ways, and a ray starting on it.
    const Vector3d line = (a - b).norm() > (a - c).norm() ? (a - b) : (a - c);
    rays.emplace_back(a - 5 * line, line);
    rays.emplace_back(a + 5 * line, -line);
    rays.emplace_back(a, Vector3d(0, 1, 0));
    for (int i = 0; i < 50; ++i) {
      rays.emplace_back(uniformInCube(rng, 5), randomUnitVector(rng));
    }

    for (const auto& r : rays) {
      const RayT<T> ray = makeRay<T>(r.first, r.second);
      for (const TriangleMethod m : kAllTriangleMethods) {
        for (const bool cull : {false, true}) {
          EXPECT_FALSE(hitTriangle<T>(m, ray, a, b, c, cull))
              << toString(m) << " cull " << cull << " "
              << describe("degenerate", a, b, c, r.first, r.second);
        }
      }
      if (::testing::Test::HasFailure()) return;
    }
  }
}

// NaN or Inf in any vertex coordinate, the origin or the direction, a zero direction, or a NaN
// limit: no hit in any method (the base ray hits, so each miss is caused by the bad value).
TYPED_TEST(TriangleLiteral, NonFiniteInputNeverHits) {
  using T = TypeParam;
  const Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  const Vector3d origin(0.25, 0.25, -1), dir(0, 0, 1);
  for (const TriangleMethod m : kAllTriangleMethods) {
    ASSERT_TRUE(hitTriangle<T>(m, makeRay<T>(origin, dir), a, b, c)) << toString(m);
  }
  auto expectNoHit = [&](const std::string& what, const Vector3d& a2, const Vector3d& b2,
                         const Vector3d& c2, const RayT<T>& ray) {
    for (const TriangleMethod m : kAllTriangleMethods) {
      for (const bool cull : {false, true}) {
        const auto hit = hitTriangle<T>(m, ray, a2, b2, c2, cull);
        EXPECT_FALSE(hit) << toString(m) << " cull " << cull << ": " << what
                          << " gave t = " << (hit ? double(hit->t) : 0.0);
      }
    }
  };
  for (const double bad : {kNaN, kInf, -kInf}) {
    for (int k = 0; k < 3; ++k) {
      const std::string value = std::to_string(bad) + " in component " + std::to_string(k);
      Vector3d bad_vector = a;
      bad_vector[k] = bad;
      expectNoHit("vertex a " + value, bad_vector, b, c, makeRay<T>(origin, dir));
      bad_vector = b;
      bad_vector[k] = bad;
      expectNoHit("vertex b " + value, a, bad_vector, c, makeRay<T>(origin, dir));
      bad_vector = c;
      bad_vector[k] = bad;
      expectNoHit("vertex c " + value, a, b, bad_vector, makeRay<T>(origin, dir));
      bad_vector = origin;
      bad_vector[k] = bad;
      expectNoHit("origin " + value, a, b, c, makeRay<T>(bad_vector, dir));
      bad_vector = dir;
      bad_vector[k] = bad;
      expectNoHit("dir " + value, a, b, c, makeRay<T>(origin, bad_vector));
    }
  }
  expectNoHit("zero dir", a, b, c, makeRay<T>(origin, Vector3d::Zero()));
  expectNoHit("NaN tmin", a, b, c, makeRay<T>(origin, dir, kNaN, kInf));
  expectNoHit("NaN tmax", a, b, c, makeRay<T>(origin, dir, 0, kNaN));
}

// Regression: watertight hit every triangle its line crossed at t = 0 when the direction had an
// infinite component (the shear's scale 1 / dir[kz] became 0, so t = 0). Fixed by treating an
// invalid ray (isValidRay false) as one with tmin = NaN, in PreparedRay itself so that the BVH path
// is covered too.
TYPED_TEST(TriangleLiteral, WatertightInfiniteDirectionRegression) {
  using T = TypeParam;
  const Vec3<T> a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  const T inf = std::numeric_limits<T>::infinity();
  for (const Vec3<T>& dir : {Vec3<T>(0, 0, inf), Vec3<T>(0, 0, -inf), Vec3<T>(0.1f, 0.2f, inf)}) {
    RayT<T> ray;
    ray.origin = Vec3<T>(0.25, 0.25, dir.z() > 0 ? -1 : 1);
    ray.dir = dir;
    EXPECT_FALSE(intersectTriangle<TriangleMethod::kWatertight>(ray, a, b, c)) << dir.transpose();
    EXPECT_FALSE(intersectTriangle<TriangleMethod::kWatertight>(ray, a, b, c, true))
        << dir.transpose();
    const PreparedRay<T, TriangleMethod::kWatertight> prepared(ray, false);
    EXPECT_FALSE(prepared.intersect(a, b, c, inf)) << dir.transpose();
  }
}

// Regression: a hit is always finite. A triangle 1e300 (1e30 in float) away along a direction of
// length 1e-10 lies at t = 1e310 (1e40), beyond the largest finite value: every method computed
// t = +Inf, and with tmax = +Inf (the Ray default) reported it as a hit. The true t cannot be
// represented, so there is no hit to report; with the triangle near, the same ray still hits.
TYPED_TEST(TriangleLiteral, HitBeyondTheLargestFiniteTIsNoHitRegression) {
  using T = TypeParam;
  const double far = std::is_same<T, float>::value ? 1e30 : 1e300;
  const Vector3d dir(1e-10, 0, 0);
  for (const double x : {far, -far}) {
    const Vector3d a(x, -1, -1), b(x, 1, -1), c(x, 0, 2);
    const Vector3d origin(0, 0, 0);
    const RayT<T> ray = makeRay<T>(origin, x > 0 ? dir : Vector3d(-dir), 0, kInf);
    for (const TriangleMethod m : kAllTriangleMethods) {
      for (const bool cull : {false, true}) {
        const auto hit = hitTriangle<T>(m, ray, a, b, c, cull);
        EXPECT_FALSE(hit) << toString(m) << " cull " << cull << " x " << x
                          << ": t = " << (hit ? double(hit->t) : 0.0);
      }
      // The reverse winding, which the cull flag treats as the front face.
      const auto reversed = hitTriangle<T>(m, ray, a, c, b, true);
      EXPECT_FALSE(reversed) << toString(m) << " reversed, x " << x;
      // Nearer, the same ray hits (t = 1e10 exactly representable in double; checked in range).
      const Vector3d near_a(1, -1, -1), near_b(1, 1, -1), near_c(1, 0, 2);
      const auto near = hitTriangle<T>(m, makeRay<T>(origin, dir), near_a, near_b, near_c);
      ASSERT_TRUE(near) << toString(m);
      EXPECT_NEAR(double(near->t), 1e10, 1e10 * Tolerance<T>::kT) << toString(m);
    }
  }
}

// Regression (found by test/fuzz/fuzz_core): an edge function whose exact value is below the
// smallest subnormal (here about -1e-460 in double, -1e-50 in float) underflowed to -0, and the
// watertight test took the ray, which passes outside the triangle, for one exactly on its edge and
// hit. The triangle lies in x = 0, one edge 1e-160 (1e-20) long, the third vertex 1e300 (1e30)
// away; the ray is nearly parallel to that plane and crosses it at t = 0, at the origin.
TYPED_TEST(TriangleLiteral, WatertightEdgeFunctionUnderflowRegression) {
  using T = TypeParam;
  const bool is_float = std::is_same<T, float>::value;
  const double small = is_float ? 1e-20 : 1e-160, large = is_float ? 1e30 : 1e300;
  const Vector3d a(0, 0, 0), b(0, small, 0), c(0, -4, large),
      dir(-4, 0, 1.0568661007955367 * large);
  const auto hit = [&](const Vector3d& origin) {
    return hitTriangle<T>(TriangleMethod::kWatertight, makeRay<T>(origin, dir, -1, 1), a, b, c);
  };
  // Below the triangle (z < 0, and the triangle has z >= 0): the case that hit.
  EXPECT_FALSE(hit(Vector3d(0, small, -0.5)));
  // Beside its short edge, on either side.
  EXPECT_FALSE(hit(Vector3d(0, 1.5 * small, 0.5)));
  EXPECT_FALSE(hit(Vector3d(0, -0.5 * small, 0.5)));
  // Inside it, near that edge: a hit. (Its t, 0 in exact arithmetic, is not asserted: every term
  // of t's numerator underflows here.)
  EXPECT_TRUE(hit(Vector3d(0, 0.5 * small, 0.5)));
}

// Regression (found by test/fuzz/fuzz_core): a vertex about half the largest value from the ray
// made the edge functions so large that det = ea + eb + ec overflowed to +Inf; t = scaled_t / det
// came out -0, and a ray over [0, 0] hit a triangle whose true t is -0.19. Scaling the edge
// functions (detail::rescaledHit) gives the true t. The numbers are the fuzzer's (double), with the
// large ones taken relative to the largest value so that float overflows the same way.
TYPED_TEST(TriangleLiteral, WatertightDetOverflowRegression) {
  using T = TypeParam;
  const double max = std::numeric_limits<T>::max();
  const Vector3d a(-0.5, -5.9438276512801007, 3.5), b(1.6449181260460009, 0, 0),
      c(1, 0.5251521 * max, 0);
  const Vector3d origin(0, 3.6444008742688023, -0.19068 * max), dir(-3.5, -4, -max);
  const auto hit = [&](double tmin, double tmax) {
    return hitTriangle<T>(TriangleMethod::kWatertight, makeRay<T>(origin, dir, tmin, tmax), a, b,
                          c);
  };
  const auto at_origin = hit(0, 0);
  EXPECT_FALSE(at_origin) << "t = " << (at_origin ? double(at_origin->t) : 0.0);
  // The triangle's z (0 to 3.5) is nothing beside the origin's, so the true t is -origin.z / dir.z
  // (the float shear, with 1 / dir.z subnormal, keeps a few digits fewer).
  const auto found = hit(-1, 1);
  ASSERT_TRUE(found);
  const double tolerance = std::is_same<T, float>::value ? 1e-4 : 1e-12;
  EXPECT_NEAR(double(found->t), -0.19068, tolerance);
  EXPECT_GE(found->u, 0);
  EXPECT_GE(found->v, 0);
  EXPECT_LE(found->u + found->v, 1);
  EXPECT_FALSE(hit(-0.1, 1));
}

// The ray-plane worked example of docs/design.md §6.4: plane [1 0 0 -7], R0 = [2 3 4],
// Rd = [0.577 0.577 0.577] give Vd = 0.577, V0 = 5, t = 8.66 and Pi = [7 8 9]; "Vd > 0: the plane
// points away from the ray", so the ray-facing normal is [-1 0 0]. (Its source says "x = -7";
// [1 0 0 -7] is the plane x = 7, as its numbers show.)
TYPED_TEST(TriangleLiteral, RayPlaneWorkedExample) {
  using T = TypeParam;
  // The example's own arithmetic.
  const Eigen::Vector4d plane(1, 0, 0, -7);
  const Vector3d pn = plane.head<3>();
  const Vector3d r0(2, 3, 4), rd(0.577, 0.577, 0.577);
  const double vd = pn.dot(rd);
  const double v0 = -(pn.dot(r0) + plane[3]);
  const double t = v0 / vd;
  EXPECT_DOUBLE_EQ(vd, 0.577);
  EXPECT_DOUBLE_EQ(v0, 5.0);
  // 5 / 0.577 = 8.6655...: the example truncates to its 3 digits.
  EXPECT_EQ(std::trunc(t * 100) / 100, 8.66);
  EXPECT_GT(vd, 0);  // the plane faces away from the ray
  const Vector3d pi = r0 + t * rd;
  EXPECT_NEAR((pi - Vector3d(7, 8, 9)).norm(), 0, 1e-12);

  // A large triangle in the plane x = 7 around Pi, front normal +x = Pn.
  const Vector3d a(7, -100, -100), b(7, 100, -100), c(7, 0, 200);
  ASSERT_GT((b - a).cross(c - a).normalized().dot(pn), 0.999);
  // Precision of the result: double to ~1e-14; float inputs (0.577f) carry 2^-24 relative, which
  // t = 5 / 0.577 and Pi inherit at the scale of |R0| ~ 10.
  const double tol = std::is_same<T, double>::value ? 1e-12 : 1e-5;
  const RayT<T> ray = makeRay<T>(r0, rd);
  for (const TriangleMethod m : kAllTriangleMethods) {
    const auto hit = hitTriangle<T>(m, ray, a, b, c);
    ASSERT_TRUE(hit) << toString(m);
    EXPECT_NEAR(hit->t, 5.0 / 0.577, tol * 10) << toString(m);
    EXPECT_EQ(std::trunc(hit->t * 100) / 100, T(8.66)) << toString(m);
    const Vec3<T> on_ray = ray.origin + hit->t * ray.dir;
    EXPECT_NEAR((on_ray.template cast<double>() - Vector3d(7, 8, 9)).norm(), 0, tol * 10)
        << toString(m);
    const Vector3d on_triangle =
        (1 - double(hit->u) - double(hit->v)) * a + double(hit->u) * b + double(hit->v) * c;
    EXPECT_NEAR((on_triangle - Vector3d(7, 8, 9)).norm(), 0, tol * 100) << toString(m);

    // Vd > 0 means the ray sees the back of a triangle whose front normal is Pn = +x: culled.
    EXPECT_FALSE(hitTriangle<T>(m, ray, a, b, c, /*cull=*/true)) << toString(m);
    // With the winding reversed the front normal is -x, facing the ray: kept, same t.
    const auto reversed = hitTriangle<T>(m, ray, a, c, b, /*cull=*/true);
    ASSERT_TRUE(reversed) << toString(m);
    EXPECT_EQ(reversed->t, hitTriangle<T>(m, ray, a, c, b)->t) << toString(m);
    EXPECT_NEAR(reversed->t, 5.0 / 0.577, tol * 10) << toString(m);
  }
  // "Must reverse normal so it is N = [-1 0 0]": the ray-facing normal is -sign(Vd) Pn.
  const Vector3d front = (b - a).cross(c - a).normalized();
  const Vector3d facing = front.dot(rd) > 0 ? Vector3d(-front) : front;
  EXPECT_NEAR((facing - Vector3d(-1, 0, 0)).norm(), 0, 1e-15);
}

// seed_uv's source prints v's numerator as (AB.AS)(AB.AC) - (AB.AB)(AC.AS), the negative of
// Cramer's rule for AS = u AB + v AC (docs/design.md §6.2). seed_uv uses the corrected sign. Here
// AB = (2,0,0), AC = (1,2,0) and the hit S = (1,1,0) has u = 0.25, v = 0.5; the printed sign would
// give v = -0.5 and reject the hit.
TYPED_TEST(TriangleLiteral, SeedUvUsesTheCorrectedSignOfV) {
  using T = TypeParam;
  const Vector3d a(0, 0, 0), b(2, 0, 0), c(1, 2, 0), s(1, 1, 0);
  // The printed formula, written out, really does fail here.
  const Vector3d ab = b - a, ac = c - a, as = s - a;
  const double denom = ab.dot(ab) * ac.dot(ac) - ab.dot(ac) * ab.dot(ac);
  const double v_seed = (ab.dot(as) * ab.dot(ac) - ab.dot(ab) * ac.dot(as)) / denom;
  EXPECT_EQ(v_seed, -0.5);

  for (const Vector3d& dir : {Vector3d(0, 0, 1), Vector3d(0.3, -0.2, 1), Vector3d(0, 0, -1)}) {
    const RayT<T> ray = makeRay<T>(s - 2 * dir, dir);
    const auto hit = hitTriangle<T>(TriangleMethod::kSeedUv, ray, a, b, c);
    ASSERT_TRUE(hit) << dir.transpose();
    EXPECT_NEAR(hit->u, 0.25, 1e-6) << dir.transpose();
    EXPECT_NEAR(hit->v, 0.5, 1e-6) << dir.transpose();
    EXPECT_NEAR(hit->t, 2.0, 1e-6) << dir.transpose();
    // And it agrees with every other method.
    for (const TriangleMethod m : kAllTriangleMethods) {
      const auto other = hitTriangle<T>(m, ray, a, b, c);
      ASSERT_TRUE(other) << toString(m);
      EXPECT_NEAR(other->u, hit->u, 1e-6) << toString(m);
      EXPECT_NEAR(other->v, hit->v, 1e-6) << toString(m);
    }
  }
  // A point with u = 0.1, v = 0.8 near the edge BC: the printed sign gives v < 0 as well.
  const Vector3d s2 = 0.1 * b + 0.8 * c;
  const auto hit2 = hitTriangle<T>(TriangleMethod::kSeedUv,
                                   makeRay<T>(s2 + Vector3d(0, 0, 3), Vector3d(0, 0, -1)), a, b, c);
  ASSERT_TRUE(hit2);
  EXPECT_NEAR(hit2->u, 0.1, 1e-6);
  EXPECT_NEAR(hit2->v, 0.8, 1e-6);
}

}  // namespace
}  // namespace laser_raycast_test
