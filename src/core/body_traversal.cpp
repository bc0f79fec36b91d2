#include "laser_raycast/core/body_traversal.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "laser_raycast/core/edge_filter.h"
#include "laser_raycast/core/fan_slicer.h"
#include "laser_raycast/core/wide_bvh.h"

namespace laser_raycast {
namespace core {
namespace {

// Below this many beams a node's beams are traced through its subtree one ray at a time instead
// of its children's views being computed: views cost about as much as a few node visits of a
// traced ray. Only speed depends on it.
constexpr long long kTraceBeams = 32;

const Eigen::Matrix3d kIdentity = Eigen::Matrix3d::Identity();

// A component of n triangles is rasterised (3D patterns) if its box can reach at least
// n / kRasterBeamsPerTriangle beams of the whole pattern: setting up a triangle costs about as much
// as tracing that many beams. Only speed depends on it.
constexpr double kRasterBeamsPerTriangle = 5.0;

// A subtree being sliced with at most this many triangles is sliced whole; a larger one is walked
// with windows and occlusion tests first. Only speed depends on it.
constexpr std::uint32_t kPlainSliceTriangles = 4096;

// What slicing a component costs against testing its beams in 3D, in units of slicing one crossing
// triangle: a plane cuts about 2 sqrt(n) of a compact closed component's n triangles, and a beam's
// 3D tests cost about kBeamCostInSegments of those. Only speed depends on it.
constexpr double kBeamCostInSegments = 2.0;

template <TriangleMethod M>
class MeshWalk {
 public:
  MeshWalk(BeamSet& beams, const Mesh& mesh, const Caster::ActiveBody& active,
           const CastConfig& config)
      : beams_(beams),
        mesh_(mesh),
        wide_(mesh.wideBvh()),
        active_(active),
        config_(config),
        rot_(active.sensor_from_body.linear()),
        abs_rot_(rot_.cwiseAbs()),
        trans_(active.sensor_from_body.translation()),
        planar_(beams.pattern().planar()),
        slicing_(planar_ && config.planar_fast_path),
        rastering_(!planar_ && config.raster_fast_path),
        frame_(active.sensor_from_body, planar_, config.tmax),
        stamp_(beams.newWalkStamp()) {
    if (slicing_) {
      slicer_.emplace(mesh, active.sensor_from_body, beams.pattern(), config.tmin, config.tmax,
                      config.cull_backfaces);
    }
  }

  void run(const BeamRect& within) {
    if (wide_.empty()) return;
    const Aabb& bounds = wide_.binary().bounds();
    const View view = boxView(bounds.center(), bounds.extent() * 0.5, rot_, abs_rot_, trans_,
                              beams_.pattern().angleMin(), !planar_);
    if (!(view.near <= config_.tmax)) return;
    Mode mode = kTest;
    if (slicing_ || rastering_) {
      mode = wide_.rootGroup() >= 0
                 ? decide(wide_.rootGroup(), wide_.rootTriangles(), beams_.beamsReached(view))
                 : kMixed;
    }
    top_ = 0;
    Entry root{wide_.root(), BeamRect{}, view.near, mode, wide_.rootTriangles(), {}, {}};
    for (int a = 0; a < 3; ++a) {
      root.lo[a] = floatBelow(bounds.lo[a]);
      root.hi[a] = floatAbove(bounds.hi[a]);
    }
    beams_.forEachRect(view, within, [&](const BeamRect& rect) {
      root.rect = rect;
      push(root);
    });
    while (top_ > 0) {
      const Entry e = stack_[--top_];
      if (!beams_.anyOpen(e.rect, e.near)) continue;  // hidden behind nearer hits
      if (e.mode == kSlice && e.triangles <= kPlainSliceTriangles) {
        sliceSubtree(e);
      } else if (!e.ref.isLeaf()) {
        if (e.mode == kTest && e.rect.beams() <= kTraceBeams) {
          traceRect(e);
        } else {
          expand(e);
        }
      } else if (e.mode == kTest) {
        traceRect(e);
      } else if (planar_) {
        sliceLeaf(e.ref, e.rect, e.near);  // or a leaf of mixed components
      } else {
        rasterLeaf(e);  // or a leaf of mixed components
      }
    }
  }

 private:
  // kMixed: above the mesh's components (when components choose); within one component, chosen
  // for the whole scan: kSlice (planar fans) or kRaster (other patterns), else kTest (traced).
  enum Mode : unsigned char { kMixed, kSlice, kRaster, kTest };
  struct Entry {
    WideBvh::Ref ref;
    BeamRect rect;
    double near;
    Mode mode;
    std::uint32_t triangles;  // below ref
    float lo[3], hi[3];       // ref's box (mesh frame, rounded outward)
  };

  void push(const Entry& e) {
    if (top_ == static_cast<int>(stack_.size())) stack_.resize(stack_.size() * 2);
    stack_[top_++] = e;
  }

