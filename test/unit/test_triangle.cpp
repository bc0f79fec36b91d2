// The five ray/triangle intersectors of triangle.h, in double and float, against constructed truth:
// hits at known (t, u, v), misses by construction, the conventions every method shares (inclusive
// [tmin, tmax], front face and culling, degenerate triangles, non-finite input), agreement between
// the methods, and the worked examples of docs/design.md §6.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <limits>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "laser_raycast/core/triangle.h"
#include "random.h"
#include "test_geometry.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;
using Eigen::Vector3d;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Tolerances per precision. The random cases below keep the geometry well conditioned: triangles
// with no tiny angle, the origin 0.2 to 5 triangle sizes from the hit, the ray at least 17 degrees
// off the plane (|cos| >= 0.3 to the normal), the triangle centre within 2 sizes of the world
// origin. Under those bounds:
// - double: the constructed truth and the methods carry ~1e-15 relative rounding, amplified at most
//   ~100x (the worst seen is ~3e-14); 1e-9 is far above that and far below any formula error,
//   which is O(1).
// - float: the inputs are rounded to float (2^-24 relative), which moves the true hit by up to
//   ~1e-5 relative to the triangle size; float arithmetic adds the same order (the worst seen is
//   ~9e-6). 1e-3 holds with margin and still catches a wrong formula.
// kMargin is how far (in barycentrics) a constructed hit stays inside the edges, and a constructed
// miss outside them, so that the verdict is not decided by rounding.
template <typename T>
struct Tolerance;
template <>
struct Tolerance<double> {
  static constexpr double kT = 1e-9;   // relative, on t
  static constexpr double kUv = 1e-9;  // absolute, on u and v
  static constexpr double kMargin = 1e-6;
};
template <>
struct Tolerance<float> {
  static constexpr double kT = 1e-3;
  static constexpr double kUv = 1e-3;
  static constexpr double kMargin = 1e-3;
};

template <typename T>
RayT<T> makeRay(const Vector3d& origin, const Vector3d& dir, double tmin = 0, double tmax = kInf) {
  RayT<T> ray;
  ray.origin = origin.cast<T>();
  ray.dir = dir.cast<T>();
  ray.tmin = static_cast<T>(tmin);
  ray.tmax = static_cast<T>(tmax);
  return ray;
}

template <typename T>
std::optional<TriangleHitT<T>> hitTriangle(TriangleMethod method, const RayT<T>& ray,
                                           const Vector3d& a, const Vector3d& b, const Vector3d& c,
                                           bool cull = false) {
  const Vec3<T> at = a.cast<T>(), bt = b.cast<T>(), ct = c.cast<T>();
  return intersectTriangle(method, ray, at, bt, ct, cull);
}

template <typename T>
const char* precisionName() {
  return std::is_same<T, double>::value ? "double" : "float";
}

std::string describe(const char* what, const Vector3d& a, const Vector3d& b, const Vector3d& c,
                     const Vector3d& origin, const Vector3d& dir) {
  std::ostringstream s;
  s << std::setprecision(17) << what << ": a = " << a.transpose() << ", b = " << b.transpose()
    << ", c = " << c.transpose() << ", origin = " << origin.transpose()
    << ", dir = " << dir.transpose();
  return s.str();
}

// A random triangle with no tiny angle (|n| >= 0.1 * longest edge^2), vertices in a cube of
// half-size `size` around `center`.
void randomWellShapedTriangle(Rng& rng, const Vector3d& center, double size, Vector3d* a,
                              Vector3d* b, Vector3d* c) {
  for (;;) {
    *a = center + uniformInCube(rng, size);
    *b = center + uniformInCube(rng, size);
    *c = center + uniformInCube(rng, size);
    const double longest =
        std::max({(*b - *a).squaredNorm(), (*c - *b).squaredNorm(), (*a - *c).squaredNorm()});
    if ((*b - *a).cross(*c - *a).norm() >= 0.1 * longest) return;
  }
}

// A ray aimed at the point with barycentrics (u, v) of a random triangle (u, v may lie outside the
// triangle), from 0.2 to 5 triangle sizes away, along a random direction at least 17 degrees off
// the plane. The whole scene (triangle size, its offset from the world origin, the distance) has a
// random scale in 1e-3..1e3, and |dir| one in 1e-2..1e2.
struct AimedCase {
  Vector3d a, b, c, origin, dir;
  double t;     // where the ray meets the plane, in units of |dir|
  double u, v;  // barycentrics of the aimed point
  bool front;   // the ray sees the front face: dir . ((b - a) x (c - a)) < 0
};

AimedCase makeAimedCase(Rng& rng, const Eigen::Vector2d& uv) {
  AimedCase k;
  const double scale = logUniform(rng, -3, 3);
  const Vector3d center = uniformInCube(rng, 2 * scale);
  randomWellShapedTriangle(rng, center, scale, &k.a, &k.b, &k.c);
  k.u = uv[0];
  k.v = uv[1];
  const Vector3d p = (1 - k.u - k.v) * k.a + k.u * k.b + k.v * k.c;
  const Vector3d n = (k.b - k.a).cross(k.c - k.a).normalized();
  Vector3d w;
  do {
    w = randomUnitVector(rng);
  } while (std::abs(w.dot(n)) < 0.3);
  const double dist = scale * uniform(rng, 0.2, 5.0);
  const double dir_scale = logUniform(rng, -2, 2);  // t is in units of |dir|
  k.origin = p - dist * w;
  k.dir = dir_scale * w;
  k.t = dist / dir_scale;
  k.front = w.dot(n) < 0;
  return k;
}

// Barycentrics uniform over the part of the triangle at least `margin` inside every edge.
Eigen::Vector2d randomInsideBarycentrics(Rng& rng, double margin) {
  for (;;) {
    const Eigen::Vector2d uv = randomBarycentrics(rng);
    if (std::min({uv[0], uv[1], 1 - uv[0] - uv[1]}) >= margin) return uv;
  }
}

// Barycentrics of a point in the triangle's plane, outside by at least `margin` across some edge.
Eigen::Vector2d randomOutsideBarycentrics(Rng& rng, double margin) {
  for (;;) {
    const Eigen::Vector2d uv(uniform(rng, -2, 3), uniform(rng, -2, 3));
    if (std::min({uv[0], uv[1], 1 - uv[0] - uv[1]}) <= -margin) return uv;
  }
}

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
class PrecisionNames {
 public:
  template <typename T>
  static std::string GetName(int) {
    return precisionName<T>();
  }
};
using Precisions = ::testing::Types<double, float>;
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

// ---------------------------------------------------------------------------------------------------
// Literal cases, once per precision.

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
