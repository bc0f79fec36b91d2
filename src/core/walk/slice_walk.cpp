#include "walk/slice_walk.h"

#include <algorithm>
#include <array>
#include <limits>
#include <optional>
#include <vector>

#include "beams/placed_body.h"
#include "geometry/hit_order.h"
#include "slice/slice_views.h"
#include "util/walk_stack.h"
#include "walk/frame_walk.h"
#include "walk/primitive_cast.h"

namespace laser_raycast {
namespace core {
namespace {

// A node whose window holds at most this many beams has them traced through its subtree one ray at
// a time instead of its children's windows being computed. Only speed depends on it. It is not the
// mesh walk's kTraceBeams (12, mesh_walk.cpp) on purpose: each was measured on the benchmark's
// scenes for its own walk, and here a traced beam tests 2D segments and walks paired with another
// (traceWidePair), so tracing stays cheaper than expanding for somewhat wider windows.
constexpr long long kTraceBeams = 16;

// The map from plane coordinates (z = 0) to the sensor frame, for the node views.
Eigen::Isometry3d sensorFromPlane(const ScanPlane& f) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() << f.a, f.b, 0, f.c, f.d, 0, 0, 0, 1;
  pose.translation() << f.tx, f.ty, 0;
  return pose;
}

class SliceWalk {
 public:
  SliceWalk(BeamSet& beams, const Scene& scene, const KeptSlice& slice, const ScanPlane& plane,
            const Eigen::Isometry3d& sensor_from_frame, const CastConfig& config,
            std::vector<std::atomic<char>>* cast, const ColumnMotion* motion)
      : beams_(beams),
        scene_(scene),
        slice_(slice),
        plane_(plane),
        sensor_from_frame_(sensor_from_frame),
        config_(config),
        cast_(cast),
        motion_(motion),
        spread_(motion ? motion->spread() : Spread()),
        sensor_from_plane_(sensorFromPlane(plane)),
        views_(plane, config.tmax, beams.grid().pattern(), spread_) {
    // The sensor and the beams in plane coordinates, for the traced rays' box tests: the inverse
    // of the map to the sensor frame.
    const double det = plane.a * plane.d - plane.b * plane.c;
    inverse_ << plane.d / det, -plane.b / det, -plane.c / det, plane.a / det;
    origin_.emplace(-(inverse_ * Eigen::Vector2d(plane.tx, plane.ty)), slice.tree.bounds(),
                    config.tmin);
  }

  void run(const BeamRect& within) {
    if (slice_.wide.empty()) return;
    const Aabb& bounds = slice_.tree.bounds();
    const Eigen::Matrix3d& rot = sensor_from_plane_.linear();
    const View view = boxView(bounds.center(), bounds.extent() * 0.5, rot, rot.cwiseAbs(),
                              sensor_from_plane_.translation(), beams_.grid().pattern().angleMin(),
                              false, spread_);
    if (!(view.near <= config_.tmax)) return;
    beams_.grid().forEachRect(view, within, [&](const BeamRect& rect) {
      stack_.push(Entry{slice_.wide.root(), rect, floatBelow(view.near)});
    });
    walk();
    deferred_.cast(beams_, scene_, config_);
  }

 private:
  struct Entry {
    WideBvh::Ref ref;
    BeamRect rect;
    float near;
  };

  void walk() {
    while (!stack_.empty()) {
      Entry e = stack_.pop();
      // The nearest child of an expanded node goes on at once, without a round trip through the
      // stack.
      while (beams_.anyOpen(e.rect, e.near)) {  // else hidden behind nearer hits
        if (e.ref.isLeaf()) {
          for (std::uint32_t i = e.ref.index; i < e.ref.index + e.ref.count; ++i) {
            testItem(slice_.items[i], e.rect, e.near);
          }
          break;
        }
        if (e.rect.beams() <= kTraceBeams) {
          traceRect(e);
          break;
        }
        if (!expand(&e)) break;
      }
    }
  }

