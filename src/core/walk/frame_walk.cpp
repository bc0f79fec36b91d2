#include "walk/frame_walk.h"
#include "beams/placed_body.h"

#include <algorithm>
#include <optional>

#include "walk/mesh_walk.h"
#include "slice/slicer.h"
#include "beams/node_views.h"
#include "walk/primitive_cast.h"

namespace laser_raycast {
namespace core {
namespace {

class FrameWalk {
 public:
  FrameWalk(BeamSet& beams, const Scene& scene, const SceneIndex::Group& group,
            const Eigen::Isometry3d& sensor_from_frame, const CastConfig& config,
            std::vector<std::atomic<char>>* cast, const ColumnMotion* motion)
      : beams_(beams),
        scene_(scene),
        group_(group),
        sensor_from_frame_(sensor_from_frame),
        config_(config),
        cast_(cast),
        motion_(motion),
        spread_(motion ? motion->spread() : Spread()),
        planar_(beams.grid().pattern().planar()),
        basis_(sensor_from_frame, planar_, config.tmax, spread_) {
    // A sweep's planar beams are traced, not sliced (their planes differ from column to column).
    if (planar_ && !motion) plane_.emplace(sensor_from_frame);
  }

  void run(const BeamRect& within) {
    if (group_.wide.empty()) return;
    const Aabb& bounds = group_.tree.bounds();
    const Eigen::Matrix3d& rot = sensor_from_frame_.linear();
    const View view =
        boxView(bounds.center(), bounds.extent() * 0.5, rot, rot.cwiseAbs(),
                sensor_from_frame_.translation(), beams_.grid().pattern().angleMin(), !planar_,
                spread_);
    if (!(view.near <= config_.tmax) || (planar_ && !view.crosses)) return;
    beams_.grid().forEachRect(view, within, [&](const BeamRect& rect) {
      push(Entry{group_.wide.root(), rect, floatBelow(view.near), -1});
    });
    while (!heap_.empty()) {
      std::pop_heap(heap_.begin(), heap_.end(), farther);
      const Entry e = heap_.back();
      heap_.pop_back();
      if (!beams_.anyOpen(e.rect, e.near)) continue;  // hidden behind nearer hits
      if (e.body >= 0) {
        const PlacedBody& a = bodies_[e.body];
        (*cast_)[a.index].store(1, std::memory_order_relaxed);
        if (!isPrimitive(a.index)) {
          walkMesh(beams_, scene_, a, config_, e.rect);
        } else if (deferLargePrimitive(a)) {
          deferred_.add(a, e.rect);
        } else {
          castPrimitive(beams_, scene_, a, config_, e.rect);
        }
      } else if (e.ref.isLeaf()) {
        for (std::uint32_t slot = e.ref.index; slot < e.ref.index + e.ref.count; ++slot) {
          placeLeafBody(group_.bodies[group_.tree.triangleIds()[slot]], e.rect);
        }
      } else {
        expand(e);
      }
    }
    // Large primitives, nearest first, once everything nearer has had its turn.
    deferred_.cast(beams_, scene_, config_);
  }

 private:
  bool isPrimitive(int body) const {
    return !std::holds_alternative<std::shared_ptr<const Mesh>>(scene_.bodies()[body].shape);
  }

  // A node of the tree, or a body ready to be cast (body >= 0: its index in bodies_).
  struct Entry {
    WideBvh::Ref ref;
    BeamRect rect;
    float near;
    int body = -1;
  };

  void expand(const Entry& e) {
    const WideBvh::Node& node = group_.wide.nodes()[e.ref.index];
    NodeViews views;
    views.compute(node, basis_);
    Entry children[4 * 3];  // a child's view may wrap into several rects
    int n = 0;
    for (int k = 0; k < WideBvh::kWidth; ++k) {
      if (!(views.mask & (1 << k))) continue;
      beams_.grid().forEachChildRect(views, k, e.rect, [&](const BeamRect& rect) {
        if (n < 12) children[n++] = Entry{node.child(k), rect, views.near[k], -1};
      });
    }
    for (int j = 0; j < n; ++j) push(children[j]);
  }

  // A body of a leaf: its pose relative to the sensor, then culled by its bounding sphere against
  // the search interval and by its box's view against the scan plane (planar fans) and the leaf's
  // beams; the rest waits its turn by its own nearest distance.
  void placeLeafBody(int index, const BeamRect& rect) {
    // The sphere first: a cheap answer for bodies out of range.
    PlacedBody a = placeBody(scene_, index, sensor_from_frame_);
    const double dist = a.center.norm();
    const double radius = a.radius + spread_.shift;  // from every origin of a sweep's block
    const double slack = kWindowSlack * (dist + radius + config_.tmax);
    if (dist - radius > config_.tmax + slack || dist + radius < config_.tmin - slack) return;
    viewPlacedBody(scene_, beams_.grid().pattern().angleMin(), !planar_, &a, spread_);
    a.motion = motion_;
    if (!(a.view.near <= config_.tmax) || (planar_ && !a.view.crosses)) return;
    if (plane_) {
      a.plane = &*plane_;
      a.frame_from_body = scene_.bodies()[index].frame_from_body;
    }
    const int slot = static_cast<int>(bodies_.size());
    bodies_.push_back(a);
    beams_.grid().forEachRect(a.view, rect, [&](const BeamRect& r) {
      push(Entry{WideBvh::Ref{WideBvh::kEmpty, 0}, r, floatBelow(a.view.near), slot});
    });
  }

  BeamSet& beams_;
  const Scene& scene_;
  const SceneIndex::Group& group_;
  const Eigen::Isometry3d sensor_from_frame_;
  const CastConfig& config_;
  std::vector<std::atomic<char>>* cast_;
  const ColumnMotion* motion_;
  const Spread spread_;
  const bool planar_;
  const ViewBasis basis_;
  std::optional<ScanPlane> plane_;  // planar fans: the scan plane in the frame
  // Nearest first over the whole tree (a heap rather than a stack: a depth-first walk would finish
  // a near node's far bodies before the next near node), so that near hits hide far bodies.
  static bool farther(const Entry& a, const Entry& b) { return a.near > b.near; }
  void push(const Entry& e) {
    heap_.push_back(e);
    std::push_heap(heap_.begin(), heap_.end(), farther);
  }
  std::vector<Entry> heap_;
  std::vector<PlacedBody> bodies_;  // placed this walk
  DeferredPrimitives deferred_;             // large primitives, cast after the walk
};

}  // namespace

void walkFrame(BeamSet& beams, const Scene& scene, const SceneIndex::Group& group,
               const Eigen::Isometry3d& sensor_from_frame, const CastConfig& config,
               const BeamRect& within, std::vector<std::atomic<char>>* cast,
               const ColumnMotion* motion) {
  FrameWalk(beams, scene, group, sensor_from_frame, config, cast, motion).run(within);
}

}  // namespace core
}  // namespace laser_raycast
