// A ray with a parametric interval, in double (production) or float (for the error study).
#pragma once

#include <Eigen/Geometry>
#include <limits>

namespace laser_raycast {
namespace core {

template <typename T>
using Vec3 = Eigen::Matrix<T, 3, 1>;

// Points on the ray are origin + t * dir for t in [tmin, tmax]. Triangle and primitive tests report
// t in units of |dir|; the caster uses unit directions, so there t is a distance in metres.
template <typename T>
struct RayT {
  Vec3<T> origin = Vec3<T>::Zero();
  Vec3<T> dir = Vec3<T>::UnitX();
  T tmin = 0;
  T tmax = std::numeric_limits<T>::infinity();
};

using Ray = RayT<double>;
using RayF = RayT<float>;

// True if origin and direction are finite and the direction is not zero. A ray failing this gives
// no hit anywhere; the caster reports it as an erroneous beam (NaN, REP 117) without testing any
// geometry.
template <typename T>
bool isValidRay(const RayT<T>& ray) {
  return ray.origin.allFinite() && ray.dir.allFinite() && ray.dir.squaredNorm() > T(0);
}

template <typename T>
RayT<float> toFloat(const RayT<T>& ray) {
  RayT<float> r;
  r.origin = ray.origin.template cast<float>();
  r.dir = ray.dir.template cast<float>();
  r.tmin = static_cast<float>(ray.tmin);
  r.tmax = static_cast<float>(ray.tmax);
  return r;
}

}  // namespace core
}  // namespace laser_raycast
