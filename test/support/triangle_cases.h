// The triangle tests' cases: tolerances per precision, rays built in either precision, and random
// well-shaped triangles with rays aimed at chosen barycentrics (the constructed truth).
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>

#include "laser_raycast/core/triangle.h"
#include "random.h"

namespace laser_raycast_test {

namespace core = laser_raycast::core;

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
core::RayT<T> makeRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double tmin = 0,
                      double tmax = std::numeric_limits<double>::infinity()) {
  core::RayT<T> ray;
  ray.origin = origin.cast<T>();
  ray.dir = dir.cast<T>();
  ray.tmin = static_cast<T>(tmin);
  ray.tmax = static_cast<T>(tmax);
  return ray;
}

template <typename T>
std::optional<core::TriangleHitT<T>> hitTriangle(core::TriangleMethod method,
                                                 const core::RayT<T>& ray, const Eigen::Vector3d& a,
                                                 const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                                 bool cull = false) {
  const core::Vec3<T> at = a.cast<T>(), bt = b.cast<T>(), ct = c.cast<T>();
  return core::intersectTriangle(method, ray, at, bt, ct, cull);
}

template <typename T>
const char* precisionName() {
  return std::is_same<T, double>::value ? "double" : "float";
}

inline std::string describe(const char* what, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                            const Eigen::Vector3d& c, const Eigen::Vector3d& origin,
                            const Eigen::Vector3d& dir) {
  std::ostringstream s;
  s << std::setprecision(17) << what << ": a = " << a.transpose() << ", b = " << b.transpose()
    << ", c = " << c.transpose() << ", origin = " << origin.transpose()
    << ", dir = " << dir.transpose();
  return s.str();
}

// A random triangle with no tiny angle (|n| >= 0.1 * longest edge^2), vertices in a cube of
// half-size `size` around `center`.
inline void randomWellShapedTriangle(Rng& rng, const Eigen::Vector3d& center, double size,
                                     Eigen::Vector3d* a, Eigen::Vector3d* b, Eigen::Vector3d* c) {
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
  Eigen::Vector3d a, b, c, origin, dir;
  double t;     // where the ray meets the plane, in units of |dir|
  double u, v;  // barycentrics of the aimed point
  bool front;   // the ray sees the front face: dir . ((b - a) x (c - a)) < 0
};

inline AimedCase makeAimedCase(Rng& rng, const Eigen::Vector2d& uv) {
  AimedCase k;
  const double scale = logUniform(rng, -3, 3);
  const Eigen::Vector3d center = uniformInCube(rng, 2 * scale);
  randomWellShapedTriangle(rng, center, scale, &k.a, &k.b, &k.c);
  k.u = uv[0];
  k.v = uv[1];
  const Eigen::Vector3d p = (1 - k.u - k.v) * k.a + k.u * k.b + k.v * k.c;
  const Eigen::Vector3d n = (k.b - k.a).cross(k.c - k.a).normalized();
  Eigen::Vector3d w;
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
inline Eigen::Vector2d randomInsideBarycentrics(Rng& rng, double margin) {
  for (;;) {
    const Eigen::Vector2d uv = randomBarycentrics(rng);
    if (std::min({uv[0], uv[1], 1 - uv[0] - uv[1]}) >= margin) return uv;
  }
}

// Barycentrics of a point in the triangle's plane, outside by at least `margin` across some edge.
inline Eigen::Vector2d randomOutsideBarycentrics(Rng& rng, double margin) {
  for (;;) {
    const Eigen::Vector2d uv(uniform(rng, -2, 3), uniform(rng, -2, 3));
    if (std::min({uv[0], uv[1], 1 - uv[0] - uv[1]}) <= -margin) return uv;
  }
}

class PrecisionNames {
 public:
  template <typename T>
  static std::string GetName(int) {
    return precisionName<T>();
  }
};
using Precisions = ::testing::Types<double, float>;

}  // namespace laser_raycast_test
