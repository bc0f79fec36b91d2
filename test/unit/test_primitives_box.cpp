// The box primitive against hand-written distances and an enumeration of its faces in long double.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "laser_raycast/core/primitives.h"
#include "primitive_cases.h"
#include "random.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;
using Eigen::Vector3d;
using L = long double;
using Vec3L = Eigen::Matrix<L, 3, 1>;

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(BoxIntersect, LiteralCases) {
  const double n = std::nextafter(2.0, 3.0);  // just outside y = 2
  checkLiteralCases(
      kBox,
      {
          // From outside, axis-aligned: the entry face.
          {"-x face", {-5, 0, 0}, {1, 0, 0}, 4.0, {-1, 0, 0}},
          {"+x face, |dir| = 2 (t in units of |dir|)", {5, 0.5, -1}, {-2, 0, 0}, 2.0, {1, 0, 0}},
          {"+y face", {0.5, 10, -1}, {0, -1, 0}, 8.0, {0, 1, 0}},
          {"-y face, |dir| = 0.5", {0, -7, 2}, {0, 0.5, 0}, 10.0, {0, -1, 0}},
          {"+z face", {0, 0, 10}, {0, 0, -1}, 7.0, {0, 0, 1}},
          {"-z face", {0.9, 1.9, -4}, {0, 0, 1}, 1.0, {0, 0, -1}},
          // Oblique from outside: slabs x [2, 4], y [1, 5] -> enters through -x at t = 2.
          {"oblique, -x face", {-3, -3, 0}, {1, 1, 0}, 2.0, {-1, 0, 0}},
          // x [-2, 6], y [-5, 3], z [2, 8] -> enters through +z at (0, 1.5, 3).
          {"oblique 3D, +z face", {0.5, 0.5, 5}, {-0.25, 0.5, -1}, 2.0, {0, 0, 1}},
          // From inside: the exit face.
          {"inside, exits +z", {0, 0, 0}, {0, 0, 1}, 3.0, {0, 0, 1}},
          {"inside, exits -y", {0.5, 0.5, 0.5}, {0, -1, 0}, 2.5, {0, -1, 0}},
          {"inside oblique, exits +x", {0.5, 0.5, 0.5}, {1, 1, 1}, 0.5, {1, 0, 0}},
          // On the surface, pointing in: the surface is at t = 0 = tmin (inclusive).
          {"on -x face, inwards", {-1, 0, 0}, {1, 0, 0}, 0.0, {-1, 0, 0}},
          // Grazing: in the plane of the +y face, and along the edge y = 2, z = 3. Boundary
          // points belong to the box.
          {"in the +y face plane", {-5, 2, 0}, {1, 0, 0}, 4.0, {-1, 0, 0}},
          {"along the edge y = 2, z = 3", {-5, 2, 3}, {1, 0, 0}, 4.0, {-1, 0, 0}},
          // Misses.
          {"one ulp outside the +y face plane", {-5, n, 0}, {1, 0, 0}, std::nullopt},
          {"passes beside (|y| > 2)", {-5, 3, 0}, {1, 0, 0}, std::nullopt},
          {"oblique, slabs disjoint", {-5, 0, 0}, {1, 1, 0}, std::nullopt},
          {"box behind the origin", {-5, 0, 0}, {-1, 0, 0}, std::nullopt},
          {"parallel above", {0, 0, 10}, {1, 0, 0}, std::nullopt},
      });
}

// Through a vertex or along an edge, two faces are hit at the same t: either normal is right.
TEST(BoxIntersect, CornerHitHasOneOfTheTouchingFacesNormals) {
  // Slabs x [1, 3], y [1, 5]: enters at (-1, -2, 0), on the edge of the -x and -y faces.
  const auto hit = intersect(makeRay({-2, -3, 0}, {1, 1, 0}), kBox);
  ASSERT_TRUE(hit);
  EXPECT_EQ(hit->t, 1.0);
  EXPECT_TRUE(hit->normal == Vector3d(-1, 0, 0) || hit->normal == Vector3d(0, -1, 0))
      << hit->normal.transpose();
  // The corner (1, 2, 3) from (2, 3, 4): all three slabs start at t = 1.
  const auto corner = intersect(makeRay({2, 3, 4}, {-1, -1, -1}), kBox);
  ASSERT_TRUE(corner);
  EXPECT_EQ(corner->t, 1.0);
  EXPECT_EQ(corner->normal.squaredNorm(), 1.0);
  EXPECT_EQ(corner->normal.minCoeff(), 0.0);  // +x, +y or +z
}

