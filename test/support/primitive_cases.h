// The primitive tests' rays and literal cases (a ray, and the expected hit or none), and the shapes
// the literal cases use.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "laser_raycast/core/primitives.h"

namespace laser_raycast_test {

namespace core = laser_raycast::core;

inline core::Ray makeRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double tmin = 0,
                         double tmax = std::numeric_limits<double>::infinity()) {
  core::Ray ray;
  ray.origin = origin;
  ray.dir = dir;
  ray.tmin = tmin;
  ray.tmax = tmax;
  return ray;
}

inline std::string describe(const core::Ray& ray) {
  std::ostringstream s;
  s << std::setprecision(17) << "origin " << ray.origin.transpose() << " dir "
    << ray.dir.transpose() << " [" << ray.tmin << ", " << ray.tmax << "]";
  return s.str();
}

// A literal case: the ray, and the expected hit (t, outward normal) or none.
struct Expect {
  const char* what;
  Eigen::Vector3d origin, dir;
  std::optional<double> t;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};

// Hand-written distances are exact or a few roundings away from it: 1e-12 relative.
template <typename Shape>
void checkLiteralCases(const Shape& shape, const std::vector<Expect>& cases) {
  for (const Expect& e : cases) {
    const core::Ray ray = makeRay(e.origin, e.dir);
    const auto hit = core::intersect(ray, shape);
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

// Box of size 2 x 4 x 6: the faces are x = +-1, y = +-2, z = +-3.
inline const core::Box kBox{Eigen::Vector3d(2, 4, 6)};
// Cylinder of radius 1, length 4: the side x^2 + y^2 = 1, the caps z = +-2.
inline const core::Cylinder kCylinder{1.0, 4.0};
// Sphere of radius 2.
inline const core::Sphere kSphere{2.0};

}  // namespace laser_raycast_test
