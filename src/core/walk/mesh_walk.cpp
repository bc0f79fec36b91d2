#include "walk/mesh_walk.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>

#include "accel/wide_bvh.h"
#include "beams/column_motion.h"
#include "beams/column_raster.h"
#include "beams/edge_filter.h"
#include "geometry/hit_order.h"
#include "util/walk_stack.h"
#include "walk/beam_rays.h"
#include "walk/body_triangles.h"
#include "walk/mesh_slices.h"
#include "walk/slot_cache.h"
#include "walk/sub_ray_filter.h"
#include "walk/sub_ray_walk.h"
#include "walk/triangle_batch.h"

namespace laser_raycast {
namespace core {
namespace {

// The walk's choices below change only how beams and triangles are paired, never a triangle's test,
// so they change only the speed. Their values come from the benchmark's scenes.

// An inner node whose window holds at most kTraceBeams beams has them traced through its subtree
// one ray at a time instead of its children's windows being computed; so does one with at most
// kTraceBeamsDense beams of a 3D pattern and at least one triangle below it for every
// kBeamsPerTriangle of them (a detailed part: its triangles would each be rasterised for a few
// beams, a beam traced meets only the few on its way). Thin geometry seen across many beams (a wall
// of two triangles) keeps being rasterised, and a planar fan's nodes keep being sliced.
constexpr long long kTraceBeams = 12;
constexpr long long kTraceBeamsDense = 96;
constexpr long long kBeamsPerTriangle = 2;
// A leaf whose window holds at most this many beams has them tested against each of its triangles;
// more are rasterised (3D) against each triangle's edge planes first.
constexpr long long kLeafDirectBeams = 8;

template <TriangleMethod M>
class MeshWalk {
 public:
  using SensorTriangle = BodyTriangles::Triangle;

  MeshWalk(BeamSet& beams, const Mesh& mesh, const PlacedBody& active, const CastConfig& config)
      : beams_(beams),
        wide_(mesh.wideBvh()),
        ids_(mesh.bvh().triangleIds()),
        active_(active),
        config_(config),
        rot_(active.sensor_from_body.linear()),
        abs_rot_(rot_.cwiseAbs()),
        trans_(active.sensor_from_body.translation()),
        motion_(active.motion),
        spread_(motion_ ? motion_->spread() : Spread()),
        planar_(beams.grid().pattern().planar()),
        // A sweep's beams leave from their columns' poses, each in its own plane: traced.
        slicing_(planar_ && config.planar_fast_path && !motion_),
        // Without the fast paths every beam is traced from the root, as the reference.
        tracing_only_(planar_ ? !config.planar_fast_path : !config.raster_fast_path),
        basis_(active.sensor_from_body, planar_, config.tmax, spread_),
        triangles_(mesh, active, config.tmin, spread_.shift, !slicing_),
        rays_(beams, active, mesh.bvh().bounds(), config) {
    if (slicing_) slices_.emplace(beams, mesh, active, config);
  }

  void run(const BeamRect& within) {
    if (wide_.empty()) return;
    const Aabb& bounds = wide_.binary().bounds();
    const View view = boxView(bounds.center(), bounds.extent() * 0.5, rot_, abs_rot_, trans_,
                              beams_.grid().pattern().angleMin(), !planar_, spread_);
    if (!(view.near <= config_.tmax)) return;
    stack_.clear();
    const Entry root{wide_.root(), BeamRect{}, floatBelow(view.near), wide_.rootTriangles()};
    beams_.grid().forEachRect(view, within, [&](const BeamRect& rect) {
      Entry e = root;
      e.rect = rect;
      push(e);
    });
    while (!stack_.empty()) {
      const Entry e = stack_.pop();
      if (!beams_.anyOpen(e.rect, e.near)) continue;  // hidden behind nearer hits
      if (tracing_only_) {
        traceRect(e);
      } else {
        visit(e);
      }
    }
  }

 private:
  struct Entry {
    WideBvh::Ref ref;
    BeamRect rect;
    float near;               // no point of ref's box is nearer to the sensor
    std::uint32_t triangles;  // below ref
  };

  void push(const Entry& e) { stack_.push(e); }

