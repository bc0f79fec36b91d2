#include "bench_reference.h"

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <limits>
#include <utility>

namespace laser_raycast {
namespace bench {
namespace {

constexpr Real kInfL = std::numeric_limits<Real>::infinity();

// a * b - c * d with its exact sign: the rounded difference where rounding cannot have changed
// the sign (as the core's detail::edgeFunction), otherwise Kahan's difference of products with
// fmal, whose relative error is at most 2 ulp (Jeannerod, Louvet, Muller 2013), so its sign is
// exact and it is 0 only for an exact 0. glibc's fmal is correctly rounded for x87 long double.
Real edgeFunction(Real a, Real b, Real c, Real d) {
  const Real ab = a * b;
  const Real cd = c * d;
  const Real e = ab - cd;
  if (std::fabs(e) > LDBL_EPSILON * (std::fabs(ab) + std::fabs(cd))) return e;
  const Real cd_error = std::fma(-c, d, cd);  // cd - c * d, exactly
  return std::fma(a, b, -cd) + cd_error;
}

// The core's rule (detail::ownsBoundary): a boundary point belongs to the triangle the ray would
// pass inside if nudged by one fixed infinitesimal offset.
bool ownsBoundary(Real dx, Real dy) { return dy > 0 || (dy == 0 && dx > 0); }

// Whether the ray can meet box within [tmin, limit]. The box is padded by 1e-9 of the magnitudes
// involved: long double rounds the slab distances by ~1e-19 relative, so the padded test never
// rejects a box the exact ray meets; the padding only costs a few extra triangle tests.
bool mayHit(const RayL& ray, const core::Aabb& box, Real limit) {
  Real tnear = ray.tmin, tfar = limit;
  for (int k = 0; k < 3; ++k) {
    const Real o = ray.origin[k], d = ray.dir[k];
    const Real lo0 = box.lo[k], hi0 = box.hi[k];
    const Real pad = 1e-9L * (1 + std::max({std::fabs(lo0), std::fabs(hi0), std::fabs(o)}));
    const Real lo = lo0 - pad, hi = hi0 + pad;
    if (d == 0) {
      if (o < lo || o > hi) return false;
      continue;
    }
    Real t0 = (lo - o) / d, t1 = (hi - o) / d;
    if (t0 > t1) std::swap(t0, t1);
    tnear = std::max(tnear, t0);
    tfar = std::min(tfar, t1);
    if (tnear > tfar) return false;
  }
  return true;
}

// The smallest root in [tmin, tmax] of a t^2 + 2 b t + c = 0 (a > 0), or +inf. The roots come from
// q = -(b + sign(b) sqrt(b^2 - a c)) as q / a and c / q, so neither subtracts nearly equal numbers.
Real firstRoot(Real a, Real b, Real c, Real tmin, Real tmax) {
  const Real disc = b * b - a * c;
  if (!(disc >= 0) || !(a > 0)) return kInfL;
  const Real s = std::sqrt(disc);
  const Real q = b >= 0 ? -(b + s) : -b + s;
  Real t0 = q / a, t1 = q != 0 ? c / q : t0;
  if (t0 > t1) std::swap(t0, t1);
  if (t0 >= tmin && t0 <= tmax) return t0;
  if (t1 >= tmin && t1 <= tmax) return t1;
  return kInfL;
}

}  // namespace

ReferenceRay::ReferenceRay(const RayL& ray) : origin_(ray.origin), tmin_(ray.tmin) {
  // The core's permutation: z along the largest direction component, x and y swapped when it is
  // negative so that the winding is kept.
  kz_ = 0;
  if (std::fabs(ray.dir.y()) > std::fabs(ray.dir[kz_])) kz_ = 1;
  if (std::fabs(ray.dir.z()) > std::fabs(ray.dir[kz_])) kz_ = 2;
  kx_ = kz_ == 2 ? 0 : kz_ + 1;
  ky_ = kx_ == 2 ? 0 : kx_ + 1;
  if (ray.dir[kz_] < 0) std::swap(kx_, ky_);
  sx_ = ray.dir[kx_] / ray.dir[kz_];
  sy_ = ray.dir[ky_] / ray.dir[kz_];
  sz_ = 1 / ray.dir[kz_];
}

std::optional<Real> ReferenceRay::intersect(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                            const Eigen::Vector3d& c, Real tmax) const {
  // Translate and shear: the same operations on the same inputs for every triangle sharing a
  // vertex, so a shared vertex lands on the same long double values in each.
  const Vec3L pa = a.cast<Real>() - origin_;
  const Vec3L pb = b.cast<Real>() - origin_;
  const Vec3L pc = c.cast<Real>() - origin_;
  const Real ax = pa[kx_] - sx_ * pa[kz_], ay = pa[ky_] - sy_ * pa[kz_];
  const Real bx = pb[kx_] - sx_ * pb[kz_], by = pb[ky_] - sy_ * pb[kz_];
  const Real cx = pc[kx_] - sx_ * pc[kz_], cy = pc[ky_] - sy_ * pc[kz_];

  // Edge functions with exact signs; inside iff they agree, boundary points by ownership.
  const Real ea = edgeFunction(cx, by, cy, bx);
  const Real eb = edgeFunction(ax, cy, ay, cx);
  const Real ec = edgeFunction(bx, ay, by, ax);
  if ((ea < 0 || eb < 0 || ec < 0) && (ea > 0 || eb > 0 || ec > 0)) return std::nullopt;
  const Real det = ea + eb + ec;
  if (!(det != 0)) return std::nullopt;
  if (ea == 0 || eb == 0 || ec == 0) {
    const Real s = det > 0 ? 1 : -1;
    if (ea == 0 && !ownsBoundary(s * (cx - bx), s * (cy - by))) return std::nullopt;
    if (eb == 0 && !ownsBoundary(s * (ax - cx), s * (ay - cy))) return std::nullopt;
    if (ec == 0 && !ownsBoundary(s * (bx - ax), s * (by - ay))) return std::nullopt;
  }

  // Distance along the ray: the barycentric combination of the vertices' sheared z.
  const Real t = (ea * sz_ * pa[kz_] + eb * sz_ * pb[kz_] + ec * sz_ * pc[kz_]) / det;
  if (!(t >= tmin_ && t <= tmax)) return std::nullopt;
  return t;
}

// The nearest hit among the triangle slots that visit(descend, leaf) reaches through a tree of
// boxes (a Bvh's, or a Mesh's wide BVH).
template <class Visit>
Real referenceClosestHit(const core::SlotVertices<double>& slots, Visit&& visit, const RayL& ray) {
  Real best = kInfL;
  const ReferenceRay prepared(ray);
  visit([&](const core::Aabb& box) { return mayHit(ray, box, std::min(ray.tmax, best)); },
        [&](std::uint32_t slot) {
          const auto& tri = slots[slot];
          const auto t = prepared.intersect(tri[0], tri[1], tri[2], std::min(ray.tmax, best));
          if (t && *t < best) best = *t;
        });
  return best;
}

Real referenceClosestHit(const core::Bvh& bvh, const RayL& ray) {
  return referenceClosestHit(
      bvh.triangleVertices(), [&](auto&& descend, auto&& leaf) { bvh.visit(descend, leaf); }, ray);
}

Real referenceClosestHit(const core::Mesh& mesh, const RayL& ray) {
  return referenceClosestHit(
      mesh.bvh().triangleVertices(),
      [&](auto&& descend, auto&& leaf) { mesh.visit(descend, leaf); }, ray);
}

Real referenceHit(const RayL& ray, const core::Box& box) {
  Real tnear = -kInfL, tfar = kInfL;
  for (int k = 0; k < 3; ++k) {
    const Real h = static_cast<Real>(box.size[k]) / 2;
    const Real o = ray.origin[k], d = ray.dir[k];
    if (d == 0) {
      if (o < -h || o > h) return kInfL;
      continue;
    }
    Real t0 = (-h - o) / d, t1 = (h - o) / d;
    if (t0 > t1) std::swap(t0, t1);
    tnear = std::max(tnear, t0);
    tfar = std::min(tfar, t1);
  }
  if (!(tnear <= tfar)) return kInfL;
  if (tnear >= ray.tmin && tnear <= ray.tmax) return tnear;
  if (tfar >= ray.tmin && tfar <= ray.tmax) return tfar;  // from inside, on the way out
  return kInfL;
}

Real referenceHit(const RayL& ray, const core::Cylinder& cylinder) {
  const Real r = cylinder.radius, h = static_cast<Real>(cylinder.length) / 2;
  const Vec3L& o = ray.origin;
  const Vec3L& d = ray.dir;
  Real best = kInfL;
  // Side: the first crossing of x^2 + y^2 = r^2 within the length, then the second.
  const Real a = d.x() * d.x() + d.y() * d.y();
  const Real b = o.x() * d.x() + o.y() * d.y();
  const Real c = o.x() * o.x() + o.y() * o.y() - r * r;
  const Real disc = b * b - a * c;
  if (a > 0 && disc >= 0) {
    const Real s = std::sqrt(disc);
    const Real q = b >= 0 ? -(b + s) : -b + s;
    for (const Real t : {q / a, q != 0 ? c / q : q / a}) {
      if (t >= ray.tmin && t <= ray.tmax && t < best && std::fabs(o.z() + t * d.z()) <= h) {
        best = t;
      }
    }
  }
  // Caps.
  if (d.z() != 0) {
    for (const Real z : {-h, h}) {
      const Real t = (z - o.z()) / d.z();
      const Real x = o.x() + t * d.x(), y = o.y() + t * d.y();
      if (t >= ray.tmin && t <= ray.tmax && t < best && x * x + y * y <= r * r) best = t;
    }
  }
  return best;
}

Real referenceHit(const RayL& ray, const core::Sphere& sphere) {
  const Real r = sphere.radius;
  return firstRoot(ray.dir.squaredNorm(), ray.origin.dot(ray.dir), ray.origin.squaredNorm() - r * r,
                   ray.tmin, ray.tmax);
}

std::vector<RayL> exactRays(const std::vector<core::Ray>& rays) {
  std::vector<RayL> out(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    out[i].origin = rays[i].origin.cast<Real>();
    out[i].dir = rays[i].dir.cast<Real>();
    out[i].tmin = rays[i].tmin;
    out[i].tmax = rays[i].tmax;
  }
  return out;
}

std::vector<RayL> pipelineRays(const std::vector<SensorPose>& poses, const core::FanSpec& fan,
                               const std::vector<double>& elevations, double tmax,
                               bool per_column) {
  // Azimuth i at angle_min + i * increment, as core::ScanPattern defines it, without rounding.
  const int n = fan.beamCount();
  const Real angle_min = fan.angle_min;
  const Real increment = fan.samples != 0
                             ? (static_cast<Real>(fan.angle_max) - angle_min) / (fan.samples - 1)
                             : static_cast<Real>(fan.angle_increment);
  std::vector<Vec3L> dirs;
  for (const double elevation : elevations) {
    const Real ce = std::cos(static_cast<Real>(elevation));
    const Real se = std::sin(static_cast<Real>(elevation));
    for (int i = 0; i < n; ++i) {
      const Real a = angle_min + i * increment;
      dirs.emplace_back(ce * std::cos(a), ce * std::sin(a), se);
    }
  }
  std::vector<PoseL> sensors;
  for (const SensorPose& p : poses) sensors.push_back(p.exact());
  const std::size_t scans = per_column ? poses.size() / n : poses.size();
  std::vector<RayL> out;
  out.reserve(scans * dirs.size());
  for (std::size_t scan = 0; scan < scans; ++scan) {
    for (std::size_t b = 0; b < dirs.size(); ++b) {
      const PoseL& sensor = per_column ? sensors[scan * n + b % n] : sensors[scan];
      RayL ray;
      ray.origin = sensor.trans;
      ray.dir = sensor.rot * dirs[b];
      ray.tmin = 0;
      ray.tmax = tmax;
      out.push_back(ray);
    }
  }
  return out;
}

std::vector<Real> referenceSoup(const core::Bvh& soup_bvh, const std::vector<RayL>& rays) {
  std::vector<Real> out(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    out[i] = referenceClosestHit(soup_bvh, rays[i]) * std::sqrt(rays[i].dir.squaredNorm());
  }
  return out;
}

std::vector<Real> referenceBodies(const BenchScene& s, const std::vector<RayL>& rays) {
  // Each body: the inverse of its pose (a general inverse: a loaded double rotation is orthonormal
  // only to rounding) and its bounding sphere in the world.
  struct BodyL {
    Mat3L inv_rot;
    Vec3L trans, center;
    Real radius;
  };
  const auto& bodies = s.scene.bodies();
  std::vector<BodyL> placed;
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const PoseL& pose = s.body_poses[b];
    const Vec3L center = pose.apply(s.scene.sphereCenter(static_cast<int>(b)).cast<Real>());
    // Generous: the sphere only skips bodies a beam cannot reach.
    const Real radius = s.scene.sphereRadius(static_cast<int>(b)) * (1 + 1e-6L) + 1e-9L;
    placed.push_back(BodyL{pose.rot.inverse(), pose.trans, center, radius});
  }

