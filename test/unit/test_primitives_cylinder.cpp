// The cylinder primitive against hand-written distances and a world-frame closed form.
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

TEST(CylinderIntersect, LiteralCases) {
  const double s = std::sqrt(0.5);
  checkLiteralCases(
      kCylinder,
      {
          // Side from outside.
          {"side, along -x", {-5, 0, 0}, {1, 0, 0}, 4.0, {-1, 0, 0}},
          {"side, |dir| = 0.5", {0, 3, 1}, {0, -0.5, 0}, 4.0, {0, 1, 0}},
          {"side, oblique in z", {0, -5, -1}, {0, 1, 0.2}, 4.0, {0, -1, 0}},
          {"side, diagonal", {-3, -3, 0.5}, {1, 1, 0}, 3 - s, {-s, -s, 0}},
          // Caps from outside: along the axis, and oblique (the side is reached later, at t = 5).
          {"bottom cap along the axis", {0, 0, -10}, {0, 0, 1}, 8.0, {0, 0, -1}},
          {"top cap, oblique", {0.5, 0, 5}, {-0.1, 0.2, -1}, 3.0, {0, 0, 1}},
          // From inside: along the axis to the far cap, radially to the side, obliquely to a cap.
          {"inside along +z: top cap", {0, 0, 0.5}, {0, 0, 1}, 1.5, {0, 0, 1}},
          {"inside along -z: bottom cap", {0, 0, 0.5}, {0, 0, -2}, 1.25, {0, 0, -1}},
          {"inside radially", {0, 0, 0}, {1, 0, 0}, 1.0, {1, 0, 0}},
          {"inside, off-axis chord",
           {0.5, 0, 1},
           {0, 1, 0},
           std::sqrt(0.75),
           {0.5, std::sqrt(0.75), 0}},
          {"inside, steep: top cap", {0, 0, 0}, {0.1, 0, 1}, 2.0, {0, 0, 1}},
          // Tangent to the side: touches (0, 1, 0).
          {"tangent to the side", {-5, 1, 0}, {1, 0, 0}, 5.0, {0, 1, 0}},
          {"one ulp beyond tangent", {-5, std::nextafter(1.0, 2.0), 0}, {1, 0, 0}, std::nullopt},
          // In the plane of the top cap: meets the side where the side ends (|z| = h).
          {"in the top cap's plane", {-5, 0, 2}, {1, 0, 0}, 4.0, {-1, 0, 0}},
          // Misses.
          {"above the top", {-5, 0, 3}, {1, 0, 0}, std::nullopt},
          {"parallel to the axis, outside", {2, 0, -10}, {0, 0, 1}, std::nullopt},
          {"beside", {-5, 1.5, 0}, {1, 0, 0}, std::nullopt},
          {"behind the origin", {5, 0, 0}, {1, 0, 0}, std::nullopt},
      });
}

// A ray exactly on the side surface (radius 5, the point (3, 4) has x^2 + y^2 = 25 exactly) runs
// parallel to the axis: it has no side hit, and meets the rim of a cap, which is part of the disc.
TEST(CylinderIntersect, RayAlongTheSideSurfaceHitsTheCapRim) {
  const Cylinder c{5.0, 4.0};
  checkLiteralCases(
      c,
      {
          {"along the side from below", {3, 4, -10}, {0, 0, 1}, 8.0, {0, 0, -1}},
          {"along the side from above", {-4, 3, 7}, {0, 0, -1}, 5.0, {0, 0, 1}},
          {"on the side surface, inside the length", {3, 4, 0}, {0, 0, 1}, 2.0, {0, 0, 1}},
          {"one ulp outside the side", {3, std::nextafter(4.0, 5.0), -10}, {0, 0, 1}, std::nullopt},
      });
}

