// A 3x3 matrix (or the linear part of an affine pose) times a 3-vector, written out so that the
// compiler always inlines it. Written as Eigen's product, GCC compiles the fixed-size product out
// of line in the hottest callers (a sweep's every sub-ray and box ray), through temporaries on the
// stack. The sums are Eigen 3.4's, in its order, so that the bits are the product's (the core is
// compiled without contraction into fused multiply-adds): rows 0 and 1 as one SSE2 packet,
// (m(i,0) v0 + m(i,1) v1) + m(i,2) v2, and row 2 as its unrolled sum of the row's three terms,
// split in halves, m(2,0) v0 + (m(2,1) v1 + m(2,2) v2). test_recorded_ranges holds the bits of
// sweeps.
#pragma once

#include <Eigen/Core>

namespace laser_raycast {
namespace core {

template <class Matrix>
__attribute__((always_inline)) inline Eigen::Vector3d turn(const Matrix& m,
                                                           const Eigen::Vector3d& v) {
  return Eigen::Vector3d(m(0, 0) * v.x() + m(0, 1) * v.y() + m(0, 2) * v.z(),
                         m(1, 0) * v.x() + m(1, 1) * v.y() + m(1, 2) * v.z(),
                         m(2, 0) * v.x() + (m(2, 1) * v.y() + m(2, 2) * v.z()));
}

}  // namespace core
}  // namespace laser_raycast
