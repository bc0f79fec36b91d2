// The exact tests of one triangle with the beams (or a bundle's sub-rays) a raster lets through
// (mesh_walk.cpp's rasterLeaf), a batch at a time: every beam's prepared ray is made before any of
// them is tested, so that the divisions of one ray (its shear, and on a sweep its pose's turns)
// overlap the next's rather than each test waiting for its own. Each hit is then offered as it
// would be one beam at a time. A beam meets the triangle once, so deferring its test changes
// nothing another test reads: the same tests, offers and bits as testing each beam at once.
#pragma once

#include <new>
#include <type_traits>
#include <utility>

#include "beams/beam_set.h"
#include "laser_raycast/core/triangle.h"
#include "walk/beam_rays.h"
#include "walk/body_triangles.h"

namespace laser_raycast {
namespace core {

template <TriangleMethod M, class Normal>
class TriangleBatch {
 public:
  // s: the triangle in the sensor frame (kept by the caller while this lives); body, triangle: its
  // body's and its own index, as the hits are kept; normal(row, col): its unit normal in the frame
  // of the beam at (row, col), asked for a hit that is kept.
  TriangleBatch(BeamSet& beams, const BeamRays<M>& rays, const BodyTriangles::Triangle& s,
                int body, int triangle, Normal normal)
      : beams_(beams),
        rays_(rays),
        s_(s),
        body_(body),
        triangle_(triangle),
        normal_(std::move(normal)) {}
  TriangleBatch(const TriangleBatch&) = delete;
  TriangleBatch& operator=(const TriangleBatch&) = delete;

  // The beam at (row, col), or its sub-ray sub (>= 0), out to tmax.
  LASER_RAYCAST_HOT_INLINE void add(int row, int col, int sub, double tmax) {
    // A sub-ray's direction (or its kept shear) is read from the bundle's list (a calibrated
    // head's 28,928, in the order the raster meets them): asked for now, it has arrived by the
    // flush.
    if (sub >= 0) {
      const BeamSet::SubShear* shears = beams_.subShears();
      __builtin_prefetch(shears ? static_cast<const void*>(shears + sub)
                                : static_cast<const void*>(&beams_.subDirection(sub)));
    }
    pending_[n_++] = Pending{row, col, sub, tmax};
    if (n_ == kBatch) flush();
  }
  // Tests what is queued; call once the raster is done.
  void flush() {
    Ray* rays = reinterpret_cast<Ray*>(storage_);
    for (int i = 0; i < n_; ++i) {
      const Pending& p = pending_[i];
      new (&rays[i]) Ray(p.sub < 0 ? rays_.beamRay(p.row, p.col)
                                   : rays_.subRay(p.sub, p.row, p.col));
    }
    for (int i = 0; i < n_; ++i) {
      const Pending& p = pending_[i];
      const auto hit = rays[i].intersect(s_.a, s_.b, s_.c, p.tmax);
      if (!hit) continue;
      const int row = p.row, col = p.col;
      auto normal = [&] { return normal_(row, col); };
      if (p.sub < 0) {
        beams_.keepNearestHit(row, col, hit->t, body_, triangle_, normal);
      } else {
        beams_.keepNearestSubHit(p.sub, row, col, hit->t, body_, triangle_, normal);
      }
    }
    n_ = 0;
  }

 private:
  using Ray = PreparedRay<double, M>;
  static_assert(std::is_trivially_destructible_v<Ray>, "the batch's rays are never destroyed");
  // 8 and 32 did as well on the warehouse drive of test/perf/make_warehouse_bag.py.
  static constexpr int kBatch = 16;
  struct Pending {
    int row, col, sub;  // sub: a bundle's sub-ray, or -1 for the grid's beam
    double tmax;
  };

  BeamSet& beams_;
  const BeamRays<M>& rays_;
  const BodyTriangles::Triangle& s_;
  const int body_, triangle_;
  Normal normal_;
  int n_ = 0;
  Pending pending_[kBatch];
  alignas(Ray) unsigned char storage_[kBatch * sizeof(Ray)];
};

}  // namespace core
}  // namespace laser_raycast
