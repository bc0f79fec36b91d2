// The sub-rays of a bundle's beams (BeamSet::Bundle: a divergent beam's, a calibrated lidar's) in
// a mesh walk (mesh_walk.cpp), a beam's sub-rays at a time: against a rasterised triangle, and
// through a subtree, walked together (one walk and one box test a node for all of them, where a
// walk each tested every node once per sub-ray).
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "accel/wide_bundle_ray.h"
#include "accel/wide_bvh.h"
#include "beams/beam_set.h"
#include "geometry/hit_order.h"
#include "laser_raycast/core/cast_config.h"
#include "laser_raycast/core/triangle.h"
#include "walk/beam_rays.h"
#include "walk/body_triangles.h"
#include "walk/sub_ray_filter.h"
#include "walk/sub_ray_pair.h"

namespace laser_raycast {
namespace core {

template <TriangleMethod M>
class SubRayWalk {
 public:
  using SensorTriangle = BodyTriangles::Triangle;
  // Beams of up to this many sub-rays are walked together (traceBeam).
  static constexpr int kMaxTogether = 16;

  // body: the walked body's index.
  SubRayWalk(BeamSet& beams, BodyTriangles& triangles, const std::vector<std::uint32_t>& ids,
             const BeamRays<M>& rays, const CastConfig& config, int body)
      : beams_(beams),
        triangles_(triangles),
        ids_(ids),
        rays_(rays),
        config_(config),
        body_(body),
        // The kept shears are the watertight test's, from the origin (BeamRays::subRay).
        shears_(M == TriangleMethod::kWatertight && beams.bundle() ? beams.subShears() : nullptr) {}

  // Whether the bundle's sub-rays have their shears kept: testRasterBeam() needs them.
  bool shearsKept() const { return shears_ != nullptr; }

  // The sub-rays of the beam at (row, col) that filter (if not null) lets through, against
  // triangle s (its index: triangle), each from the origin along its kept shear (shearsKept());
  // their hits kept, and the beam's culling range settled once for all of them.
  // (Out of line, as traceBeam: inlined, the walk's own raster and trace stopped being inlined
  // as they were, and a scan without a bundle counted 7% more instructions.)
  __attribute__((noinline)) void testRasterBeam(const SubRayFilter* filter, int row, int col,
                                                const SensorTriangle& s, std::uint32_t triangle) {
    bool kept = false;
    const auto keep = [&](int j, double t) {
      kept |= beams_.keepSubHit(j, t, body_, static_cast<int>(triangle),
                                [&] { return triangles_.beamNormal(row, col, triangle); });
    };
    forEachPassing(
        filter, beams_.subBegin(row, col), beams_.subEnd(row, col), s,
        [&](int j) { return std::min(config_.tmax, beams_.subRange(j)); }, keep);
    if (kept) beams_.settleSubHits(row, col);
  }

  // Whether a beam's sub-rays are taken together (testRasterBeam, traceBeam): 2 to kMaxTogether
  // sub-rays a beam (a divergent beam's). A calibrated lidar's one sub-ray a beam and a cell's list
  // (beams/beam_cells.h) keep the walk's batch and its walks one sub-ray at a time: taken this way,
  // bench --quick's warehouse counted 4.1% more instructions for vlp16_calibrated and 1.8% more
  // for pattern_rosette.
  bool together() const {
    const BeamSet::Bundle* bundle = beams_.bundle();
    return bundle && !bundle->first && bundle->per_beam >= 2 && bundle->per_beam <= kMaxTogether;
  }

  // traceBeam() for each beam of rect whose range is not nearer than near.
  void traceRect(const WideBvh& wide, WideBvh::Ref start, const BeamRect& rect, float near) {
    for (int row = rect.row_lo; row <= rect.row_hi; ++row) {
      for (int col = rect.col_lo; col <= rect.col_hi; ++col) {
        if (beams_.range(row, col) >= near) traceBeam(wide, start, row, col, near);
      }
    }
  }