// Regression: side hits were accepted where the recomputed hit point had |z| <= h, cap hits where
// it lay inside the disc; near the rim rounding could fail both, and a ray from inside left the
// closed cylinder (36 of 720 rays aimed at rim points from (0.1, 0.2, 0.3) here, e.g. this one,
// aimed at (0.7 cos 9deg, 0.7 sin 9deg, 1.25)). Fixed by intersecting the tube's and the slab's t
// intervals.
TEST(CylinderIntersect, RayFromInsideAimedAtTheRimRegression) {
  const Cylinder cylinder{0.7, 2.5};
  const Ray ray = makeRay({0.1, 0.2, 0.3}, {0.59138183841659642, -0.090495874471838406, 0.95});
  const auto hit = intersect(ray, cylinder);
  ASSERT_TRUE(hit);
  // dir = rim point - origin, so the rim is at t = 1 (up to the rounding of the literal).
  EXPECT_NEAR(hit->t, 1.0, 1e-12);
  EXPECT_NEAR(hit->normal.norm(), 1.0, 1e-12);
  EXPECT_GT(hit->normal.dot(ray.dir), 0.0);  // leaving
}

TEST(CylinderIntersect, TminTmaxLimitsAreInclusive) {
  // Along -x at y = z = 0: enters at t = 4, leaves at t = 6.
  const Vector3d o(-5, 0, 0), d(1, 0, 0);
  auto hit = [&](double tmin, double tmax) {
    return intersect(makeRay(o, d, tmin, tmax), kCylinder);
  };
  ASSERT_TRUE(hit(0, 4));
  EXPECT_EQ(hit(0, 4)->t, 4.0);
  EXPECT_FALSE(hit(0, std::nextafter(4.0, 0.0)));
  ASSERT_TRUE(hit(4.5, kInf));
  EXPECT_EQ(hit(4.5, kInf)->t, 6.0);
  EXPECT_EQ(hit(4.5, kInf)->normal, Vector3d(1, 0, 0));
  EXPECT_FALSE(hit(4.5, 5.5));
  // Along the axis: bottom cap at t = 8, top cap at t = 12.
  auto axial = [&](double tmin, double tmax) {
    return intersect(makeRay({0, 0, -10}, {0, 0, 1}, tmin, tmax), kCylinder);
  };
  EXPECT_EQ(axial(8, 8)->t, 8.0);
  EXPECT_EQ(axial(9, kInf)->t, 12.0);
  EXPECT_EQ(axial(9, kInf)->normal, Vector3d(0, 0, 1));
  EXPECT_FALSE(axial(9, std::nextafter(12.0, 0.0)));
}

// The first crossing of a cylinder with centre c, unit axis w, radius r and half length h, in
// world coordinates and long double (a closed form independent of the implementation's frame).
// Returns false when a candidate lies within a small margin of the rim or the ray is close to
// tangent (the verdict would be decided by rounding); *t is NaN for a miss.
bool cylinderTruth(const Vec3L& c, const Vec3L& w, L r, L h, const Ray& ray, L* t, Vec3L* normal) {
  const Vec3L o = ray.origin.cast<L>(), d = ray.dir.cast<L>();
  const Vec3L delta = o - c;
  const L dw = d.dot(w), delta_w = delta.dot(w);
  const Vec3L dp = d - dw * w, delta_p = delta - delta_w * w;
  const L margin = 1e-9L;
  *t = std::numeric_limits<L>::quiet_NaN();
  auto offer = [&](L tc, const Vec3L& n) {
    if (std::abs(tc - L(ray.tmin)) * d.norm() < margin * r) return false;
    if (tc >= ray.tmin && !(tc > *t)) {
      *t = tc;
      *normal = n;
    }
    return true;
  };
  // Side: |delta_p + t dp|^2 = r^2, where |delta_w + t dw| <= h.
  const L a = dp.squaredNorm(), b = delta_p.dot(dp), cc = delta_p.squaredNorm() - r * r;
  if (a > 0) {
    const L disc = b * b - a * cc;
    if (std::abs(disc) < margin * (b * b + std::abs(a * cc))) return false;  // near tangent
    if (disc > 0) {
      for (const L sign : {-1.0L, 1.0L}) {
        const L tc = (-b + sign * std::sqrt(disc)) / a;
        const L z = delta_w + tc * dw;
        if (std::abs(std::abs(z) - h) < margin * h) return false;
        if (std::abs(z) < h && !offer(tc, (delta_p + tc * dp) / r)) return false;
      }
    }
  }
  // Caps: delta_w + t dw = +-h, where |delta_p + t dp| <= r.
  if (dw != 0) {
    for (const L side : {-1.0L, 1.0L}) {
      const L tc = (side * h - delta_w) / dw;
      const L radial = (delta_p + tc * dp).norm();
      if (std::abs(radial - r) < margin * r) return false;
      if (radial < r && !offer(tc, side * w)) return false;
    }
  }
  return true;
}

