#include "slice/kept_slice.h"

#include <algorithm>
#include <cstring>
#include <functional>

#include "accel/wide_bvh.h"

namespace laser_raycast {
namespace core {
namespace {

// A mesh body's segments: the triangles of its BVH whose boxes may meet the plane, each cut as
// Slicer cuts it.
void addMeshSegments(const Mesh& mesh, int body, const Eigen::Isometry3d& frame_from_mesh,
                     const ScanPlane& plane, std::vector<KeptSlice::Item>* items) {
  const auto& slots = mesh.bvh().triangleVertices();
  const MeshCut cut(plane, frame_from_mesh);
  mesh.wideBvh().visit([&](const Aabb& box) { return plane.mayMeet(frame_from_mesh, box); },
                       [&](std::uint32_t slot) {
                         Eigen::Vector2d p, q;
                         if (!cut.crossing(slots[slot], &p, &q) || p == q) return;
                         items->push_back(KeptSlice::Item{p, q, body, slot});
                       });
}

// A primitive body whose box may meet the plane, with the bounds of its box's corners in plane
// coordinates.
void addPrimitive(const Scene& scene, int body, const ScanPlane& plane,
                  std::vector<KeptSlice::Item>* items) {
  const Eigen::Isometry3d& pose = scene.bodies()[body].frame_from_body;
  Aabb own;
  own.lo = scene.boxCenter(body) - scene.boxHalf(body);
  own.hi = scene.boxCenter(body) + scene.boxHalf(body);
  if (!plane.mayMeet(pose, own)) return;
  Eigen::Vector3d c, e;
  boxInFrame(pose, own, &c, &e);
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d sign(corner & 1 ? 1 : -1, corner & 2 ? 1 : -1, corner & 4 ? 1 : -1);
    const Eigen::Vector2d w = plane.planeCoords(c + sign.cwiseProduct(e));
    lo = lo.cwiseMin(w);
    hi = hi.cwiseMax(w);
  }
  // Widened for the rounding of the plane coordinates: the walk only culls by these bounds.
  const Eigen::Vector2d pad = 8 * std::numeric_limits<double>::epsilon() *
                              (lo.cwiseAbs() + hi.cwiseAbs() + Eigen::Vector2d::Ones());
  items->push_back(KeptSlice::Item{lo - pad, hi + pad, body, KeptSlice::kPrimitive});
}

}  // namespace

std::unique_ptr<KeptSlice> KeptSlice::build(const Scene& scene, const SceneIndex::Group& group,
                                            const ScanPlane& plane) {
  auto slice = std::make_unique<KeptSlice>();
  for (const int body : group.bodies) {
    const Body& b = scene.bodies()[body];
    if (const auto* mesh = std::get_if<std::shared_ptr<const Mesh>>(&b.shape)) {
      addMeshSegments(**mesh, body, b.frame_from_body, plane, &slice->items);
    } else {
      addPrimitive(scene, body, plane, &slice->items);
    }
  }
  // The tree is built over 2D boxes, but the SAH weighs a box by its area, and a flat box (an
  // axis-aligned segment) has none: each box gets the same height, as large as the slice, so that
  // the area follows the perimeter, which is what a 2D ray meets. The walk ignores the height.
  Aabb all;
  for (const Item& item : slice->items) {
    all.grow(Eigen::Vector3d(item.p.x(), item.p.y(), 0));
    all.grow(Eigen::Vector3d(item.q.x(), item.q.y(), 0));
  }
  const double height = all.empty() ? 1.0 : std::max(1.0, all.extent().maxCoeff());
  std::vector<Aabb> boxes;
  boxes.reserve(slice->items.size());
  for (const Item& item : slice->items) {
    Aabb box;
    box.grow(Eigen::Vector3d(item.p.x(), item.p.y(), -height));
    box.grow(Eigen::Vector3d(item.q.x(), item.q.y(), height));
    boxes.push_back(box);
  }
  slice->tree = Bvh::buildOverBoxes(boxes);
  slice->wide = WideBvh(slice->tree, {});
  // The items in the tree's slot order: a leaf's are side by side, with no look-up in between.
  std::vector<Item> by_slot;
  by_slot.reserve(slice->items.size());
  for (const std::uint32_t id : slice->tree.triangleIds()) by_slot.push_back(slice->items[id]);
  slice->items = std::move(by_slot);
  return slice;
}

bool KeptSlices::Key::operator==(const Key& o) const {
  // Bitwise: the same plane, not a nearby one.
  return scene_version == o.scene_version && group == o.group &&
         std::memcmp(n, o.n, sizeof n) == 0 && std::memcmp(&offset, &o.offset, sizeof offset) == 0;
}

std::size_t KeptSlices::KeyHash::operator()(const Key& k) const {
  std::size_t h = std::hash<const void*>()(k.group) ^ std::hash<std::uint64_t>()(k.scene_version);
  for (const double x : {k.n[0], k.n[1], k.n[2], k.offset}) {
    std::uint64_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    h ^= std::hash<std::uint64_t>()(bits) + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
  }
  return h;
}

const KeptSlice* KeptSlices::find(const Scene& scene, const SceneIndex::Group& group,
                                  const ScanPlane& plane) {
  const Key key{scene.version(), &group, {plane.n.x(), plane.n.y(), plane.n.z()}, plane.offset};
  std::lock_guard<std::mutex> lock(mutex_);
  Entry& entry = entries_[key];
  entry.last_scan = scan_;
  if (entry.slice) return entry.slice.get();
  if (++entry.sightings != 2) return nullptr;  // once: not yet; beyond 2: too large to keep
  std::unique_ptr<KeptSlice> slice = KeptSlice::build(scene, group, plane);
  if (slice->items.size() > kMaxItems / 4) return nullptr;  // and never built again
  items_ += slice->items.size();
  entry.slice = std::move(slice);
  return entry.slice.get();
}

void KeptSlices::newScan() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++scan_;
  for (auto it = entries_.begin(); it != entries_.end();) {
    if (scan_ - it->second.last_scan > kKeepScans) {
      if (it->second.slice) items_ -= it->second.slice->items.size();
      it = entries_.erase(it);
    } else {
      ++it;
    }
  }
  while (items_ > kMaxItems) {
    auto oldest = entries_.end();
    for (auto it = entries_.begin(); it != entries_.end(); ++it) {
      if (it->second.slice &&
          (oldest == entries_.end() || it->second.last_scan < oldest->second.last_scan)) {
        oldest = it;
      }
    }
    items_ -= oldest->second.slice->items.size();
    entries_.erase(oldest);
  }
}

std::size_t KeptSlices::slices() const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::size_t n = 0;
  for (const auto& entry : entries_) n += entry.second.slice != nullptr;
  return n;
}

}  // namespace core
}  // namespace laser_raycast
