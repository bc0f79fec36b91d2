// Where the BVH may differ from brute force (the BVH tests, the core fuzz harness): the one
// documented exception to "the BVH returns exactly what testing every triangle returns".
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>

#include "laser_raycast/core/bvh.h"
#include "triangle_soup.h"

namespace laser_raycast_test {

// True if t is not where the exact ray, evaluated in long double from its rounded (T) values, is
// inside the bounding box of the triangle's rounded vertices within [tmin, tmax] (or if it is
// nowhere): the exact ray cannot touch the triangle at t. A reference method (any but watertight)
// can still report a hit there: rounding puts a ray that passes just outside a vertex onto the
// triangle, or a distance underflows (t = 0 for a true 1e-307). Brute force then finds it and the
// BVH, which culls boxes geometrically, does not. The BVH's traversal is the same for every method,
// and the watertight method is held to exact agreement.
template <typename T>
bool hitOutsideExactTriangleBox(const Soup& s, std::uint32_t triangle,
                                const laser_raycast::core::RayT<T>& ray, T t) {
  using L = long double;
  const laser_raycast::core::TriangleIndices& tri = s.triangles[triangle];
  L tnear = ray.tmin, tfar = ray.tmax;
  for (int k = 0; k < 3; ++k) {
    L lo = std::numeric_limits<L>::infinity(), hi = -lo;
    for (const std::uint32_t v : tri) {
      lo = std::min<L>(lo, static_cast<T>(s.vertices[v][k]));
      hi = std::max<L>(hi, static_cast<T>(s.vertices[v][k]));
    }
    const L o = ray.origin[k], d = ray.dir[k];
    if (d == 0) {
      if (o < lo || o > hi) return true;
      continue;
    }
    const L t0 = (lo - o) / d, t1 = (hi - o) / d;
    tnear = std::max(tnear, std::min(t0, t1));
    tfar = std::min(tfar, std::max(t0, t1));
  }
  return !(tnear <= t && t <= tfar);
}

}  // namespace laser_raycast_test