// A cylinder posed in the world (random rotation and position), hit as a caller does it: the ray
// moved into the cylinder's frame with the inverse pose, the normal rotated back. t is the same in
// both frames (rigid motion keeps |dir|).
TEST(CylinderIntersect, TiltedCylindersMatchAWorldFrameClosedForm) {
  Rng rng(43);
  int hits = 0, checked = 0, cap_hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const double radius = logUniform(rng, -2, 1);
    const double length = logUniform(rng, -2, 1);
    const Cylinder cylinder{radius, length};
    const Eigen::Isometry3d world_from_cylinder = randomPose(rng, 10.0);
    const double extent = radius + length;
    // Origins outside (mostly) and inside; aimed near the cylinder.
    const Vector3d local_origin =
        i % 4 == 0 ? Vector3d(uniform(rng, -0.7, 0.7) * radius, uniform(rng, -0.7, 0.7) * radius,
                              uniform(rng, -0.5, 0.5) * length)
                   : Vector3d(uniformInCube(rng, 3 * extent));
    const Vector3d local_target(uniform(rng, -1.3, 1.3) * radius, uniform(rng, -1.3, 1.3) * radius,
                                uniform(rng, -0.7, 0.7) * length);
    const Vector3d origin = world_from_cylinder * local_origin;
    const Vector3d dir =
        world_from_cylinder.linear() * (local_target - local_origin) * logUniform(rng, -1, 1);
    const Ray world_ray = makeRay(origin, dir);

    const Eigen::Matrix<L, 3, 3> rotation = world_from_cylinder.linear().cast<L>();
    L t;
    Vec3L normal;
    if (!cylinderTruth(world_from_cylinder.translation().cast<L>(), rotation.col(2), radius,
                       length / 2, world_ray, &t, &normal)) {
      continue;
    }
    ++checked;

    // What a caller does.
    const Eigen::Isometry3d cylinder_from_world = world_from_cylinder.inverse();
    const Ray local_ray = makeRay(cylinder_from_world * origin, cylinder_from_world.linear() * dir);
    const auto hit = intersect(local_ray, cylinder);
    ASSERT_EQ(hit.has_value(), !std::isnan(t))
        << describe(world_ray) << " r " << radius << " length " << length << " case " << i;
    if (!hit) continue;
    ++hits;
    cap_hits += std::abs(hit->normal.z()) == 1.0;
    // The rounding of the transform and of the roots: ~1e-15 relative, amplified near grazing.
    EXPECT_NEAR(hit->t, double(t), 1e-9 * double(t)) << describe(world_ray) << " case " << i;
    const Vector3d world_normal = world_from_cylinder.linear() * hit->normal;
    EXPECT_NEAR((world_normal - normal.cast<double>()).norm(), 0, 1e-9)
        << describe(world_ray) << " case " << i;
    if (::testing::Test::HasFailure()) return;
  }
  EXPECT_GT(checked, 19000);
  EXPECT_GT(hits, checked / 3);
  EXPECT_GT(cap_hits, hits / 20);
}

}  // namespace
}  // namespace laser_raycast_test
