#include "laser_raycast/core/primitives.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace laser_raycast {
namespace core {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kMaxFinite = std::numeric_limits<double>::max();

// The two roots of a t^2 + 2 b t + c = 0, given the discriminant b^2 - a c. It is passed in because
// the callers compute it without cancellation (see sphere and cylinder). Returns false if there is
// no real root.
bool solveQuadratic(double a, double b, double c, double discriminant, double* t0, double* t1) {
  if (!(discriminant >= 0)) return false;
  // q has the sign of -b, so -b and the root never cancel.
  const double q = -(b + std::copysign(std::sqrt(discriminant), b));
  if (q == 0) {  // b == 0 and discriminant == 0: a double root at 0
    *t0 = *t1 = 0;
    return true;
  }
  *t0 = q / a;
  *t1 = c / q;
  if (*t0 > *t1) std::swap(*t0, *t1);
  return true;
}

void requirePositive(const char* what, double value) {
  if (!(std::isfinite(value) && value > 0)) {
    std::ostringstream msg;
    msg << what << " must be finite and > 0, got " << value;
    throw std::invalid_argument(msg.str());
  }
}

// Keeps the nearest accepted candidate: t in [tmin, tmax] and finite. A distance that overflowed
// to +-Inf (a tiny direction, a far or huge primitive) is no hit, even with tmax = +Inf.
struct Nearest {
  double tmin, tmax;
  std::optional<PrimitiveHit> hit;
  void offer(double t, const Eigen::Vector3d& normal) {
    const bool accepted = t >= tmin && t <= tmax && std::abs(t) <= kMaxFinite;
    if (accepted && (!hit || t < hit->t)) hit = PrimitiveHit{t, normal};
  }
};

}  // namespace

std::optional<PrimitiveHit> intersect(const Ray& ray, const Box& box) {
  if (!isValidRay(ray)) return std::nullopt;
  return detail::intersectValid(ray, box);
}

namespace detail {

std::optional<PrimitiveHit> intersectValid(const Ray& ray, const Box& box) {
  const Eigen::Vector3d half = box.size * 0.5;
  double t_enter = -kInf, t_exit = kInf;
  int enter_axis = -1, exit_axis = -1;
  for (int k = 0; k < 3; ++k) {
    const double o = ray.origin[k], d = ray.dir[k];
    if (d == 0) {
      if (o < -half[k] || o > half[k]) return std::nullopt;  // parallel to and outside this slab
      continue;
    }
    double t0 = (-half[k] - o) / d;
    double t1 = (half[k] - o) / d;
    if (t0 > t1) std::swap(t0, t1);
    // The first moving axis always sets the axes: when every distance overflows to +-inf, none is
    // strictly beyond the initial +-inf, and the normals below would be indexed with -1.
    if (enter_axis < 0 || t0 > t_enter) {
      t_enter = t0;
      enter_axis = k;
    }
    if (exit_axis < 0 || t1 < t_exit) {
      t_exit = t1;
      exit_axis = k;
    }
  }
  if (!(t_enter <= t_exit)) return std::nullopt;
  Nearest nearest{ray.tmin, ray.tmax, std::nullopt};
  // Entering, the normal opposes the direction on the entry axis; leaving, it follows it on the
  // exit axis.
  Eigen::Vector3d n_enter = Eigen::Vector3d::Zero(), n_exit = Eigen::Vector3d::Zero();
  n_enter[enter_axis] = ray.dir[enter_axis] > 0 ? -1.0 : 1.0;
  n_exit[exit_axis] = ray.dir[exit_axis] > 0 ? 1.0 : -1.0;
  nearest.offer(t_enter, n_enter);
  if (!nearest.hit) nearest.offer(t_exit, n_exit);
  return nearest.hit;
}

}  // namespace detail

std::optional<PrimitiveHit> intersect(const Ray& ray, const Sphere& sphere) {
  if (!isValidRay(ray)) return std::nullopt;
  return detail::intersectValid(ray, sphere);
}