  void visit(const Entry& e) {
    const long long beams = e.rect.beams();
    if (e.ref.isLeaf()) {
      if (slicing_) {
        slices_->sliceLeaf(e.ref, e.rect, e.near);
      } else if (beams <= kLeafDirectBeams) {
        testLeaf(e);
      } else {
        rasterLeaf(e);
      }
    } else if (slicing_ && MeshSlices::slicedWhole(e.triangles, beams)) {
      slices_->sliceSubtree(e.ref, e.rect, e.near, basis_);
    } else if (beams <= kTraceBeams || (!planar_ && beams <= kTraceBeamsDense &&
                                        e.triangles * kBeamsPerTriangle >= beams)) {
      traceRect(e);
    } else {
      expand(e);
    }
  }

  void expand(const Entry& e) {
    const WideBvh::Node& node = wide_.nodes()[e.ref.index];
    NodeViews views;
    views.compute(node, basis_);
    if (!views.mask) return;
    Entry children[4 * 3];  // a child's view may wrap into several rects
    int n = 0;
    for (int k = 0; k < WideBvh::kWidth; ++k) {
      if (!(views.mask & (1 << k))) continue;
      beams_.grid().forEachChildRect(views, k, e.rect, [&](const BeamRect& rect) {
        if (n < 12) {
          children[n++] =
              Entry{node.child(k), rect, views.near[k], wide_.childTriangles(e.ref.index, k)};
        }
      });
    }
    sortFarthestFirst(children, n);
    for (int j = 0; j < n; ++j) {
      // A leaf to be sliced: its triangles are asked for now, to be in the cache when it is popped.
      if (slicing_ && children[j].ref.isLeaf()) slices_->prefetchLeaf(children[j].ref);
      push(children[j]);
    }
  }

  // The nearest hit of one beam so far in this walk: a hit improves it if nearer, or as near on a
  // lower triangle index, so the result does not depend on the order triangles are met in.
  struct Best {
    double t = std::numeric_limits<double>::infinity();
    std::uint32_t triangle = std::numeric_limits<std::uint32_t>::max();
    std::uint32_t slot = 0;
    bool found() const { return triangle != std::numeric_limits<std::uint32_t>::max(); }
    bool improves(double t2, std::uint32_t triangle2) const {
      return hitBefore(t2, triangle2, t, triangle);
    }
  };

  void offer(int row, int col, const Best& best) {
    beams_.keepNearestHit(row, col, best.t, active_.index, static_cast<int>(best.triangle), [&] {
      return slicing_ ? slices_->sensorNormal(best.slot)
                      : triangles_.beamNormal(row, col, best.triangle);
    });
  }

  // Sub-ray s of a bundle's beam: as offer() for the beam.
  void offerSub(int s, int row, int col, const Best& best) {
    beams_.keepNearestSubHit(s, row, col, best.t, active_.index, static_cast<int>(best.triangle),
                             [&] { return triangles_.beamNormal(row, col, best.triangle); });
  }

  // A beam (or a bundle's sub-ray) traced on its own through a subtree: its rays, its far limit
  // and its nearest hit.
  struct Traced {
    int row, col;
    int sub;  // the sub-ray, or -1 for the grid's beam
    double tmax;
    Best best;
    WideBoxRay box_ray;
    // For the 3D tests (not when slicing): made when the trace first reaches a triangle (many
    // traces cross boxes alone, and on a sweep a beam's ray costs two turns and three divisions).
    std::optional<PreparedRay<double, M>> ray;
  };

  // The traced beam's ray for the exact tests, made the first time it is asked for.
  const PreparedRay<double, M>& rayOf(Traced* b) const {
    if (!b->ray) b->ray.emplace(b->sub >= 0 ? rays_.subRay(b->sub, b->row, b->col)
                                            : rays_.beamRay(b->row, b->col));
    return *b->ray;
  }

  // What a traced beam does with each triangle slot of a leaf it enters: its segment in the scan
  // plane (slicing), or the exact 3D test.
  auto leafOf(Traced* b) {
    return [this, b](std::uint32_t slot) {
      if (hidden(slot)) return;
      if (slicing_) {
        sliceOne(slot, b->col, &b->tmax, &b->best);
      } else {
        testSlot(rayOf(b), slot, &b->tmax, &b->best);
      }
    };
  }