// Regression: the entry and exit axes started at -1 and were set only by a strictly larger entry
// (smaller exit) than +-inf. When every slab distance overflows (a tiny direction in a huge box),
// neither was set and the normal was written at index -1, out of bounds. The true distance here,
// 5e349, rounds to +inf: no hit (a hit is finite; see the next test), but nothing out of bounds on
// the way (the sanitizer build checks). A direction 1e100 times longer reaches the +x face at
// 5e249.
TEST(BoxIntersect, OverflowingSlabDistancesRegression) {
  const Box huge{Vector3d(1e200, 1e200, 1e200)};
  EXPECT_FALSE(intersect(makeRay({0, 0, 0}, {1e-150, 0, 0}), huge));
  EXPECT_FALSE(intersect(makeRay({0, 0, 0}, {1e-150, 0, 0}, 0, 1e300), huge));
  const auto hit = intersect(makeRay({0, 0, 0}, {1e-50, 0, 0}), huge);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->t, 5e249, 5e249 * 1e-15);
  EXPECT_EQ(hit->normal, Vector3d(1, 0, 0));
}

// Enters at t = 4 and leaves at t = 6 (both exact).
TEST(BoxIntersect, TminTmaxLimitsAreInclusive) {
  const Vector3d o(-5, 0, 0), d(1, 0, 0);
  auto hit = [&](double tmin, double tmax) { return intersect(makeRay(o, d, tmin, tmax), kBox); };
  ASSERT_TRUE(hit(0, 4));
  EXPECT_EQ(hit(0, 4)->t, 4.0);
  EXPECT_FALSE(hit(0, std::nextafter(4.0, 0.0)));
  EXPECT_EQ(hit(4, 4)->t, 4.0);
  // Past the entry, the exit surface is the hit, with the exit face's normal.
  ASSERT_TRUE(hit(std::nextafter(4.0, 5.0), kInf));
  EXPECT_EQ(hit(std::nextafter(4.0, 5.0), kInf)->t, 6.0);
  EXPECT_EQ(hit(std::nextafter(4.0, 5.0), kInf)->normal, Vector3d(1, 0, 0));
  EXPECT_EQ(hit(6, 6)->t, 6.0);
  EXPECT_FALSE(hit(5, 5.5));  // between the surfaces
  EXPECT_FALSE(hit(std::nextafter(6.0, 7.0), kInf));
}

// First surface crossing by enumerating the six faces in long double: the plane of each face, then
// whether the point lies in the face's rectangle. Returns false if a candidate lies within `margin`
// of a rectangle's border (the verdict would be decided by rounding); *t is NaN for a miss.
bool boxTruth(const Vector3d& size, const Ray& ray, L* t, Vector3d* normal) {
  const Vec3L h = size.cast<L>() / 2, o = ray.origin.cast<L>(), d = ray.dir.cast<L>();
  const L margin = 1e-9L * h.maxCoeff();
  *t = std::numeric_limits<L>::quiet_NaN();
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) continue;
    for (const int side : {-1, 1}) {
      const L tk = (side * h[k] - o[k]) / d[k];
      const Vec3L p = o + tk * d;
      bool inside = true;
      for (int j = 0; j < 3; ++j) {
        if (j == k) continue;
        if (std::abs(std::abs(p[j]) - h[j]) < margin) return false;
        inside = inside && std::abs(p[j]) < h[j];
      }
      if (std::abs(tk - L(ray.tmin)) < margin / d.norm()) return false;
      if (inside && tk >= ray.tmin && !(tk > *t)) {
        *t = tk;
        *normal = Vector3d::Zero();
        (*normal)[k] = side;
      }
    }
  }
  return true;
}

TEST(BoxIntersect, RandomRaysMatchFaceEnumeration) {
  Rng rng(41);
  int hits = 0, checked = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vector3d size(logUniform(rng, -2, 2), logUniform(rng, -2, 2), logUniform(rng, -2, 2));
    const double extent = size.maxCoeff();
    // Half the origins inside the box, half outside; aimed near the box.
    const Vector3d origin =
        i % 2 ? uniformInBox(rng, -size / 2, size / 2) : uniformInCube(rng, 3 * extent);
    const Vector3d target = uniformInBox(rng, -0.7 * size, 0.7 * size);
    const Ray ray = makeRay(origin, (target - origin) * logUniform(rng, -2, 2));
    L t;
    Vector3d normal;
    if (!boxTruth(size, ray, &t, &normal)) continue;
    ++checked;
    const auto hit = intersect(ray, Box{size});
    ASSERT_EQ(hit.has_value(), !std::isnan(t)) << describe(ray) << " size " << size.transpose();
    if (!hit) continue;
    ++hits;
    EXPECT_NEAR(hit->t, double(t), 1e-12 * double(t)) << describe(ray);
    EXPECT_EQ(hit->normal, normal) << describe(ray);
  }
  EXPECT_GT(checked, 19000);
  EXPECT_GT(hits, checked / 2);
}

}  // namespace
}  // namespace laser_raycast_test
