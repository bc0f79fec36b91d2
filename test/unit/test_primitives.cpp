// The analytic primitives (primitives.h): box, cylinder and sphere against distances written by
// hand or computed independently in long double (never by calling the implementation): rays from
// outside (entry), from inside (exit: surfaces are surfaces), misses, tangent and grazing rays,
// rays along the cylinder's axis and side, tilted cylinders through a caller's transform, a sphere
// seen from 10^6 m, normals, the [tmin, tmax] limits, non-finite rays and validate().
#include <gtest/gtest.h>

#include <cmath>
#include <iomanip>
#include <limits>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "laser_raycast/core/primitives.h"
#include "random.h"
#include "test_geometry.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;
using Eigen::Vector3d;
using L = long double;
using Vec3L = Eigen::Matrix<L, 3, 1>;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Ray makeRay(const Vector3d& origin, const Vector3d& dir, double tmin = 0, double tmax = kInf) {
  Ray ray;
  ray.origin = origin;
  ray.dir = dir;
  ray.tmin = tmin;
  ray.tmax = tmax;
  return ray;
}

std::string describe(const Ray& ray) {
  std::ostringstream s;
  s << std::setprecision(17) << "origin " << ray.origin.transpose() << " dir "
    << ray.dir.transpose() << " [" << ray.tmin << ", " << ray.tmax << "]";
  return s.str();
}

// A literal case: the ray, and the expected hit (t, outward normal) or none.
struct Expect {
  const char* what;
  Vector3d origin, dir;
  std::optional<double> t;
  Vector3d normal = Vector3d::Zero();
};

// Hand-written distances are exact or a few roundings away from it: 1e-12 relative.
template <typename Shape>
void checkLiteralCases(const Shape& shape, const std::vector<Expect>& cases) {
  for (const Expect& e : cases) {
    const Ray ray = makeRay(e.origin, e.dir);
    const auto hit = intersect(ray, shape);
    if (!e.t) {
      EXPECT_FALSE(hit) << e.what << ": hit at t = " << (hit ? hit->t : 0.0);
      continue;
    }
    ASSERT_TRUE(hit) << e.what;
    EXPECT_NEAR(hit->t, *e.t, 1e-12 * std::max(1.0, *e.t)) << e.what;
    EXPECT_NEAR((hit->normal - e.normal).norm(), 0.0, 1e-12)
        << e.what << ": normal " << hit->normal.transpose();
  }
}

// ---------------------------------------------------------------------------------------------------
// Box (size 2 x 4 x 6: the faces are x = +-1, y = +-2, z = +-3).

const Box kBox{Vector3d(2, 4, 6)};

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

