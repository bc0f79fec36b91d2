// The box tests of a bundle of rays that leave from one point with directions known only within
// bounds, axis by axis: a divergent beam's sub-rays, walked through a subtree together (one walk,
// one box test a node for all of them, instead of a walk each).
#pragma once

#include <emmintrin.h>

#include <Eigen/Core>
#include <limits>

#include "accel/wide_bvh.h"
#include "util/float_rounding.h"

namespace laser_raycast {
namespace core {

// A ray from the walk's origin whose direction's component k may be anything in [lo[k], hi[k]]:
// it enters a box if some direction within those bounds does. On an axis where the bounds have one
// sign, a slab plane is reached at (plane - origin) / d, which over d in [lo, hi] is smallest and
// largest at the two ends: the entry is the smaller of the quotients by the ends for the near
// plane, the exit the larger for the far one. An axis whose bounds hold 0 (or come within
// kFreeComponent of it) bounds nothing. The rounding is WideSlabRay's: the bounds rounded outward
// to float, each plane measured from the origin rounded towards the ray, the exit widened by
// 1 + 2 gamma(3). So a box that a ray of the bundle enters before the cull limit is entered, no
// later than that ray enters it.
class WideBundleRay : public WideSlabRay<3> {
 public:
  // origin: the walk's; lo, hi: bounds on the rays' unit directions, in the tree's frame.
  WideBundleRay(const Origin& origin, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    reach_ = origin.reach;
    tnear0_ = origin.tnear0;
    for (int k = 0; k < 3; ++k) {
      const float l = floatBelow(lo[k]), h = floatAbove(hi[k]);
      free_[k] = !(l >= kFreeComponent || h <= -kFreeComponent);
      if (free_[k]) continue;
      // The planes and the origin's rounding by the bounds' sign (both ends have it).
      setAxis(k, l > 0 ? 1.0 : -1.0, origin.up[k], origin.down[k]);
      inv_lo_[k] = 1.0f / l;
      inv_hi_[k] = 1.0f / h;
    }
  }

  // As WideSlabRay::enter: the children the bundle may enter at or before `cull`, and where.
  LASER_RAYCAST_HOT_INLINE int enter(const WideBvh::Node& node, float cull,
                                     float t_entry[4]) const {
    const char* base = reinterpret_cast<const char*>(&node);
    __m128 tnear = _mm_set1_ps(tnear0_);
    __m128 tfar = _mm_set1_ps(std::numeric_limits<float>::infinity());
    for (int k = 0; k < 3; ++k) {
      if (free_[k]) continue;
      const __m128 near_plane = _mm_load_ps(reinterpret_cast<const float*>(base + near_offset_[k]));
      const __m128 far_plane = _mm_load_ps(reinterpret_cast<const float*>(base + far_offset_[k]));
      const __m128 lo = _mm_set1_ps(inv_lo_[k]), hi = _mm_set1_ps(inv_hi_[k]);
      const __m128 to_near = _mm_sub_ps(near_plane, _mm_set1_ps(origin_near_[k]));
      const __m128 to_far = _mm_sub_ps(far_plane, _mm_set1_ps(origin_far_[k]));
      // NaN never narrows the interval (maxps and minps return their second operand).
      tnear = _mm_max_ps(_mm_min_ps(_mm_mul_ps(to_near, lo), _mm_mul_ps(to_near, hi)), tnear);
      tfar = _mm_min_ps(_mm_max_ps(_mm_mul_ps(to_far, lo), _mm_mul_ps(to_far, hi)), tfar);
    }
    tfar = _mm_min_ps(_mm_mul_ps(tfar, _mm_set1_ps(kWidenExit)), _mm_set1_ps(cull));
    _mm_storeu_ps(t_entry, tnear);
    return _mm_movemask_ps(_mm_cmple_ps(tnear, tfar)) & node.presentMask();
  }

 private:
  // Bounds nearer 0 than this leave their axis free: their reciprocals could overflow a float.
  static constexpr float kFreeComponent = 1e-30f;
  bool free_[3] = {};
  float inv_lo_[3] = {}, inv_hi_[3] = {};
};

}  // namespace core
}  // namespace laser_raycast
