// Axis-aligned bounding box and the conservative ray/box slab test.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

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
    const T largest = ray.dir.cwiseAbs().maxCoeff();
    for (int k = 0; k < 3; ++k) {
      // Adding +0 turns -0 into +0, so a zero component always gives +inf. With -inf, a ray lying
      // exactly in a box face would get (face - origin) * inv = 0 * -inf paired with a -inf bound
      // and miss the box.
      inv_dir[k] = T(1) / (ray.dir[k] + T(0));
      // A nonzero component below the smallest normal number times the largest one: the
      // watertight test's shear (this component over the largest) underflows, so the ray it tests
      // can differ from this one by more than any widening of t covers (found by
      // test/fuzz/fuzz_core). NaN makes the slab test ignore this axis (see below): conservative.
      if (ray.dir[k] != 0 && std::abs(ray.dir[k]) < largest * std::numeric_limits<T>::min()) {
        inv_dir[k] = std::numeric_limits<T>::quiet_NaN();
      }
    }
  }
};

// Conservative slab test (Ize, "Robust BVH Ray Traversal", JCGT 2013): the far distance is enlarged
// by 1 + 2 * gamma(3) so that rounding never culls a box the exact ray touches. Ize's ray starts at
// t = 0; for a box behind the origin (negative tmin) the same bound holds mirrored, with the near
// distance as the one to enlarge: each end is scaled by 1 + 2 gamma(3) where that moves it away
// from the box (the far end when positive, the near end when negative), never towards it. True if
// the ray meets the box within [ray.tmin, tmax]; *t_entry is then where it enters (clamped to
// ray.tmin).
//
// A zero direction component gives inv_dir = +inf. Then (bound - origin) * inv_dir is +-inf when
// the origin is strictly inside or outside that slab, and NaN when it lies exactly on a face. The
// comparisons below are ordered so that a NaN never tightens the interval: the ray is then treated
// as inside that slab, which is the conservative answer for a ray lying in a box face (and for an
// axis SlabRay marks with inv_dir = NaN).
// The box is given as its corners' coordinates (B may be float for a double ray: the box is then
// converted exactly).
template <typename T, typename B>
inline bool slabTest(const SlabRay<T>& ray, const B* lo, const B* hi, T tmax, T* t_entry) {
  T tnear = ray.tmin;
  T tfar = std::numeric_limits<T>::infinity();
  for (int k = 0; k < 3; ++k) {
    const T t0 = (static_cast<T>(lo[k]) - ray.origin[k]) * ray.inv_dir[k];
    const T t1 = (static_cast<T>(hi[k]) - ray.origin[k]) * ray.inv_dir[k];
    // NaN in t1 keeps t0; NaN in t0 stays NaN and is ignored below.
    const T near_k = t1 < t0 ? t1 : t0;
    const T far_k = t0 > t1 ? t0 : t1;        // likewise, NaN in t0 picks t1
    tnear = near_k > tnear ? near_k : tnear;  // NaN never replaces tnear
    tfar = far_k < tfar ? far_k : tfar;       // NaN never replaces tfar
  }
  // Enlarging the nearest exit equals enlarging each exit (rounding is monotonic), for one
  // multiply; likewise the farthest entry.
  constexpr T kEnlarge = 1 + 2 * roundingGamma<T>(3);
  tfar = tfar * kEnlarge > tfar ? tfar * kEnlarge : tfar;       // positive: moved up
  tnear = tnear * kEnlarge < tnear ? tnear * kEnlarge : tnear;  // negative: moved down
  tfar = tfar < tmax ? tfar : tmax;
  *t_entry = tnear;
  return tnear <= tfar;
}

// The same test for two boxes at once (lo[k] and hi[k] are box k's corners): a BVH node's two
// children. With SSE2 the two boxes share each instruction; the comparisons map one to one onto
// minpd/maxpd, which return their second operand when either is NaN, exactly as the scalar selects
// above do.
template <typename T, typename B>
inline void slabTestPair(const SlabRay<T>& ray, const B (*lo)[3], const B (*hi)[3], T tmax,
                         T* t_entry0, T* t_entry1, bool* hit0, bool* hit1) {
  *hit0 = slabTest(ray, lo[0], hi[0], tmax, t_entry0);
  *hit1 = slabTest(ray, lo[1], hi[1], tmax, t_entry1);
}

#ifdef __SSE2__
template <typename B>
inline void slabTestPair(const SlabRay<double>& ray, const B (*lo)[3], const B (*hi)[3],
                         double tmax, double* t_entry0, double* t_entry1, bool* hit0, bool* hit1) {
  __m128d tnear = _mm_set1_pd(ray.tmin);
  __m128d tfar = _mm_set1_pd(std::numeric_limits<double>::infinity());
  for (int k = 0; k < 3; ++k) {
    const __m128d origin = _mm_set1_pd(ray.origin[k]);
    const __m128d inv = _mm_set1_pd(ray.inv_dir[k]);
    const __m128d t0 = _mm_mul_pd(_mm_sub_pd(_mm_set_pd(lo[1][k], lo[0][k]), origin), inv);
    const __m128d t1 = _mm_mul_pd(_mm_sub_pd(_mm_set_pd(hi[1][k], hi[0][k]), origin), inv);
    const __m128d near_k = _mm_min_pd(t1, t0);  // t1 < t0 ? t1 : t0
    const __m128d far_k = _mm_max_pd(t0, t1);   // t0 > t1 ? t0 : t1
    tnear = _mm_max_pd(near_k, tnear);          // near_k > tnear ? near_k : tnear
    tfar = _mm_min_pd(far_k, tfar);             // far_k < tfar ? far_k : tfar
  }
  const __m128d enlarge = _mm_set1_pd(1 + 2 * roundingGamma<double>(3));
  tfar = _mm_max_pd(_mm_mul_pd(tfar, enlarge), tfar);     // the larger: positive moved up
  tnear = _mm_min_pd(_mm_mul_pd(tnear, enlarge), tnear);  // the smaller: negative moved down
  tfar = _mm_min_pd(tfar, _mm_set1_pd(tmax));
  const int hits = _mm_movemask_pd(_mm_cmple_pd(tnear, tfar));
  double entries[2];
  _mm_storeu_pd(entries, tnear);
  *t_entry0 = entries[0];
  *t_entry1 = entries[1];
  *hit0 = (hits & 1) != 0;
  *hit1 = (hits & 2) != 0;
}
#endif

template <typename T>
inline bool slabTest(const SlabRay<T>& ray, const AabbT<T>& box, T tmax, T* t_entry) {
  return slabTest(ray, box.lo.data(), box.hi.data(), tmax, t_entry);
}

}  // namespace core
}  // namespace laser_raycast