// Regression: a hit is always finite. With a direction so short that the true distance exceeds
// the largest double (1e310 here), every primitive computed t = +Inf and, with tmax = +Inf (the
// Ray default), reported it as a hit. From the inside (the exit surface) and from outside (the
// entry).
TEST(PrimitiveContracts, HitBeyondTheLargestFiniteTIsNoHitRegression) {
  const Vector3d tiny_x(1e-160, 0, 0), tiny_z(0, 0, 1e-120);
  // From the centre of a sphere and a cylinder of radius 1e150: exit at 1e150 / 1e-160.
  EXPECT_FALSE(intersect(makeRay({0, 0, 0}, tiny_x), Sphere{1e150}));
  EXPECT_FALSE(intersect(makeRay({0, 0, 0}, tiny_x), Cylinder{1e150, 2}));
  EXPECT_FALSE(intersect(makeRay({0, 0, 0}, tiny_x), Box{Vector3d(2e150, 2, 2)}));
  // From 1e200 below a unit box and cylinder, along z: entry at (1e200 - 1) / 1e-120.
  EXPECT_FALSE(intersect(makeRay({0, 0, -1e200}, tiny_z), kBox));
  EXPECT_FALSE(intersect(makeRay({0, 0, -1e200}, tiny_z), Cylinder{1, 2}));
  // The same shapes within reach are hit, at finite distances.
  const auto sphere = intersect(makeRay({0, 0, 0}, {1e-150, 0, 0}), Sphere{1e140});
  ASSERT_TRUE(sphere);
  EXPECT_NEAR(sphere->t, 1e290, 1e290 * 1e-12);
  const auto cylinder = intersect(makeRay({0, 0, -1e100}, tiny_z), Cylinder{1, 2});
  ASSERT_TRUE(cylinder);
  EXPECT_NEAR(cylinder->t, 1e220, 1e220 * 1e-12);
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

// ---------------------------------------------------------------------------------------------------
// Cylinder (radius 1, length 4: the side x^2 + y^2 = 1, the caps z = +-2).

const Cylinder kCylinder{1.0, 4.0};

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

// ---------------------------------------------------------------------------------------------------
// Sphere (radius 2).

const Sphere kSphere{2.0};

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

// ---------------------------------------------------------------------------------------------------
// All three shapes.

// Normals are unit and outward; they oppose the ray where it enters (origin outside) and follow it
// where it leaves (origin inside). Hit points lie on the shape's bounds.
TEST(PrimitiveNormals, UnitOutwardAndFacingTheRightWay) {
  Rng rng(59);
  const Box box{Vector3d(1.5, 0.4, 3)};
  const Cylinder cylinder{0.7, 2.5};
  const Sphere sphere{1.2};
  auto inside = [&](int shape, const Vector3d& p) {
    switch (shape) {
      case 0:
        return (p.cwiseAbs().array() < box.size.array() / 2).all();
      case 1:
        return p.head<2>().norm() < cylinder.radius && std::abs(p.z()) < cylinder.length / 2;
      default:
        return p.norm() < sphere.radius;
    }
  };
  int counted[3] = {0, 0, 0};
  for (int i = 0; i < 30000; ++i) {
    const int shape = i % 3;
    const Vector3d origin = uniformInCube(rng, 3);
    const Ray ray = makeRay(origin, uniformInCube(rng, 1) - origin);
    const auto hit = shape == 0   ? intersect(ray, box)
                     : shape == 1 ? intersect(ray, cylinder)
                                  : intersect(ray, sphere);
    if (!hit) continue;
    ++counted[shape];
    const Vector3d p = origin + hit->t * ray.dir;
    // Half the extent of the shape's tight box along x, y, z.
    const Vector3d half = shape == 0 ? Vector3d(box.size / 2)
                          : shape == 1
                              ? Vector3d(cylinder.radius, cylinder.radius, cylinder.length / 2)
                              : Vector3d::Constant(sphere.radius);
    EXPECT_NEAR(hit->normal.norm(), 1.0, 1e-12) << shape << " " << describe(ray);
    // Outward: the hit point lies on the far side of the centre along the normal...
    EXPECT_GT(hit->normal.dot(p), 0.0) << shape << " " << describe(ray);
    // ...the ray enters against the normal and leaves along it.
    if (inside(shape, origin)) {
      EXPECT_GT(hit->normal.dot(ray.dir), 0.0) << shape << " " << describe(ray);
    } else {
      EXPECT_LT(hit->normal.dot(ray.dir), 0.0) << shape << " " << describe(ray);
    }
    EXPECT_TRUE((p.cwiseAbs().array() <= half.array() + 1e-12).all())
        << shape << " " << describe(ray);
    if (::testing::Test::HasFailure()) return;
  }
  for (const int c : counted) EXPECT_GT(c, 3000);
}

// A closed surface around the origin of the ray is always hit, including by rays aimed exactly at
// its edges: the box's edges and corners, the cylinder's rims (where side and cap meet), points of
// the sphere. The hit is the aimed point (the shapes are convex).
TEST(PrimitiveClosedSurfaces, RaysFromInsideAimedAtEdgesAlwaysHit) {
  Rng rng(61);
  const Box box{Vector3d(1.5, 0.4, 3)};
  const Cylinder cylinder{0.7, 2.5};
  const Sphere sphere{1.2};
  int misses[3] = {0, 0, 0};
  std::string first_miss;
  for (int i = 0; i < 30000; ++i) {
    const int shape = i % 3;
    Vector3d origin, target;
    if (shape == 0) {
      origin = uniformInBox(rng, -0.45 * box.size, 0.45 * box.size);
      // A corner, or a point of an edge: two coordinates on their faces, one anywhere.
      const Vector3d h = box.size / 2;
      target =
          Vector3d(i % 2 ? h.x() : -h.x(), i % 4 < 2 ? h.y() : -h.y(), i % 8 < 4 ? h.z() : -h.z());
      const int free_axis = (i / 8) % 4;  // 3: the corner itself
      if (free_axis < 3) target[free_axis] = uniform(rng, -h[free_axis], h[free_axis]);
    } else if (shape == 1) {
      const double r = cylinder.radius, h = cylinder.length / 2;
      origin = Vector3d(0.6 * r * uniform(rng, -1, 1), 0.6 * r * uniform(rng, -1, 1),
                        0.9 * h * uniform(rng, -1, 1));
      const double angle = uniform(rng, -M_PI, M_PI);
      target = Vector3d(r * std::cos(angle), r * std::sin(angle), i % 2 ? h : -h);
    } else {
      origin = 0.9 * sphere.radius * std::cbrt(uniform(rng, 0, 1)) * randomUnitVector(rng);
      target = sphere.radius * randomUnitVector(rng);
    }
    const Ray ray = makeRay(origin, (target - origin) * logUniform(rng, -1, 1));
    const auto hit = shape == 0   ? intersect(ray, box)
                     : shape == 1 ? intersect(ray, cylinder)
                                  : intersect(ray, sphere);
    if (!hit) {
      if (misses[shape]++ == 0 && first_miss.empty()) {
        first_miss = "shape " + std::to_string(shape) + ": " + describe(ray);
      }
      continue;
    }
    const double expected = (target - origin).norm() / ray.dir.norm();
    EXPECT_NEAR(hit->t, expected, 1e-12 * expected) << shape << " " << describe(ray);
    if (::testing::Test::HasFailure()) return;
  }
  EXPECT_EQ(misses[0], 0) << "box; first: " << first_miss;
  EXPECT_EQ(misses[1], 0) << "cylinder; first: " << first_miss;
  EXPECT_EQ(misses[2], 0) << "sphere; first: " << first_miss;
}

// NaN or Inf in the origin or direction, a zero direction, or a NaN limit: no hit (each base ray
// hits, so the miss is caused by the bad value).
TEST(PrimitiveNonFinite, NonFiniteRaysNeverHit) {
  const Vector3d origin(-5, 0.1, 0.2), dir(1, 0, 0);
  auto hits = [&](const Ray& ray) {
    return std::vector<bool>{intersect(ray, kBox).has_value(),
                             intersect(ray, kCylinder).has_value(),
                             intersect(ray, kSphere).has_value()};
  };
  ASSERT_EQ(hits(makeRay(origin, dir)), std::vector<bool>({true, true, true}));
  const std::vector<bool> none = {false, false, false};
  for (const double bad : {kNaN, kInf, -kInf}) {
    for (int k = 0; k < 3; ++k) {
      Vector3d o = origin, d = dir;
      o[k] = bad;
      EXPECT_EQ(hits(makeRay(o, dir)), none) << "origin[" << k << "] = " << bad;
      d[k] = bad;
      EXPECT_EQ(hits(makeRay(origin, d)), none) << "dir[" << k << "] = " << bad;
    }
  }
  EXPECT_EQ(hits(makeRay(origin, Vector3d::Zero())), none) << "zero dir";
  EXPECT_EQ(hits(makeRay(origin, dir, kNaN, kInf)), none) << "NaN tmin";
  EXPECT_EQ(hits(makeRay(origin, dir, 0, kNaN)), none) << "NaN tmax";
}

// ---------------------------------------------------------------------------------------------------
// validate().

// Expects validate(shape) to throw std::invalid_argument whose message names `dimension`.
template <typename Shape>
void expectRejected(const Shape& shape, const std::string& dimension) {
  try {
    validate(shape);
    ADD_FAILURE() << "no exception for " << dimension;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(dimension), std::string::npos)
        << "message \"" << e.what() << "\" does not name " << dimension;
  }
}

TEST(PrimitiveValidate, RejectsZeroNegativeAndNonFiniteSizesNamingTheDimension) {
  for (const double bad : {0.0, -0.0, -1.0, kNaN, kInf, -kInf}) {
    expectRejected(Box{Vector3d(bad, 1, 1)}, "box size x");
    expectRejected(Box{Vector3d(1, bad, 1)}, "box size y");
    expectRejected(Box{Vector3d(1, 1, bad)}, "box size z");
    expectRejected(Cylinder{bad, 1}, "cylinder radius");
    expectRejected(Cylinder{1, bad}, "cylinder length");
    expectRejected(Sphere{bad}, "sphere radius");
  }
  // The message also carries the value.
  try {
    validate(Cylinder{1, -2.5});
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("-2.5"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(validate(Box{Vector3d(1e-9, 2, 1e9)}));
  EXPECT_NO_THROW(validate(Cylinder{0.01, 100}));
  EXPECT_NO_THROW(validate(Sphere{1e-6}));
}

}  // namespace
}  // namespace laser_raycast_test