namespace detail {

std::optional<PrimitiveHit> intersectValid(const Ray& ray, const Sphere& sphere) {
  const Eigen::Vector3d& o = ray.origin;
  const Eigen::Vector3d& d = ray.dir;
  const double r = sphere.radius;
  const double a = d.squaredNorm();
  const double b = o.dot(d);
  const double c = o.squaredNorm() - r * r;
  // b^2 - a c = a (r^2 - |f|^2), f the point of the ray's line nearest the centre: no cancellation
  // when the origin is far from the sphere (pbrt-v4's formulation).
  const double f = (o - (b / a) * d).norm();
  const double discriminant = a * (r - f) * (r + f);
  double t0, t1;
  if (!solveQuadratic(a, b, c, discriminant, &t0, &t1)) return std::nullopt;
  Nearest nearest{ray.tmin, ray.tmax, std::nullopt};
  for (const double t : {t0, t1}) nearest.offer(t, (o + t * d) / r);
  return nearest.hit;
}

}  // namespace detail

std::optional<PrimitiveHit> intersect(const Ray& ray, const Cylinder& cylinder) {
  if (!isValidRay(ray)) return std::nullopt;
  return detail::intersectValid(ray, cylinder);
}

namespace detail {

std::optional<PrimitiveHit> intersectValid(const Ray& ray, const Cylinder& cylinder) {
  const Eigen::Vector3d& o = ray.origin;
  const Eigen::Vector3d& d = ray.dir;
  const double r = cylinder.radius;
  const double h = cylinder.length * 0.5;

  // The solid is the infinite tube x^2 + y^2 <= r^2 cut by the slab |z| <= h. Each gives the
  // interval of t where the ray is inside it; the surface is crossed where the intersection of the
  // two intervals begins and ends, on whichever surface bounds it there (the box's slab test, with
  // the tube as one slab). Testing each surface's hit point against the other surface instead (|z|
  // <= h for the side, inside the disc for a cap) lets rounding reject both near the rim, and rays
  // slip out between side and cap.
  double tube_in = -kInf, tube_out = kInf;
  const double a = d.x() * d.x() + d.y() * d.y();
  if (a > 0) {
    const double b = o.x() * d.x() + o.y() * d.y();
    const double c = o.x() * o.x() + o.y() * o.y() - r * r;
    const Eigen::Vector2d f(o.x() - (b / a) * d.x(), o.y() - (b / a) * d.y());
    const double fn = f.norm();
    const double discriminant = a * (r - fn) * (r + fn);
    if (!solveQuadratic(a, b, c, discriminant, &tube_in, &tube_out)) return std::nullopt;
  } else if (o.x() * o.x() + o.y() * o.y() > r * r) {
    // Parallel to the axis and outside the tube. A ray exactly on the side surface is inside: it
    // meets the rim of a cap.
    return std::nullopt;
  }
  double slab_in = -kInf, slab_out = kInf;
  if (d.z() != 0) {
    slab_in = (-h - o.z()) / d.z();
    slab_out = (h - o.z()) / d.z();
    if (slab_in > slab_out) std::swap(slab_in, slab_out);
  } else if (std::abs(o.z()) > h) {
    return std::nullopt;  // parallel to the caps, outside the slab
  }
  const bool enter_side = tube_in > slab_in;  // otherwise through a cap
  const bool exit_side = tube_out < slab_out;
  const double t_enter = enter_side ? tube_in : slab_in;
  const double t_exit = exit_side ? tube_out : slab_out;
  if (!(t_enter <= t_exit)) return std::nullopt;

  auto side_normal = [&](double t) {
    const Eigen::Vector3d p = o + t * d;
    return Eigen::Vector3d(p.x() / r, p.y() / r, 0.0);
  };
  // Through a cap the ray enters against its normal and leaves along it.
  const Eigen::Vector3d cap_exit_normal(0.0, 0.0, d.z() > 0 ? 1.0 : -1.0);
  Nearest nearest{ray.tmin, ray.tmax, std::nullopt};
  nearest.offer(t_enter, enter_side ? side_normal(t_enter) : Eigen::Vector3d(-cap_exit_normal));
  if (!nearest.hit) nearest.offer(t_exit, exit_side ? side_normal(t_exit) : cap_exit_normal);
  return nearest.hit;
}

}  // namespace detail

void validate(const Box& box) {
  requirePositive("box size x", box.size.x());
  requirePositive("box size y", box.size.y());
  requirePositive("box size z", box.size.z());
}

void validate(const Cylinder& cylinder) {
  requirePositive("cylinder radius", cylinder.radius);
  requirePositive("cylinder length", cylinder.length);
}

void validate(const Sphere& sphere) { requirePositive("sphere radius", sphere.radius); }

}  // namespace core
}  // namespace laser_raycast