  // The same for every beam and every thread: it depends only on the component (its triangles)
  // and how many beams of the whole pattern its box can reach.
  Mode decide(std::int32_t group, std::uint32_t triangles, long long reached) const {
    const double n = triangles, beams = static_cast<double>(reached);
    if (planar_) {
      if (wide_.groupInMixedLeaf(group)) return kSlice;  // sliced wherever it is met
      return kBeamCostInSegments * beams >= 2 * std::sqrt(n) ? kSlice : kTest;
    }
    if (wide_.groupInMixedLeaf(group)) return kRaster;
    return kRasterBeamsPerTriangle * beams >= n ? kRaster : kTest;
  }

  void expand(const Entry& e) {
    const WideBvh::Node& node = wide_.nodes()[e.ref.index];
    NodeViews views;
    views.compute(node, frame_);
    if (!views.mask) return;
    Entry children[4 * 3];  // a child's view may wrap into several rects
    int n = 0;
    for (int k = 0; k < WideBvh::kWidth; ++k) {
      if (!(views.mask & (1 << k))) continue;
      Mode mode = e.mode;
      if (mode == kMixed) {
        const std::int32_t group = wide_.childGroup(e.ref.index, k);
        if (group >= 0) {
          long long reached = 0;
          beams_.forEachChildRect(views, k, beams_.all(),
                                  [&](const BeamRect& rect) { reached += rect.beams(); });
          mode = decide(group, wide_.childTriangles(e.ref.index, k), reached);
        }
      }
      beams_.forEachChildRect(views, k, e.rect, [&](const BeamRect& rect) {
        if (n < 12) {
          Entry& child = children[n++];
          child.ref = node.child(k);
          child.rect = rect;
          child.near = views.near[k];
          child.mode = mode;
          child.triangles = wide_.childTriangles(e.ref.index, k);
          for (int a = 0; a < 3; ++a) {
            child.lo[a] = node.lo[a][k];
            child.hi[a] = node.hi[a][k];
          }
        }
      });
    }
    // Farthest first onto the stack, so that the nearest is walked next (insertion sort: n <= 12).
    for (int j = 1; j < n; ++j) {
      const Entry moving = children[j];
      int i = j;
      for (; i > 0 && children[i - 1].near < moving.near; --i) children[i] = children[i - 1];
      children[i] = moving;
    }
    for (int j = 0; j < n; ++j) push(children[j]);
  }

  // The beam as a ray in the body's frame, the same one for every test against this body.
  const WideRay<M>& ray(int row, int col) {
    return beams_.template bodyRay<M>(row, col, stamp_, [&](const Eigen::Vector3d& dir) {
      Ray r;
      r.origin = active_.sensor_in_body;
      r.dir = active_.body_from_sensor_rot * dir;
      r.tmin = config_.tmin;
      return WideRay<M>(r, config_.cull_backfaces, wide_.binary().bounds());
    });
  }

  void offerMeshHit(int row, int col, double t, std::uint32_t triangle) {
    beams_.offer(row, col, t, active_.index, static_cast<int>(triangle),
                 [&] { return Eigen::Vector3d(rot_ * mesh_.normal(triangle)); });
  }

  // Each open beam of the rect through the node's subtree (or leaf), one ray at a time, starting
  // with the node's box.
  void traceRect(const Entry& e) {
    for (int row = e.rect.row_lo; row <= e.rect.row_hi; ++row) {
      for (int col = e.rect.col_lo; col <= e.rect.col_hi; ++col) {
        const double range = beams_.range(row, col);
        if (!(range >= e.near)) continue;  // a hit nearer than this node can be
        double tmax = std::min(config_.tmax, range);
        std::optional<MeshHit> best;
        if (ray(row, col).closestHit(wide_, e.ref, e.lo, e.hi, &tmax, &best)) {
          offerMeshHit(row, col, best->t, best->triangle);
        }
      }
    }
  }

  // Each triangle of the leaf, in the sensor frame, against the open beams of its own window:
  // four beams at a time through a conservative float test of the three edge planes (through the
  // sensor and an edge each), then the exact test for the beams that pass. Every beam meets this
  // component only here, through the same sensor-frame rays, so shared edges stay watertight.
  void rasterLeaf(const Entry& e) {
    const auto& slots = mesh_.bvh().triangleVertices();
    const auto& ids = mesh_.bvh().triangleIds();
    for (std::uint32_t slot = e.ref.index; slot < e.ref.index + e.ref.count; ++slot) {
      const auto& v = slots[slot];
      const Eigen::Vector3d a = rot_ * v[0] + trans_, b = rot_ * v[1] + trans_,
                            c = rot_ * v[2] + trans_;
      const Eigen::Vector3d lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
      const View view = boxView((lo + hi) * 0.5, (hi - lo) * 0.5, kIdentity, kIdentity,
                                Eigen::Vector3d::Zero(), beams_.pattern().angleMin(), true);
      if (!(view.near <= config_.tmax)) continue;
      EdgeFilter filter(a, b, c);
      beams_.forEachRect(view, e.rect, [&](const BeamRect& rect) {
        for (int row = rect.row_lo; row <= rect.row_hi; ++row) {
          filter.forEachCandidate(beams_, row, rect.col_lo, rect.col_hi, [&](int col) {
            const double range = beams_.range(row, col);
            if (!(range >= view.near)) return;
            const auto hit = beams_.template sensorRay<M>(row, col).intersect(
                a, b, c, std::min(config_.tmax, range));
            if (!hit) return;
            const std::uint32_t triangle = ids[slot];
            beams_.offer(row, col, hit->t, active_.index, static_cast<int>(triangle),
                         [&] { return Eigen::Vector3d(rot_ * mesh_.normal(triangle)); });
          });
        }
      });
    }
  }

