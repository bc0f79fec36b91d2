// One ray's nearest hit in a mesh's wide BVH, the whole walk from a subtree down: the walks of the
// caster trace beams through the same WideWalk, box test and exact triangle test, but in their own
// loops; the wide BVH's tests check the tree and its box test with this one.
#pragma once

#include <optional>

#include "accel/wide_bvh.h"
#include "geometry/hit_order.h"

namespace laser_raycast {
namespace core {

// A ray prepared for the wide BVH (WideBoxRay) together with the exact triangle test. Every test of
// one ray against one mesh goes through the same PreparedRay, so that a ray exactly on a shared
// edge is decided the same way everywhere.
template <TriangleMethod M>
class WideRay {
 public:
  // bounds: the box of everything the ray will be tested against (a mesh's), for the reach.
  WideRay(const Ray& ray, bool cull_backfaces, const Aabb& bounds)
      : prepared_(ray, cull_backfaces), box_(ray, bounds) {}

  const PreparedRay<double, M>& prepared() const { return prepared_; }
  const WideBoxRay& box() const { return box_; }

  // Nearest hit with t in [ray.tmin, *tmax] in the subtree `start` whose box is start_box (float
  // corners lo[3], hi[3], rounded outward), skipping triangles that do not improve *best: a hit
  // improves it if it is nearer, or as near with a smaller triangle index (so the result does not
  // depend on the order the tree is walked in). Shrinks *tmax to each improving hit. Returns true
  // if *best changed.
  bool closestHit(const WideBvh& bvh, WideBvh::Ref start, const float* start_lo,
                  const float* start_hi, double* tmax, std::optional<MeshHit>* best) const;

 private:
  PreparedRay<double, M> prepared_;
  WideBoxRay box_;
};

template <TriangleMethod M>
inline bool WideRay<M>::closestHit(const WideBvh& bvh, WideBvh::Ref start, const float* start_lo,
                            const float* start_hi, double* tmax,
                            std::optional<MeshHit>* best) const {
  if (start.isEmpty() || !box_.enters(start_lo, start_hi, box_.cullLimit(*tmax))) return false;
  const Bvh& binary = bvh.binary();
  const auto& slots = binary.triangleVertices();
  const auto& ids = binary.triangleIds();
  bool improved = false;
  traceWide(bvh, start, box_, tmax, [&](std::uint32_t slot) {
    const auto& tri = slots[slot];
    const auto hit = prepared_.intersect(tri[0], tri[1], tri[2], *tmax);
    if (!hit) return;
    const std::uint32_t id = ids[slot];
    if (*best && !hitBefore(hit->t, id, (*best)->t, (*best)->triangle)) return;
    *best = MeshHit{hit->t, hit->u, hit->v, id};
    improved = true;
    *tmax = hit->t;
  });
  return improved;
}

}  // namespace core
}  // namespace laser_raycast