  // The open sub-rays of the beam at (row, col) (their range not nearer than near) walked together
  // through subtree start: the boxes that any of them may enter (WideBundleRay, from bounds on
  // their directions in the body's frame), nearest first, out to the farthest of their far limits;
  // at each triangle, each sub-ray's exact test against its own far limit. Every sub-ray meets the
  // triangles its own walk would have (and maybe more): the same nearest hits.
  __attribute__((noinline)) void traceBeam(const WideBvh& wide, WideBvh::Ref start, int row,
                                           int col, float near) {
    const int begin = beams_.subBegin(row, col), end = beams_.subEnd(row, col);
    double tmax[kMaxTogether];
    Hit best[kMaxTogether];
    unsigned open = 0;
    // Bounds on the open sub-rays' directions in the body's frame, axis by axis.
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    double farthest = -std::numeric_limits<double>::infinity();
    for (int j = begin; j < end; ++j) {
      const int i = j - begin;
      tmax[i] = std::min(config_.tmax, beams_.subRange(j));
      if (!(tmax[i] >= near)) continue;
      open |= 1u << i;
      farthest = std::max(farthest, tmax[i]);
      const Eigen::Vector3d d = rays_.boxDirection(row, col, beams_.subDirection(j));
      lo = lo.cwiseMin(d);
      hi = hi.cwiseMax(d);
    }
    if (!open) return;
    // The rays of the tests from elsewhere than the origin, each made when first needed.
    std::optional<PreparedRay<double, M>> rays[kMaxTogether];
    const auto test = [&](std::uint32_t slot) LASER_RAYCAST_HOT_LAMBDA {
      if (triangles_.hidden(slot)) return;
      const SensorTriangle& s = triangles_.cachedTriangle(slot);
      const std::uint32_t triangle = ids_[slot];
      const auto improve = [&](int j, double t) {
        const int i = j - begin;
        if (best[i].improvedBy(t, triangle)) {
          best[i] = Hit{t, triangle};
          tmax[i] = t;
        }
      };
      if (shears_) {
        // Kept shears are rays from the origin, unturned: the pre-test applies.
        const SubRayFilter filter(s.a, s.b, s.c);
        forEachPassing(
            &filter, begin, end, s,
            // (A closed sub-ray, its far limit below near, is tested too and its hit dropped.)
            [&](int j) { return tmax[j - begin]; }, improve);
      } else {
        for (unsigned left = open; left; left &= left - 1) {
          const int i = __builtin_ctz(left);
          if (!rays[i]) rays[i].emplace(rays_.subRay(begin + i, row, col));
          const auto hit = rays[i]->intersect(s.a, s.b, s.c, tmax[i]);
          if (hit) improve(begin + i, hit->t);
        }
      }
      farthest = -std::numeric_limits<double>::infinity();
      for (unsigned left = open; left; left &= left - 1) {
        farthest = std::max(farthest, tmax[__builtin_ctz(left)]);
      }
    };
    traceWide(wide, start, WideBundleRay(rays_.boxOrigin(col), lo, hi), &farthest, test);
    bool kept = false;
    for (unsigned left = open; left; left &= left - 1) {
      const int i = __builtin_ctz(left);
      if (!best[i].found()) continue;
      const std::uint32_t triangle = best[i].triangle;
      kept |= beams_.keepSubHit(begin + i, best[i].t, body_, static_cast<int>(triangle),
                                [&] { return triangles_.beamNormal(row, col, triangle); });
    }
    if (kept) beams_.settleSubHits(row, col);
  }

 private:
  // A sub-ray's nearest hit so far in this walk: nearer, or as near on a lower triangle index.
  struct Hit {
    double t = std::numeric_limits<double>::infinity();
    std::uint32_t triangle = std::numeric_limits<std::uint32_t>::max();
    bool found() const { return triangle != std::numeric_limits<std::uint32_t>::max(); }
    bool improvedBy(double t2, std::uint32_t triangle2) const {
      return hitBefore(t2, triangle2, t, triangle);
    }
  };

  // Sub-rays begin to end - 1 that filter (if not null) lets through, against triangle s, each
  // from the origin along its kept shear out to tmax_of(j): hit(j, t) for each that hits. Two at a
  // time where their shears permute the axes alike (as a beam's close sub-rays' nearly always do;
  // intersectPairFromOrigin), else one.
  template <class TmaxOf, class OnHit>
  LASER_RAYCAST_HOT_INLINE void forEachPassing(const SubRayFilter* filter, int begin, int end,
                                               const SensorTriangle& s, TmaxOf&& tmax_of,
                                               OnHit&& hit) const {
    int waiting = -1;  // a sub-ray let through, not yet tested
    const auto one = [&](int j) {
      const auto h = intersectFromOrigin(shears_[j], s.a, s.b, s.c, config_.tmin,
                                         config_.cull_backfaces, tmax_of(j));
      if (h) hit(j, h->t);
    };
    const auto passing = [&](int j) {
      if (waiting < 0) {
        waiting = j;
        return;
      }
      const BeamSet::SubShear &p = shears_[waiting], &q = shears_[j];
      if (p.kx != q.kx || p.ky != q.ky || p.kz != q.kz) {
        one(waiting);
        waiting = j;
        return;
      }
      const double tmax[2] = {tmax_of(waiting), tmax_of(j)};
      double t[2];
      const int hits = intersectPairFromOrigin(p, q, s.a, s.b, s.c, config_.tmin,
                                               config_.cull_backfaces, tmax, t);
      if (hits & 1) hit(waiting, t[0]);
      if (hits & 2) hit(j, t[1]);
      waiting = -1;
    };
    if (filter) {
      filter->forEachPassing(beams_, begin, end, passing);
    } else {
      for (int j = begin; j < end; ++j) passing(j);
    }
    if (waiting >= 0) one(waiting);
  }

  BeamSet& beams_;
  BodyTriangles& triangles_;
  const std::vector<std::uint32_t>& ids_;
  const BeamRays<M>& rays_;
  const CastConfig& config_;
  const int body_;
  const BeamSet::SubShear* const shears_;
};

}  // namespace core
}  // namespace laser_raycast
