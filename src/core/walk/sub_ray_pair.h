// Two rays from the sensor's origin against one triangle with the watertight test, side by side in
// SSE2's two double lanes: a bundle's sub-rays, whose shears are kept (BeamSet::subShears), meet
// the triangles of a raster a beam's worth at a time, and one by one each test waited on its own
// chain of products.
#pragma once

#include <emmintrin.h>

#include <Eigen/Core>
#include <limits>
#include <optional>

#include "laser_raycast/core/triangle.h"

namespace laser_raycast {
namespace core {

using WatertightRay = PreparedRay<double, TriangleMethod::kWatertight>;

// The test of the ray from the origin with shear `shear` (tmin, cull_backfaces as the cast's)
// against triangle (a, b, c), out to tmax: PreparedRay's.
inline std::optional<TriangleHitT<double>> intersectFromOrigin(
    const WatertightRay::Shear& shear, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
    const Eigen::Vector3d& c, double tmin, bool cull_backfaces, double tmax) {
  return WatertightRay(Eigen::Vector3d::Zero(), tmin, cull_backfaces, shear)
      .intersect(a, b, c, tmax);
}

// Both rays' tests (intersectFromOrigin for shear[k] out to tmax[k]), their shears of one
// permutation (kx, ky, kz): bit k of the result is set iff ray k hits, at t[k]. Each lane does the
// scalar test's operations in its order (SSE2 has no fused multiply-add to change a rounding), so
// its hits are the scalar test's bits; a lane that would leave the common path there (an edge
// function within rounding of 0, which takes the exact sign; a ray on an edge or vertex; a hit
// distance beyond a double's range) is tested by the scalar test itself.
inline int intersectPairFromOrigin(const WatertightRay::Shear& s0, const WatertightRay::Shear& s1,
                                   const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                   const Eigen::Vector3d& c, double tmin, bool cull_backfaces,
                                   const double tmax[2], double t[2]) {
  const int kx = s0.kx, ky = s0.ky, kz = s0.kz;
  const __m128d sx = _mm_set_pd(s1.sx, s0.sx), sy = _mm_set_pd(s1.sy, s0.sy),
                sz = _mm_set_pd(s1.sz, s0.sz);
  const __m128d a_z = _mm_set1_pd(a[kz]), b_z = _mm_set1_pd(b[kz]), c_z = _mm_set1_pd(c[kz]);
  const __m128d ax = _mm_sub_pd(_mm_set1_pd(a[kx]), _mm_mul_pd(sx, a_z));
  const __m128d ay = _mm_sub_pd(_mm_set1_pd(a[ky]), _mm_mul_pd(sy, a_z));
  const __m128d bx = _mm_sub_pd(_mm_set1_pd(b[kx]), _mm_mul_pd(sx, b_z));
  const __m128d by = _mm_sub_pd(_mm_set1_pd(b[ky]), _mm_mul_pd(sy, b_z));
  const __m128d cx = _mm_sub_pd(_mm_set1_pd(c[kx]), _mm_mul_pd(sx, c_z));
  const __m128d cy = _mm_sub_pd(_mm_set1_pd(c[ky]), _mm_mul_pd(sy, c_z));

  const __m128d sign = _mm_set1_pd(-0.0);
  const auto abs = [&](__m128d v) { return _mm_andnot_pd(sign, v); };
  const __m128d zero = _mm_setzero_pd();
  constexpr double kMax = std::numeric_limits<double>::max();
  const __m128d max = _mm_set1_pd(kMax);
  // detail::edgeFunction: p q - r s where that is clearly not 0 by its rounding; the lanes where
  // it is not are returned (they need the exact sign).
  int exact = 0;
  const auto edge = [&](__m128d p, __m128d q, __m128d r, __m128d s) {
    const __m128d pq = _mm_mul_pd(p, q), rs = _mm_mul_pd(r, s);
    const __m128d e = _mm_sub_pd(pq, rs);
    const __m128d bound = _mm_add_pd(_mm_mul_pd(_mm_set1_pd(std::numeric_limits<double>::epsilon()),
                                                _mm_add_pd(abs(pq), abs(rs))),
                                     _mm_set1_pd(std::numeric_limits<double>::denorm_min()));
    exact |= ~_mm_movemask_pd(_mm_cmpgt_pd(abs(e), bound)) & 3;
    return e;
  };
  const __m128d ea = edge(cx, by, cy, bx);
  const __m128d eb = edge(ax, cy, ay, cx);
  const __m128d ec = edge(bx, ay, by, ax);
  // Outside (signs on both sides), or no hit for the determinant, as the scalar test decides.
  const __m128d below =
      _mm_or_pd(_mm_or_pd(_mm_cmplt_pd(ea, zero), _mm_cmplt_pd(eb, zero)), _mm_cmplt_pd(ec, zero));
  const __m128d above =
      _mm_or_pd(_mm_or_pd(_mm_cmpgt_pd(ea, zero), _mm_cmpgt_pd(eb, zero)), _mm_cmpgt_pd(ec, zero));
  const __m128d det = _mm_add_pd(_mm_add_pd(ea, eb), ec);
  __m128d inside = _mm_andnot_pd(_mm_and_pd(below, above), _mm_cmpneq_pd(det, zero));
  if (cull_backfaces) inside = _mm_andnot_pd(_mm_cmplt_pd(det, zero), inside);
  // On an edge or a vertex: who owns it is the scalar test's to say.
  const __m128d on_edge =
      _mm_or_pd(_mm_or_pd(_mm_cmpeq_pd(ea, zero), _mm_cmpeq_pd(eb, zero)), _mm_cmpeq_pd(ec, zero));

  const __m128d az = _mm_mul_pd(sz, a_z), bz = _mm_mul_pd(sz, b_z), cz = _mm_mul_pd(sz, c_z);
  const __m128d scaled_t =
      _mm_add_pd(_mm_add_pd(_mm_mul_pd(ea, az), _mm_mul_pd(eb, bz)), _mm_mul_pd(ec, cz));
  const __m128d inv_det = _mm_div_pd(_mm_set1_pd(1.0), det);
  // Beyond a double's range: the scalar test rescales.
  const __m128d in_range =
      _mm_and_pd(_mm_and_pd(_mm_cmple_pd(abs(det), max), _mm_cmple_pd(abs(inv_det), max)),
                 _mm_cmple_pd(abs(scaled_t), max));
  const __m128d hit_t = _mm_mul_pd(scaled_t, inv_det);
  const __m128d accepted = _mm_and_pd(_mm_and_pd(_mm_cmpge_pd(hit_t, _mm_set1_pd(tmin)),
                                                 _mm_cmple_pd(hit_t, _mm_set_pd(tmax[1], tmax[0]))),
                                      _mm_cmple_pd(abs(hit_t), max));
  const int inside_mask = _mm_movemask_pd(inside);
  const int scalar =
      exact | (inside_mask & (_mm_movemask_pd(on_edge) | (~_mm_movemask_pd(in_range) & 3)));
  int hits = inside_mask & _mm_movemask_pd(accepted) & ~scalar;
  _mm_storeu_pd(t, hit_t);
  for (int k = 0; k < 2; ++k) {
    if (!(scalar & (1 << k))) continue;
    const auto hit = intersectFromOrigin(k == 0 ? s0 : s1, a, b, c, tmin, cull_backfaces, tmax[k]);
    if (hit) {
      hits |= 1 << k;
      t[k] = hit->t;
    }
  }
  return hits;
}

}  // namespace core
}  // namespace laser_raycast
