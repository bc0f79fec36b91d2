// The sphere primitive against hand-written distances and a cancellation-free closed form.
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

TEST(SphereIntersect, LiteralCases) {
  checkLiteralCases(
      kSphere,
      {
          {"from -x", {-10, 0, 0}, {1, 0, 0}, 8.0, {-1, 0, 0}},
          {"from +y, |dir| = 0.5", {0, 7, 0}, {0, -0.5, 0}, 10.0, {0, 1, 0}},
          {"diagonal 3-4-5", {6, 8, 0}, {-0.6, -0.8, 0}, 8.0, {0.6, 0.8, 0}},
          {"inside, from the centre, |dir| = 3", {0, 0, 0}, {0, 0, 3}, 2.0 / 3.0, {0, 0, 1}},
          {"inside, off centre, forwards", {1, 0, 0}, {1, 0, 0}, 1.0, {1, 0, 0}},
          {"inside, off centre, backwards", {1, 0, 0}, {-1, 0, 0}, 3.0, {-1, 0, 0}},
          {"tangent", {-10, 2, 0}, {1, 0, 0}, 10.0, {0, 1, 0}},
          {"one ulp beyond tangent", {-10, std::nextafter(2.0, 3.0), 0}, {1, 0, 0}, std::nullopt},
          {"beside", {-10, 3, 0}, {1, 0, 0}, std::nullopt},
          {"behind the origin", {10, 0, 0}, {1, 0, 0}, std::nullopt},
      });
}

TEST(SphereIntersect, TminTmaxLimitsAreInclusive) {
  // From (-10, 0, 0) along +x: 8 and 12, both exact.
  auto hit = [&](double tmin, double tmax) {
    return intersect(makeRay({-10, 0, 0}, {1, 0, 0}, tmin, tmax), kSphere);
  };
  EXPECT_EQ(hit(0, 8)->t, 8.0);
  EXPECT_FALSE(hit(0, std::nextafter(8.0, 0.0)));
  EXPECT_EQ(hit(8, 8)->t, 8.0);
  ASSERT_TRUE(hit(std::nextafter(8.0, 9.0), kInf));
  EXPECT_EQ(hit(std::nextafter(8.0, 9.0), kInf)->t, 12.0);
  EXPECT_EQ(hit(std::nextafter(8.0, 9.0), kInf)->normal, Vector3d(1, 0, 0));
  EXPECT_FALSE(hit(9, 11));
  EXPECT_FALSE(hit(std::nextafter(12.0, 13.0), kInf));
}

// The entry distance of a ray from far away, in long double and without cancellation: f is the
// point of the ray's line nearest the centre, t = (-o.d - sqrt(|d|^2 (r^2 - |f|^2))) / |d|^2.
// In long double, f carries ~1e-19 relative error of |o|; nothing else cancels.
L sphereEntryTruth(const Ray& ray, L r) {
  const Vec3L o = ray.origin.cast<L>(), d = ray.dir.cast<L>();
  const L a = d.squaredNorm();
  const Vec3L f = o - (o.dot(d) / a) * d;
  return (-o.dot(d) - std::sqrt(a * (r * r - f.squaredNorm()))) / a;
}

// Seen from 10^6 m, the textbook discriminant b^2 - a c cancels ~12 digits (an error of ~1e-4 m^2
// against r^2); the implementation's r^2 - |f|^2 form does not. The rays enter at a chosen point of
// the sphere, at least ~12 degrees off tangent.
TEST(SphereIntersect, FromAMillionMetresAway) {
  Rng rng(47);
  for (int i = 0; i < 5000; ++i) {
    const double r = logUniform(rng, -2, 1);
    const Vector3d n = randomUnitVector(rng);
    Vector3d w;
    do {
      w = randomUnitVector(rng);
    } while (w.dot(n) > -0.2);
    const Vector3d entry = r * n;
    const double distance = 1e6 * uniform(rng, 1, 2);
    const Ray ray = makeRay(entry - distance * w, w * logUniform(rng, -1, 1));
    const L t = sphereEntryTruth(ray, r);
    // The construction itself: the entry point is where the ray enters, to ~1e-10 m.
    ASSERT_NEAR(double(t * ray.dir.cast<L>().norm()), distance, 1e-6);

    const auto hit = intersect(ray, Sphere{r});
    ASSERT_TRUE(hit) << describe(ray) << " r " << r;
    // 1e-12 relative is 1 um at 10^6 m; the cancelling formula is off by ~10 um to metres.
    EXPECT_NEAR(hit->t, double(t), 1e-12 * double(t)) << describe(ray) << " r " << r;
    // The normal comes from the hit point (error ~1e-10 m) divided by r >= 0.01.
    EXPECT_NEAR(hit->normal.norm(), 1.0, 1e-6);
    EXPECT_NEAR((hit->normal - n).norm(), 0.0, 1e-6) << describe(ray) << " r " << r;
    if (::testing::Test::HasFailure()) return;
  }
}

// Random rays near a sphere, from outside and inside, against the long double closed form.
TEST(SphereIntersect, RandomRaysMatchTheClosedForm) {
  Rng rng(53);
  int hits = 0, checked = 0;
  for (int i = 0; i < 20000; ++i) {
    const double r = logUniform(rng, -2, 2);
    const Vector3d origin =
        i % 3 == 0 ? Vector3d(0.9 * r * std::cbrt(uniform(rng, 0, 1)) * randomUnitVector(rng))
                   : Vector3d(uniformInCube(rng, 10 * r));
    const Vector3d target = uniformInCube(rng, 1.3 * r);
    const Ray ray = makeRay(origin, (target - origin) * logUniform(rng, -2, 2));
    // Truth: the roots of |o + t d|^2 = r^2 with the cancellation-free discriminant, long double.
    const Vec3L o = ray.origin.cast<L>(), d = ray.dir.cast<L>();
    const L a = d.squaredNorm();
    const Vec3L f = o - (o.dot(d) / a) * d;
    const L disc = a * (L(r) * r - f.squaredNorm());
    if (std::abs(disc) < 1e-9L * a * r * r) continue;  // near tangent
    L t = std::numeric_limits<L>::quiet_NaN();
    if (disc > 0) {
      const L t0 = (-o.dot(d) - std::sqrt(disc)) / a, t1 = (-o.dot(d) + std::sqrt(disc)) / a;
      t = t0 >= 0 ? t0 : t1 >= 0 ? t1 : t;
    }
    ++checked;
    const auto hit = intersect(ray, Sphere{r});
    ASSERT_EQ(hit.has_value(), !std::isnan(t)) << describe(ray) << " r " << r;
    if (!hit) continue;
    ++hits;
    EXPECT_NEAR(hit->t, double(t), 1e-10 * double(t) + 1e-15 * r) << describe(ray) << " r " << r;
    const Vector3d expected_normal = ((o + t * d) / L(r)).cast<double>();
    EXPECT_NEAR((hit->normal - expected_normal).norm(), 0.0, 1e-9) << describe(ray);
    if (::testing::Test::HasFailure()) return;
  }
  EXPECT_GT(checked, 19000);
  EXPECT_GT(hits, checked / 2);
}

}  // namespace
}  // namespace laser_raycast_test