  // Each open beam of the rect through the node's subtree, two at a time (their walks side by
  // side, traceWidePair: the same visits and tests as one at a time); a bundle's sub-rays by
  // traceSubRays.
  void traceRect(const Entry& e) {
    if (bundle_) {
      traceSubRays(e);
      return;
    }
    Traced pair[2];
    int n = 0;
    for (int row = e.rect.row_lo; row <= e.rect.row_hi; ++row) {
      for (int col = e.rect.col_lo; col <= e.rect.col_hi; ++col) {
        const double range = beams_.range(row, col);
        if (!(range >= e.near)) continue;  // a hit nearer than this node can be
        Traced& b = pair[n++];
        b.row = row;
        b.col = col;
        b.sub = -1;
        b.tmax = std::min(config_.tmax, range);
        b.best = Best{};
        b.box_ray = rays_.boxRay(row, col);
        b.ray.reset();
        if (n == 2) tracePair(e, pair, [this](Traced* t) { return leafOf(t); });
        n %= 2;
      }
    }
    if (n == 1) traceOne(e, pair, [this](Traced* t) { return leafOf(t); });
  }

  // The two queued traces walked side by side (traceWidePair: the same visits and tests as one at
  // a time), or the last one alone; leaf_of(t) gives what trace t does at each slot of a leaf.
  template <class LeafOf>
  LASER_RAYCAST_HOT_INLINE void tracePair(const Entry& e, Traced* pair, LeafOf&& leaf_of) {
    traceWidePair(wide_, e.ref, pair[0].box_ray, &pair[0].tmax, leaf_of(&pair[0]), pair[1].box_ray,
                  &pair[1].tmax, leaf_of(&pair[1]));
    finish(pair[0]);
    finish(pair[1]);
  }
  template <class LeafOf>
  LASER_RAYCAST_HOT_INLINE void traceOne(const Entry& e, Traced* pair, LeafOf&& leaf_of) {
    traceWide(wide_, e.ref, pair[0].box_ray, &pair[0].tmax, leaf_of(&pair[0]));
    finish(pair[0]);
  }

  void finish(const Traced& b) {
    if (!b.best.found()) return;
    if (b.sub >= 0) {
      offerSub(b.sub, b.row, b.col, b.best);
    } else {
      offer(b.row, b.col, b.best);
    }
  }

  // Each open beam's sub-rays (a bundle's) through the node's subtree: a divergent beam's walked
  // together (SubRayWalk::traceBeam: one walk for all, where a walk each cost the forest's
  // divergent rings about 10% and million's about 30% more instructions in Caster::cast*); otherwise each on
  // its own ray, two at a time as traceRect traces beams (a calibrated lidar's one a beam), or
  // one at a time for a cell's list of beams (beams/beam_cells.h), where side by side gained
  // nothing (the rosette's still poses, bench --quick: warehouse 0.47-0.49 of Embree's speed
  // against 0.50-0.51). A sub-ray's walk reads and lowers only its own far limit, so pairing them
  // changes no test.
  void traceSubRays(const Entry& e) {
    if (bundle_->first) {
      traceEachSubRay(e);
    } else if (subs_.together()) {
      subs_.traceRect(wide_, e.ref, e.rect, e.near);
    } else {
      traceSubRayPairs(e);
    }
  }

  void traceEachSubRay(const Entry& e) {
    for (int row = e.rect.row_lo; row <= e.rect.row_hi; ++row) {
      for (int col = e.rect.col_lo; col <= e.rect.col_hi; ++col) {
        const double range = beams_.range(row, col);
        if (!(range >= e.near)) continue;
        for (int s = beams_.subBegin(row, col), end = beams_.subEnd(row, col); s < end; ++s) {
          double tmax = std::min(config_.tmax, beams_.subRange(s));
          if (!(tmax >= e.near)) continue;
          Best best;
          std::optional<PreparedRay<double, M>> ray;  // made at the first triangle, as rayOf()
          traceWide(wide_, e.ref, rays_.subBoxRay(s, row, col), &tmax, [&](std::uint32_t slot) {
            if (hidden(slot)) return;
            if (!ray) ray.emplace(rays_.subRay(s, row, col));
            testSlot(*ray, slot, &tmax, &best);
          });
          if (best.found()) offerSub(s, row, col, best);
        }
      }
    }
  }

  void traceSubRayPairs(const Entry& e) {
    Traced pair[2];
    int n = 0;
    for (int row = e.rect.row_lo; row <= e.rect.row_hi; ++row) {
      for (int col = e.rect.col_lo; col <= e.rect.col_hi; ++col) {
        const double range = beams_.range(row, col);
        if (!(range >= e.near)) continue;
        for (int s = beams_.subBegin(row, col), end = beams_.subEnd(row, col); s < end; ++s) {
          const double tmax = std::min(config_.tmax, beams_.subRange(s));
          if (!(tmax >= e.near)) continue;
          Traced& b = pair[n++];
          b.row = row;
          b.col = col;
          b.sub = s;
          b.tmax = tmax;
          b.best = Best{};
          b.box_ray = rays_.subBoxRay(s, row, col);
          b.ray.reset();
          if (n == 2) tracePair(e, pair, [this](Traced* t) { return subLeafOf(t); });
          n %= 2;
        }
      }
    }
    if (n == 1) traceOne(e, pair, [this](Traced* t) { return subLeafOf(t); });
  }