  std::vector<Real> out(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Vec3L& o = rays[i].origin;
    const Real length = std::sqrt(rays[i].dir.squaredNorm());
    const Vec3L unit = rays[i].dir / length;  // for the sphere test only
    Real best = rays[i].tmax;
    bool hit = false;
    for (std::size_t b = 0; b < bodies.size(); ++b) {
      const BodyL& body = placed[b];
      const Vec3L to_center = body.center - o;
      const Real along = to_center.dot(unit);
      if (along + body.radius < 0 || along - body.radius > best * length) continue;
      if (to_center.squaredNorm() - along * along > body.radius * body.radius) continue;
      RayL ray;
      ray.origin = body.inv_rot * (o - body.trans);
      ray.dir = body.inv_rot * rays[i].dir;  // t is unchanged by the affine map
      ray.tmin = rays[i].tmin;
      ray.tmax = best;
      const core::Shape& shape = bodies[b].shape;
      Real t;
      if (const auto* mesh = std::get_if<std::shared_ptr<const core::Mesh>>(&shape)) {
        t = referenceClosestHit(**mesh, ray);
      } else if (const auto* box = std::get_if<core::Box>(&shape)) {
        t = referenceHit(ray, *box);
      } else if (const auto* cylinder = std::get_if<core::Cylinder>(&shape)) {
        t = referenceHit(ray, *cylinder);
      } else {
        t = referenceHit(ray, std::get<core::Sphere>(shape));
      }
      if (t <= best) {
        best = t;
        hit = true;
      }
    }
    out[i] = hit ? best * length : kInfL;
  }
  return out;
}

}  // namespace bench
}  // namespace laser_raycast
