// A cheap test that a ray from the origin passes beside a triangle, before its exact test: for a
// bundle's sub-rays that all leave from the reference sensor's origin, unturned (a divergent
// beam's, a cell's of beams off any grid), where a cell's many sub-rays near a small triangle
// would each cost the exact test.
#pragma once

#include <emmintrin.h>

#include <Eigen/Core>

#include "beams/beam_set.h"
#include "laser_raycast/core/triangle.h"
#include "util/float_rounding.h"

namespace laser_raycast {
namespace core {

// A ray d from the origin passes through triangle (a, b, c) only if its triple products with the
// edges, d.(b x c), d.(c x a) and d.(a x b), share a sign (zeros aside). Where they clearly do not
// (each beyond 1e-12 of the product of its edge's corners' 1-norms, |b|_1 |c|_1 for b x c: far
// above the rounding of these products and of the exact test's edge functions, which are the same
// products seen along d), the exact test finds no hit either.
//
// Four sub-rays at a time in float where the bundle keeps its directions in float
// (BeamSet::subDirectionsFloat): the products m.d of the edges' normals m (rounded to float) with
// the unit directions (rounded to float) lie within 5 roundings of 2^-24 |m|_1 of the double
// products, so a float product beyond the tolerance plus 2^-20 |m|_1 (rounded up) is one the double
// test turns away too. A triangle whose normals are too small or too large for float (|m|_1 outside
// 1e-30 to 1e30) takes the double test.
class SubRayFilter {
 public:
  SubRayFilter(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c)
      : m_{b.cross(c), c.cross(a), a.cross(b)},
        tol_{kTolerance * b.cwiseAbs().sum() * c.cwiseAbs().sum(),
             kTolerance * c.cwiseAbs().sum() * a.cwiseAbs().sum(),
             kTolerance * a.cwiseAbs().sum() * b.cwiseAbs().sum()} {
    float_ok_ = true;
    for (int i = 0; i < 3; ++i) {
      const double norm = m_[i].cwiseAbs().sum();
      float_ok_ = float_ok_ && norm >= kFloatNormMin && norm <= kFloatNormMax;
      mx_[i] = _mm_set1_ps(static_cast<float>(m_[i].x()));
      my_[i] = _mm_set1_ps(static_cast<float>(m_[i].y()));
      mz_[i] = _mm_set1_ps(static_cast<float>(m_[i].z()));
      tol_f_[i] = _mm_set1_ps(floatAbove(tol_[i] + kFloatSlack * norm));
    }
  }

  bool misses(const Eigen::Vector3d& d) const {
    bool below = false, above = false;
    for (int i = 0; i < 3; ++i) {
      const double e = m_[i].dot(d);
      below = below || e < -tol_[i];
      above = above || e > tol_[i];
    }
    return below && above;
  }

  // f(s) for each sub-ray s from begin to end - 1 of beams' bundle, in order, that the test does
  // not turn away.
  template <class F>
  LASER_RAYCAST_HOT_INLINE void forEachPassing(const BeamSet& beams, int begin, int end,
                                               F&& f) const {
    const BeamSet::FloatDirections* dirs = beams.subDirectionsFloat();
    if (!dirs || !float_ok_) {
      for (int s = begin; s < end; ++s) {
        if (!misses(beams.subDirection(s))) f(s);
      }
      return;
    }
    for (int s = begin; s < end; s += 4) {
      // Four from s: the arrays hold three more at the end; lanes at or past end are dropped.
      const __m128 x = _mm_loadu_ps(dirs->x.data() + s);
      const __m128 y = _mm_loadu_ps(dirs->y.data() + s);
      const __m128 z = _mm_loadu_ps(dirs->z.data() + s);
      __m128 below = _mm_setzero_ps(), above = _mm_setzero_ps();
      for (int i = 0; i < 3; ++i) {
        const __m128 e = _mm_add_ps(_mm_add_ps(_mm_mul_ps(mx_[i], x), _mm_mul_ps(my_[i], y)),
                                    _mm_mul_ps(mz_[i], z));
        below = _mm_or_ps(below, _mm_cmplt_ps(e, _mm_sub_ps(_mm_setzero_ps(), tol_f_[i])));
        above = _mm_or_ps(above, _mm_cmpgt_ps(e, tol_f_[i]));
      }
      const int left = end - s;
      unsigned pass = ~static_cast<unsigned>(_mm_movemask_ps(_mm_and_ps(below, above))) &
                      (left >= 4 ? 15u : (1u << left) - 1);
      while (pass) {
        f(s + __builtin_ctz(pass));
        pass &= pass - 1;
      }
    }
  }

 private:
  static constexpr double kTolerance = 1e-12;
  static constexpr double kFloatSlack = 1.0 / (1 << 20);
  static constexpr double kFloatNormMin = 1e-30, kFloatNormMax = 1e30;
  Eigen::Vector3d m_[3];
  double tol_[3];
  bool float_ok_;
  __m128 mx_[3], my_[3], mz_[3], tol_f_[3];
};

}  // namespace core
}  // namespace laser_raycast