  // What a traced sub-ray does with each triangle slot of a leaf it enters: the exact 3D test.
  auto subLeafOf(Traced* b) {
    return [this, b](std::uint32_t slot) LASER_RAYCAST_HOT_LAMBDA {
      if (!hidden(slot)) testSlot(rayOf(b), slot, &b->tmax, &b->best);
    };
  }

  // A traced beam against a slot's triangle: a nearer hit (or as near on a lower triangle) becomes
  // its best so far and its far limit.
  LASER_RAYCAST_HOT_INLINE void testSlot(const PreparedRay<double, M>& ray, std::uint32_t slot,
                                         double* tmax, Best* best) {
    const SensorTriangle& s = triangles_.cachedTriangle(slot);
    const auto hit = ray.intersect(s.a, s.b, s.c, *tmax);
    if (hit && best->improves(hit->t, ids_[slot])) {
      *best = Best{hit->t, ids_[slot], slot};
      *tmax = hit->t;
    }
  }

  // A back face no beam meets first (BodyTriangles::hidden): only for the 3D tests, a planar fan's
  // segments being cheap, and kept slices (which must skip what the walk skips) paying more to
  // decide.
  bool hidden(std::uint32_t slot) { return triangles_.hidden(slot); }

  // The slot's segment in the scan plane against one beam, as slicing tests it.
  void sliceOne(std::uint32_t slot, int col, double* tmax, Best* best) const {
    double t;
    if (slices_->sliceBeam(slot, col, &t) && t <= *tmax && best->improves(t, ids_[slot])) {
      *best = Best{t, ids_[slot], slot};
      *tmax = t;
    }
  }

  // A few beams against each triangle of a leaf, directly.
  void testLeaf(const Entry& e) {
    SensorTriangle tris[16];  // the leaf's first triangles, moved once
    const std::uint32_t count = std::min<std::uint32_t>(e.ref.count, 16);
    for (std::uint32_t i = 0; i < count; ++i) tris[i] = triangles_.sensorTriangle(e.ref.index + i);
    for (int row = e.rect.row_lo; row <= e.rect.row_hi; ++row) {
      for (int col = e.rect.col_lo; col <= e.rect.col_hi; ++col) {
        const double range = beams_.range(row, col);
        if (!(range >= e.near)) continue;
        // The beam, or each of a bundle's sub-rays, against every triangle of the leaf.
        auto testRay = [&](const PreparedRay<double, M>& ray, double tmax, Best* best) {
          for (std::uint32_t i = 0; i < e.ref.count; ++i) {
            const std::uint32_t slot = e.ref.index + i;
            if (hidden(slot)) continue;
            const SensorTriangle s = i < count ? tris[i] : triangles_.sensorTriangle(slot);
            const auto hit = ray.intersect(s.a, s.b, s.c, tmax);
            if (hit && best->improves(hit->t, ids_[slot])) {
              *best = Best{hit->t, ids_[slot], slot};
              tmax = hit->t;
            }
          }
        };
        if (bundle_) {
          for (int s = beams_.subBegin(row, col), end = beams_.subEnd(row, col); s < end; ++s) {
            Best sub_best;
            testRay(rays_.subRay(s, row, col), std::min(config_.tmax, beams_.subRange(s)),
                    &sub_best);
            if (sub_best.found()) offerSub(s, row, col, sub_best);
          }
          continue;
        }
        Best best;
        testRay(rays_.beamRay(row, col), std::min(config_.tmax, range), &best);
        if (best.found()) offer(row, col, best);
      }
    }
  }

