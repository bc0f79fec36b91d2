// The reference every benchmark row is measured against: the same geometry the method was given,
// intersected in long double (x87, 64-bit significand: 2^11 times finer than double).
//
// Triangles: a long double version of the watertight test (Woop, Benthin, Wald 2013), with the
// sign of every edge function exact (a fused multiply-add difference of products, fmal, where the
// rounded difference could have the wrong sign) and the same one-owner rule for a ray exactly on
// a shared edge or vertex. Why this and not exact predicates throughout:
// - It cannot leak at a shared edge: both triangles transform the shared vertices with the same
//   operations on the same inputs (so to the same long double values), and the edge's sign is
//   exact, hence exactly opposite in the two; where it is exactly 0 (the vertex_rows scene puts
//   beams there) the owner rule gives the point to exactly one of them.
// - Where the coincidence is exact in the input (a beam with a zero z component at the height of
//   a vertex row), it stays exact: the shear factor is then exactly 0 and the transformed
//   coordinate is an exact difference of equal numbers. Elsewhere the only rounding is the
//   transformation's, about 1e-19 relative, which moves the decision by less than a double can
//   express and the distance by ~1e-18 m at 10 m: two thousand times below the smallest double
//   error it is used to measure.
// - Exact arithmetic throughout (expansions or rationals) would give the same decisions at many
//   times the cost, and the reference runs on every beam of every scene.
// The bench cross-checks it on box_room against the analytic boxes (independent code; only the
// double rounding of the vertices separates the two) and prints the result.
//
// Primitives (box, cylinder, sphere): closed forms in long double, cancellation-free quadratics.
#pragma once

#include <optional>
#include <vector>

#include "bench_meshes.h"
#include "bench_scenes.h"
#include "laser_raycast/core/bvh.h"
#include "laser_raycast/core/primitives.h"
#include "laser_raycast/core/scan_pattern.h"

namespace laser_raycast {
namespace bench {

struct RayL {
  Vec3L origin = Vec3L::Zero();
  Vec3L dir = Vec3L::UnitX();
  Real tmin = 0;
  Real tmax = 0;
};

// A ray prepared for the long double watertight test.
class ReferenceRay {
 public:
  explicit ReferenceRay(const RayL& ray);
  // t of the hit in [tmin, tmax], or nullopt. Degenerate triangles never hit (det = 0).
  std::optional<Real> intersect(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                const Eigen::Vector3d& c, Real tmax) const;

 private:
  Vec3L origin_;
  Real tmin_;
  int kx_, ky_, kz_;
  Real sx_, sy_, sz_;
};

// Nearest hit t (in units of |dir|) on the triangles of a double BVH, or +inf. The BVH only skips
// boxes the ray cannot reach (tested in long double on boxes padded far beyond rounding); every
// candidate triangle goes through ReferenceRay.
Real referenceClosestHit(const core::Bvh& bvh, const RayL& ray);

// Analytic primitives in their own frame (URDF conventions), first crossing in [tmin, tmax] or
// +inf; a ray from inside hits on the way out.
Real referenceHit(const RayL& ray, const core::Box& box);
Real referenceHit(const RayL& ray, const core::Cylinder& cylinder);
Real referenceHit(const RayL& ray, const core::Sphere& sphere);

// The rays the triangle methods are given (world frame, double), exactly.
std::vector<RayL> exactRays(const std::vector<core::Ray>& rays);

// The pipeline's beams: every beam of the pattern (directions from the fan's angles and the
// elevations, in long double) from every sensor pose (from its parameters, in long double). With
// per_column, poses holds one pose per azimuth column of each scan (a rotating sweep's),
// scan-major, and each beam leaves from its column's.
std::vector<RayL> pipelineRays(const std::vector<SensorPose>& poses, const core::FanSpec& fan,
                               const std::vector<double>& elevations, double tmax, bool per_column);

// Distances (m) on the soup (soup_bvh is built over it): t times |dir|, as each method's distance
// is its t times the length of the direction it was given.
std::vector<Real> referenceSoup(const core::Bvh& soup_bvh, const std::vector<RayL>& rays);

// Distances (m) on the scene's bodies as the pipeline holds them: each at its long double pose,
// meshes on their stored vertices, primitives analytic.
std::vector<Real> referenceBodies(const BenchScene& scene, const std::vector<RayL>& rays);

}  // namespace bench
}  // namespace laser_raycast
