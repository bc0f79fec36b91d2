// A conservative pre-test of beams against one triangle, four beams at a time in float (SSE2).
//
// Every beam starts at the sensor, so a beam d passes through triangle (a, b, c) (sensor frame)
// exactly where the three scalar triple products [d, b, c], [d, c, a], [d, a, b] all have the sign
// of [a, b, c]: d is then a non-negative combination of a, b and c. A beam is let through unless
// one of them is clearly of the other sign, by more than a margin far above the float rounding;
// the exact triangle test decides for the beams let through. Nor is a beam let through whose
// current range is clearly nearer than where it would meet the triangle's plane, t = |n.a| / |n.d|
// for the plane's normal n: the hit could not be kept. So no beam whose exact hit would be kept is
// ever held back.
#pragma once

#include <emmintrin.h>

#include <Eigen/Geometry>
#include <cmath>

#include "beams/beam_set.h"
#include "beams/column_raster.h"

namespace laser_raycast {
namespace core {

class EdgeFilter {
 public:
  EdgeFilter(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
    const Eigen::Vector3d n[3] = {b.cross(c), c.cross(a), a.cross(b)};
    const double det = a.dot(n[0]);
    // Seen edge-on (the triangle's plane passes by the sensor) the signs say little: test all.
    all_ = !(std::abs(det) > kEdgeOnRatio * a.norm() * b.norm() * c.norm());
    const double sign = det > 0 ? 1 : -1;
    // The plane: |n.a| rounded down, n in float with the margin of its dot products.
    const Eigen::Vector3d plane = (b - a).cross(c - a);
    for (int i = 0; i < 3; ++i) plane_[i] = _mm_set1_ps(static_cast<float>(plane[i]));
    plane_margin_ = _mm_set1_ps(static_cast<float>(kMarginRatio * plane.lpNorm<1>()));
    plane_distance_ = _mm_set1_ps(static_cast<float>(std::abs(plane.dot(a)) * (1 - kMarginRatio)));
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d oriented = sign * n[k];
      for (int i = 0; i < 3; ++i) normal_[k][i] = _mm_set1_ps(static_cast<float>(oriented[i]));
      // The float dot product with a unit direction errs by a few ulps of |n|_1 (the rounding of
      // d and n to float included); the margin is far larger.
      margin_[k] = _mm_set1_ps(static_cast<float>(-kMarginRatio * oriented.lpNorm<1>()));
    }
  }

  // Calls f(col) for every column of [first, last] in row whose beam may pass through the
  // triangle, in increasing order.
  template <class F>
  void forEachCandidate(const BeamSet& beams, int row, int first, int last, F&& f) const {
    if (all_) {
      for (int col = first; col <= last; ++col) f(col);
      return;
    }
    const float* x = beams.grid().directionX(row);
    const float* y = beams.grid().directionY(row);
    const float* range = beams.rangeAbove(row);
    const __m128 z = _mm_set1_ps(beams.grid().directionZ(row));
    const __m128 sign_bit = _mm_set1_ps(-0.0f);
    for (int base = first & ~3; base <= last; base += 4) {
      const __m128 dx = _mm_loadu_ps(x + base), dy = _mm_loadu_ps(y + base);
      __m128 inside = _mm_castsi128_ps(_mm_set1_epi32(-1));
      for (int k = 0; k < 3; ++k) {
        const __m128 dot =
            _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, normal_[k][0]), _mm_mul_ps(dy, normal_[k][1])),
                       _mm_mul_ps(z, normal_[k][2]));
        inside = _mm_and_ps(inside, _mm_cmpge_ps(dot, margin_[k]));
      }
      // Written so that a NaN range (a beam that could not be cast) is never held back.
      const __m128 along = _mm_add_ps(
          _mm_andnot_ps(sign_bit,
                        _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, plane_[0]), _mm_mul_ps(dy, plane_[1])),
                                   _mm_mul_ps(z, plane_[2]))),
          plane_margin_);
      const __m128 beyond =
          _mm_cmpgt_ps(plane_distance_, _mm_mul_ps(_mm_loadu_ps(range + base), along));
      inside = _mm_andnot_ps(beyond, inside);
      int mask = _mm_movemask_ps(inside);
      while (mask) {
        const int col = base + __builtin_ctz(static_cast<unsigned>(mask));
        mask &= mask - 1;
        if (col >= first && col <= last) f(col);
      }
    }
  }

 private:
  // The margin, as a fraction of |n|_1: about 30 times the float rounding it has to cover.
  static constexpr double kMarginRatio = 4e-6;

  bool all_;
  __m128 normal_[3][3];    // [edge][axis], oriented so that inside is positive
  __m128 margin_[3];       // minus the margin, per edge
  __m128 plane_[3];        // the plane's normal n
  __m128 plane_margin_;    // the rounding of n.d, in float, with room to spare
  __m128 plane_distance_;  // |n.a|, rounded down
};

}  // namespace core
}  // namespace laser_raycast
