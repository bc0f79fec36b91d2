// A cheap test that a ray from the origin passes beside a triangle, before its exact test: for a
// bundle's sub-rays that all leave from the reference sensor's origin, unturned (a divergent
// beam's, a cell's of beams off any grid), where a cell's many sub-rays near a small triangle
// would each cost the exact test.
#pragma once

#include <Eigen/Core>

namespace laser_raycast {
namespace core {

// A ray d from the origin passes through triangle (a, b, c) only if its triple products with the
// edges, d.(b x c), d.(c x a) and d.(a x b), share a sign (zeros aside). Where they clearly do not
// (each beyond 1e-12 of the product of its edge's corners' 1-norms, |b|_1 |c|_1 for b x c: far
// above the rounding of these products and of the exact test's edge functions, which are the same
// products seen along d), the exact test finds no hit either.
class SubRayFilter {
 public:
  SubRayFilter(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c)
      : m_{b.cross(c), c.cross(a), a.cross(b)},
        tol_{kTolerance * b.cwiseAbs().sum() * c.cwiseAbs().sum(),
             kTolerance * c.cwiseAbs().sum() * a.cwiseAbs().sum(),
             kTolerance * a.cwiseAbs().sum() * b.cwiseAbs().sum()} {}

  bool misses(const Eigen::Vector3d& d) const {
    bool below = false, above = false;
    for (int i = 0; i < 3; ++i) {
      const double e = m_[i].dot(d);
      below = below || e < -tol_[i];
      above = above || e > tol_[i];
    }
    return below && above;
  }

 private:
  static constexpr double kTolerance = 1e-12;
  Eigen::Vector3d m_[3];
  double tol_[3];
};

}  // namespace core
}  // namespace laser_raycast