 private:
  // Replaces *entry by the nearest of its node's children that may be seen in its window, after
  // pushing the others, farthest first; false if there is none.
  bool expand(Entry* entry) {
    // Only the fields needed, not the whole entry: it was just written field by field.
    const WideBvh::Node& node = slice_.wide.nodes()[entry->ref.index];
    const int col_lo = entry->rect.col_lo, col_hi = entry->rect.col_hi;
    SliceViews views;
    views.compute(node, views_);
    // The children's windows, field by field (a child's view may wrap into several windows).
    constexpr int kMax = 4 * 3;
    int child[kMax], lo[kMax], hi[kMax];
    float near[kMax];
    int n = 0;
    for (int k = 0; k < WideBvh::kWidth; ++k) {
      if (!(views.mask & (1 << k))) continue;
      auto add = [&](int first, int last) {
        const int l = std::max(first, col_lo), h = std::min(last, col_hi);
        if (l <= h && n < kMax) {
          child[n] = k;
          lo[n] = l;
          hi[n] = h;
          near[n] = views.near[k];
          ++n;
        }
      };
      if (views.columns_known & (1 << k)) {
        add(views.col_lo[k], views.col_hi[k]);
      } else if (!(views.az_half[k] >= 0)) {
        add(col_lo, col_hi);
      } else {
        beams_.grid().forEachColumnRange(views.az_center[k], views.az_half[k], add);
      }
    }
    if (n == 0) return false;
    int order[kMax];
    sortFarthestFirst(near, order, n);
    auto childEntry = [&](int j) {
      return Entry{node.child(child[j]), BeamRect{0, 0, lo[j], hi[j]}, near[j]};
    };
    for (int i = 0; i + 1 < n; ++i) stack_.push(childEntry(order[i]));
    *entry = childEntry(order[n - 1]);
    return true;
  }

  // The body's pose relative to the sensor.
  Eigen::Isometry3d sensorFromBody(int body) const {
    return sensor_from_frame_ * scene_.bodies()[body].frame_from_body;
  }
  const Mesh& meshOf(int body) const {
    return *std::get<std::shared_ptr<const Mesh>>(scene_.bodies()[body].shape);
  }

  // A segment against the beams [first, last] as Slicer tests it; a hit improving *best (if
  // given) or offered to the beam.
  template <class Hit, class Open>
  void testSegment(const KeptSlice::Item& s, int first, int last, Hit&& hit, Open&& open) {
    if (motion_) {
      testSegmentByColumn(s, first, last, hit, open);
      return;
    }
    Eigen::Vector2d front;
    if (config_.cull_backfaces) front = frontOf(s, first);
    testSegmentInFan(beams_.grid().pattern(), plane_.toSensor(s.p), plane_.toSensor(s.q),
                     config_.tmin, config_.tmax, config_.cull_backfaces ? &front : nullptr, first,
                     last, hit, open);
  }

  // testSegment for a sweep's block: the columns forSegmentColumns finds for the block's spread,
  // each beam tested against the segment mapped to its column's sensor x, y, as testSegmentInFan
  // tests it (beamCrossesSegment).
  template <class Hit, class Open>
  void testSegmentByColumn(const KeptSlice::Item& s, int first, int last, Hit&& hit, Open&& open) {
    const Eigen::Vector2d p = plane_.toSensor(s.p), q = plane_.toSensor(s.q);
    const auto& dirs = beams_.grid().pattern().directions();
    forSegmentColumns(
        beams_.grid().pattern(), p, q, first, last, spread_.shift, spread_.turn,
        [&](int lo, int hi, double near) {
          for (int col = lo; col <= hi; ++col) {
            if (!open(col, near)) continue;
            Eigen::Vector2d front;
            if (config_.cull_backfaces) front = frontOf(s, col);
            double t;
            if (beamCrossesSegment(dirs[col].x(), dirs[col].y(), motion_->pointToColumn(col, p),
                                   motion_->pointToColumn(col, q), config_.tmin, config_.tmax,
                                   config_.cull_backfaces ? &front : nullptr, &t)) {
              hit(col, t);
            }
          }
        });
  }

  // A point of the plane in the sensor's x, y (column col's sensor for a sweep).
  Eigen::Vector2d toSensor(int col, const Eigen::Vector2d& w) const {
    return motion_ ? motion_->pointToColumn(col, plane_.toSensor(w)) : plane_.toSensor(w);
  }