  // Each triangle of the leaf against the open beams of the leaf's window: column by column
  // through a conservative float test of its edge planes and its plane (ColumnRaster, widened by a
  // sweep block's spread), or for patterns too steep for it row by row (EdgeFilter; for a sweep's
  // block, the triangle's own window instead), then the exact test for the beams let through
  // (walk/triangle_batch.h: their rays made a batch at a time, then tested).
  void rasterLeaf(const Entry& e) {
    for (std::uint32_t slot = e.ref.index; slot < e.ref.index + e.ref.count; ++slot) {
      if (hidden(slot)) continue;
      const SensorTriangle s = triangles_.sensorTriangle(slot);
      const std::uint32_t triangle = ids_[slot];
      std::optional<SubRayFilter> filter;
      if (bundle_ && sub_rays_from_origin_) filter.emplace(s.a, s.b, s.c);
      TriangleBatch batch(beams_, rays_, s, active_.index, static_cast<int>(triangle),
                          [&](int row, int col) {
                            return triangles_.beamNormal(row, col, triangle);
                          });
      auto test = [&](int row, int col) {
        // The range rounded up to float (compact, so cheaper to read here than the result's): a
        // hit it lets through beyond the exact range is turned down by keepNearestHit().
        const double range = beams_.rangeAbove(row)[col];
        if (!(range >= e.near)) return;
        if (bundle_) {
          if (subs_.shearsKept() && subs_.together()) {
            subs_.testRasterBeam(filter ? &*filter : nullptr, row, col, s, triangle);
            return;
          }
          const auto add = [&](int j) {
            batch.add(row, col, j, std::min(config_.tmax, beams_.subRange(j)));
          };
          const int begin = beams_.subBegin(row, col), end = beams_.subEnd(row, col);
          if (filter) {
            filter->forEachPassing(beams_, begin, end, add);
          } else {
            for (int j = begin; j < end; ++j) add(j);
          }
          return;
        }
        batch.add(row, col, -1, std::min(config_.tmax, range));
      };
      if (beams_.grid().columnRaster()) {
        (motion_ ? ColumnRaster(beams_, s.a, s.b, s.c, *motion_, e.near)
                 : ColumnRaster(beams_, s.a, s.b, s.c))
            .forEachCandidate(beams_, e.rect, test);
      } else if (motion_) {
        forEachInWindow(s, e.rect, test);
      } else {
        const EdgeFilter edges(s.a, s.b, s.c);
        for (int row = e.rect.row_lo; row <= e.rect.row_hi; ++row) {
          edges.forEachCandidate(beams_, row, e.rect.col_lo, e.rect.col_hi,
                                 [&](int col) { test(row, col); });
        }
      }
      batch.flush();
    }
  }

  // The beams of rect in the triangle's own window (the view of its sensor-frame box, widened by
  // the sweep block's spread): f(row, col) for each.
  template <class F>
  void forEachInWindow(const SensorTriangle& s, const BeamRect& rect, F&& f) const {
    const View view =
        triangleView(s.a, s.b, s.c, beams_.grid().pattern().angleMin(), !planar_, spread_);
    if (!(view.near <= config_.tmax) || (planar_ && !view.crosses)) return;
    beams_.grid().forEachRect(view, rect, [&](const BeamRect& r) {
      for (int row = r.row_lo; row <= r.row_hi; ++row) {
        for (int col = r.col_lo; col <= r.col_hi; ++col) f(row, col);
      }
    });
  }

  BeamSet& beams_;
  const WideBvh& wide_;
  const std::vector<std::uint32_t>& ids_;
  const PlacedBody& active_;
  const CastConfig& config_;
  const Eigen::Matrix3d rot_, abs_rot_;
  const Eigen::Vector3d trans_;
  const ColumnMotion* motion_;                       // a sweep's block, or null
  const BeamSet::Bundle* bundle_ = beams_.bundle();  // a bundle's sub-rays, or null
  const Spread spread_;
  const bool planar_, slicing_, tracing_only_;
  // Every sub-ray leaves from the reference origin along its own direction (SubRayFilter).
  const bool sub_rays_from_origin_ =
      !motion_ || (motion_->spread().shift == 0 && motion_->translationsOnly());
  const ViewBasis basis_;
  BodyTriangles triangles_;
  const BeamRays<M> rays_;
  // A bundle's sub-rays, a beam's at a time.
  SubRayWalk<M> subs_{beams_, triangles_, ids_, rays_, config_, active_.index};
  std::optional<MeshSlices> slices_;  // a planar fan's cuts, where the walk slices
  WalkStack<Entry> stack_;
};

}  // namespace

void walkMesh(BeamSet& beams, const Scene& scene, const PlacedBody& active,
              const CastConfig& config, const BeamRect& within) {
  const Mesh& mesh = *std::get<std::shared_ptr<const Mesh>>(scene.bodies()[active.index].shape);
  dispatchTriangleMethod(config.method, [&](auto method) {
    MeshWalk<decltype(method)::value> walk(beams, mesh, active, config);
    walk.run(within);
  });
}

}  // namespace core
}  // namespace laser_raycast