  // Every leaf below the entry that meets the scan plane, sliced into the entry's beams, with no
  // windows or occlusion tests on the way: for a small subtree they cost more than they save.
  void sliceSubtree(const Entry& e) {
    WideBvh::Ref stack[64 * (WideBvh::kWidth - 1) + 1];
    int top = 0;
    stack[top++] = e.ref;
    while (top > 0) {
      const WideBvh::Ref ref = stack[--top];
      if (ref.isLeaf()) {
        sliceLeaf(ref, e.rect, e.near);
        continue;
      }
      const WideBvh::Node& node = wide_.nodes()[ref.index];
      const int mask = planeMask(node, frame_);
      for (int k = 0; k < WideBvh::kWidth; ++k) {
        if (mask & (1 << k)) stack[top++] = node.child(k);
      }
    }
  }

  void sliceLeaf(WideBvh::Ref leaf, const BeamRect& rect, double near) {
    const auto& ids = mesh_.bvh().triangleIds();
    for (std::uint32_t slot = leaf.index; slot < leaf.index + leaf.count; ++slot) {
      slicer_->sliceSlot(
          slot, rect.col_lo, rect.col_hi,
          [&](int col, double t) {
            beams_.offer(0, col, t, active_.index, static_cast<int>(ids[slot]),
                         [&] { return slicer_->sensorNormal(slot); });
          },
          [&](int col, double segment_near) {
            return beams_.range(0, col) >= std::max(near, segment_near);
          });
    }
  }

  BeamSet& beams_;
  const Mesh& mesh_;
  const WideBvh& wide_;
  const Caster::ActiveBody& active_;
  const CastConfig& config_;
  const Eigen::Matrix3d rot_, abs_rot_;
  const Eigen::Vector3d trans_;
  const bool planar_, slicing_, rastering_;
  const ViewFrame frame_;
  const std::uint32_t stamp_;
  std::optional<PlaneSlicer> slicer_;
  std::vector<Entry> stack_ = std::vector<Entry>(256);
  int top_ = 0;
};

// A primitive: each open beam of the window that passes within its bounding sphere, analytically.
void castPrimitive(BeamSet& beams, const Body& body, const Caster::ActiveBody& a,
                   const CastConfig& config, const BeamRect& rect) {
  const double slack = kWindowSlack * (a.center.squaredNorm() + a.radius * a.radius);
  for (int row = rect.row_lo; row <= rect.row_hi; ++row) {
    for (int col = rect.col_lo; col <= rect.col_hi; ++col) {
      const double range = beams.range(row, col);
      if (!(range >= a.view.near)) continue;
      const Eigen::Vector3d& d = beams.direction(row, col);
      const double along = d.dot(a.center);
      if ((a.center - along * d).squaredNorm() - a.radius * a.radius > slack) continue;
      Ray ray;
      ray.origin = a.sensor_in_body;
      ray.dir = a.body_from_sensor_rot * d;
      ray.tmin = config.tmin;
      ray.tmax = std::min(config.tmax, range);
      std::optional<PrimitiveHit> hit;
      if (const auto* box = std::get_if<Box>(&body.shape)) hit = intersect(ray, *box);
      if (const auto* cylinder = std::get_if<Cylinder>(&body.shape))
        hit = intersect(ray, *cylinder);
      if (const auto* sphere = std::get_if<Sphere>(&body.shape)) hit = intersect(ray, *sphere);
      if (!hit) continue;
      beams.offer(row, col, hit->t, a.index, -1,
                  [&] { return Eigen::Vector3d(a.sensor_from_body.linear() * hit->normal); });
    }
  }
}

}  // namespace

void castBody(BeamSet& beams, const Scene& scene, const Caster::ActiveBody& active,
              const CastConfig& config, const BeamRect& within) {
  const Body& body = scene.bodies()[active.index];
  const auto* mesh = std::get_if<std::shared_ptr<const Mesh>>(&body.shape);
  if (!mesh) {
    castPrimitive(beams, body, active, config, within);
    return;
  }
  dispatchTriangleMethod(config.method, [&](auto method) {
    MeshWalk<decltype(method)::value> walk(beams, **mesh, active, config);
    walk.run(within);
  });
}

}  // namespace core
}  // namespace laser_raycast