  void offerSegmentHit(int col, double t, const KeptSlice::Item& s) {
    const Mesh& mesh = meshOf(s.body);
    const std::uint32_t triangle = mesh.bvh().triangleIds()[s.slot];
    beams_.keepNearestHit(0, col, t, s.body, static_cast<int>(triangle), [&] {
      const Eigen::Vector3d n = sensorFromBody(s.body).linear() * mesh.normal(triangle);
      return motion_ ? motion_->toColumn(col, n) : n;
    });
  }

  void testItem(const KeptSlice::Item& item, const BeamRect& rect, float near) {
    (*cast_)[item.body].store(1, std::memory_order_relaxed);
    if (item.slot == KeptSlice::kPrimitive) {
      castPrimitiveItem(item.body, rect);
      return;
    }
    testSegment(
        item, rect.col_lo, rect.col_hi, [&](int col, double t) { offerSegmentHit(col, t, item); },
        [&](int col, double segment_near) {
          return beams_.range(0, col) >= std::max(double(near), segment_near);
        });
  }

  // A primitive: its pose, culled by its box's view as the scene walk culls it, then cast over the
  // rect, or after the walk if it is large for its distance (a wall the sensor stands beside:
  // nearest first would test it with every beam before the nearer things in front of it).
  void castPrimitiveItem(int index, const BeamRect& rect) {
    PlacedBody a = placeBody(scene_, index, sensor_from_frame_);
    viewPlacedBody(scene_, beams_.grid().pattern().angleMin(), false, &a, spread_);
    a.motion = motion_;
    if (!(a.view.near <= config_.tmax) || !a.view.crosses) return;
    beams_.grid().forEachRect(a.view, rect, [&](const BeamRect& r) {
      if (deferLargePrimitive(a)) {
        deferred_.add(a, r);
      } else if (beams_.anyOpen(r, a.view.near)) {
        castPrimitive(beams_, scene_, a, config_, r);
      }
    });
  }

  // A beam traced through a subtree: its ray in plane coordinates and its nearest item so far.
  struct Traced {
    int col;
    double dx, dy, tmax;
    const KeptSlice::Item* best;
    double best_t;
    PlaneRay ray;
  };

  // The test of a traced beam against a leaf's item.
  auto leafTest(Traced* b) {
    return [this, b](std::uint32_t i) {
      const KeptSlice::Item& item = slice_.items[i];
      (*cast_)[item.body].store(1, std::memory_order_relaxed);
      if (item.slot == KeptSlice::kPrimitive) {
        PlacedBody a = placeBody(scene_, item.body, sensor_from_frame_);
        placeSensorInBody(&a);
        a.motion = motion_;
        castPrimitiveBeam(beams_, scene_, a, config_, 0, b->col);
        b->tmax = std::min(b->tmax, beams_.range(0, b->col));
        return;
      }
      Eigen::Vector2d front;
      if (config_.cull_backfaces) front = frontOf(item, b->col);
      double t;
      if (!beamCrossesSegment(b->dx, b->dy, toSensor(b->col, item.p), toSensor(b->col, item.q),
                              config_.tmin, b->tmax, config_.cull_backfaces ? &front : nullptr,
                              &t)) {
        return;
      }
      if (t < b->best_t || (t == b->best_t && before(item, *b->best))) {
        b->best = &item;
        b->best_t = t;
        b->tmax = t;
      }
    };
  }

  // Each open beam of the rect through the node's subtree, two at a time (their walks side by
  // side): box tests in plane coordinates, each item tested as testItem tests it.
  void traceRect(const Entry& e) {
    const auto& dirs = beams_.grid().pattern().directions();
    Traced pair[2];
    int n = 0;
    for (int col = e.rect.col_lo; col <= e.rect.col_hi; ++col) {
      const double range = beams_.range(0, col);
      if (!(range >= e.near)) continue;
      Traced& b = pair[n++];
      b.col = col;
      b.dx = dirs[col].x();
      b.dy = dirs[col].y();
      b.tmax = std::min(config_.tmax, range);
      b.best = nullptr;
      b.best_t = std::numeric_limits<double>::infinity();
      if (motion_) {
        b.ray = columnRay(col, b.dx, b.dy);
      } else {
        b.ray = PlaneRay(*origin_, inverse_ * Eigen::Vector2d(b.dx, b.dy));
      }
      if (n == 2) {
        traceWidePair(slice_.wide, e.ref, pair[0].ray, &pair[0].tmax, leafTest(&pair[0]),
                      pair[1].ray, &pair[1].tmax, leafTest(&pair[1]));
        finish(pair[0]);
        finish(pair[1]);
        n = 0;
      }
    }
    if (n == 1) {
      traceWide(slice_.wide, e.ref, pair[0].ray, &pair[0].tmax, leafTest(&pair[0]));
      finish(pair[0]);
    }
  }

