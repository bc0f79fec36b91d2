// Every primitive: finite hits, outward normals, closed surfaces, non-finite rays, validate().
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

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

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
