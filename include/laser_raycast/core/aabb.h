// Axis-aligned bounding box and the conservative ray/box slab test.
#pragma once

#include <algorithm>
#include <limits>

#include "laser_raycast/core/ray.h"

namespace laser_raycast {
namespace core {

template <typename T>
struct AabbT {
  Vec3<T> lo = Vec3<T>::Constant(std::numeric_limits<T>::infinity());
  Vec3<T> hi = Vec3<T>::Constant(-std::numeric_limits<T>::infinity());

  bool empty() const { return !(lo.x() <= hi.x() && lo.y() <= hi.y() && lo.z() <= hi.z()); }
  void grow(const Vec3<T>& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void grow(const AabbT& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  Vec3<T> center() const { return (lo + hi) * T(0.5); }
  Vec3<T> extent() const { return hi - lo; }
  // Half the surface area; the SAH only needs ratios.
  T halfArea() const {
    if (empty()) return T(0);
    const Vec3<T> e = extent();
    return e.x() * e.y() + e.y() * e.z() + e.z() * e.x();
  }
};

using Aabb = AabbT<double>;

// n * u / (1 - n * u), the bound on the relative error of n chained roundings (pbrt's gamma).
template <typename T>
constexpr T roundingGamma(int n) {
  const T u = std::numeric_limits<T>::epsilon() / 2;
  return n * u / (1 - n * u);
}

// A ray prepared for many slab tests: the reciprocal direction, computed once.
template <typename T>
struct SlabRay {
  Vec3<T> origin;
  Vec3<T> inv_dir;
  T tmin, tmax;

  explicit SlabRay(const RayT<T>& ray) : origin(ray.origin), tmin(ray.tmin), tmax(ray.tmax) {
    for (int k = 0; k < 3; ++k) {
      // Adding +0 turns -0 into +0, so a zero component always gives +inf. With -inf, a ray lying
      // exactly in a box face would get (face - origin) * inv = 0 * -inf paired with a -inf bound
      // and miss the box.
      inv_dir[k] = T(1) / (ray.dir[k] + T(0));
    }
  }
};

// Conservative slab test (Ize, "Robust BVH Ray Traversal", JCGT 2013): the far distance is enlarged
// by 1 + 2 * gamma(3) so that rounding never culls a box the exact ray touches. True if the ray
// meets the box within [ray.tmin, tmax]; *t_entry is then where it enters (clamped to ray.tmin).
//
// A zero direction component gives inv_dir = +inf. Then (bound - origin) * inv_dir is +-inf when
// the origin is strictly inside or outside that slab, and NaN when it lies exactly on a face. The
// comparisons below are ordered so that a NaN never tightens the interval: the ray is then treated
// as inside that slab, which is the conservative answer for a ray lying in a box face.
template <typename T>
inline bool slabTest(const SlabRay<T>& ray, const AabbT<T>& box, T tmax, T* t_entry) {
  T tnear = ray.tmin;
  T tfar = tmax;
  for (int k = 0; k < 3; ++k) {
    const T t0 = (box.lo[k] - ray.origin[k]) * ray.inv_dir[k];
    const T t1 = (box.hi[k] - ray.origin[k]) * ray.inv_dir[k];
    const T near_k =
        t1 < t0 ? t1 : t0;        // NaN in t1 keeps t0; NaN in t0 stays NaN and is ignored below
    T far_k = t0 > t1 ? t0 : t1;  // likewise, NaN in t0 picks t1
    far_k *= 1 + 2 * roundingGamma<T>(3);
    tnear = near_k > tnear ? near_k : tnear;  // NaN never replaces tnear
    tfar = far_k < tfar ? far_k : tfar;       // NaN never replaces tfar
  }
  *t_entry = tnear;
  return tnear <= tfar;
}

}  // namespace core
}  // namespace laser_raycast