  void finish(const Traced& b) {
    if (b.best) offerSegmentHit(b.col, b.best_t, *b.best);
  }

  // A sweep's beam (direction dx, dy) for the box tests: from its column's origin, in plane
  // coordinates. A beam is traced in every node whose window holds it (2.2 times a scan, on the
  // benchmark's rotating LDS-01 through the warehouse), so each column's ray is made once a walk.
  // The last ones are kept by column (a node's window is at most kTraceBeams columns, and its
  // neighbours' overlap it): a walk that traces few beams sets up no more than it uses.
  const PlaneRay& columnRay(int col, double dx, double dy) {
    KeptRay& kept = column_rays_[static_cast<unsigned>(col) % column_rays_.size()];
    if (kept.col != col) {
      const ColumnMotion::Pose& m = motion_->refFromColumn(col);
      const Eigen::Vector2d at =
          inverse_ * (m.translation().head<2>() - Eigen::Vector2d(plane_.tx, plane_.ty));
      const Eigen::Vector2d along = m.linear().topLeftCorner<2, 2>() * Eigen::Vector2d(dx, dy);
      kept.ray.emplace(PlaneRay::Origin(at, slice_.tree.bounds(), config_.tmin), inverse_ * along);
      kept.col = col;
    }
    return *kept.ray;
  }

  // Which of two items hit at the same distance goes first (hit_order.h): the lower body, then the
  // lower triangle.
  bool before(const KeptSlice::Item& a, const KeptSlice::Item& b) const {
    if (a.body != b.body) return a.body < b.body;  // before reading a.body's mesh for b's slot
    const auto& ids = meshOf(a.body).bvh().triangleIds();
    return tieBefore(a.body, ids[a.slot], b.body, ids[b.slot]);
  }

  // The item's triangle's front normal in the sensor's x, y (of column col's sensor for a sweep).
  Eigen::Vector2d frontOf(const KeptSlice::Item& s, int col) const {
    Eigen::Matrix3d rot = sensorFromBody(s.body).linear();
    if (motion_) rot = motion_->refFromColumn(col).linear().transpose() * rot;
    return planarFront(rot, meshOf(s.body).bvh().triangleVertices()[s.slot]);
  }

  BeamSet& beams_;
  const Scene& scene_;
  const KeptSlice& slice_;
  const ScanPlane& plane_;
  const Eigen::Isometry3d sensor_from_frame_;
  const CastConfig& config_;
  std::vector<std::atomic<char>>* cast_;
  const ColumnMotion* motion_;  // a sweep's block, or null
  const Spread spread_;
  const Eigen::Isometry3d sensor_from_plane_;
  const SliceViewBasis views_;
  Eigen::Matrix2d inverse_;
  std::optional<PlaneRay::Origin> origin_;
  struct KeptRay {
    int col = -1;
    std::optional<PlaneRay> ray;
  };
  std::array<KeptRay, 2 * kTraceBeams> column_rays_;  // columnRay()'s last ones
  WalkStack<Entry> stack_;
  DeferredPrimitives deferred_;  // cast after the walk
};

}  // namespace

void walkSlice(BeamSet& beams, const Scene& scene, const KeptSlice& slice, const ScanPlane& plane,
               const Eigen::Isometry3d& sensor_from_frame, const CastConfig& config,
               const BeamRect& within, std::vector<std::atomic<char>>* cast,
               const ColumnMotion* motion) {
  SliceWalk(beams, scene, slice, plane, sensor_from_frame, config, cast, motion).run(within);
}

}  // namespace core
}  // namespace laser_raycast
