// A frame's bodies cut by one scan plane, kept between scans. A 2D scanner on a ground robot cuts
// the static world in the same plane scan after scan: the plane's pose in each frame (ScanPlane's
// normal and offset, kept to 44 bits) stays the same, bit for bit, while the robot drives and turns
// in it (whatever ulps TF's composition of its pose moves it by), and so do the segments where the
// frame's meshes cross it, in plane coordinates. Kept, with the primitives that cross the plane, in
// one tree per frame, they make a planar cast a 2D problem (slice_walk.h): no per-body work for
// what lies out of view, no triangle that misses the plane. The cast's result is the same either
// way: the walk without a kept slice computes a segment's ends by the same steps from the same
// vertices (slicer.h).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "laser_raycast/core/bvh.h"
#include "slice/slicer.h"
#include "laser_raycast/core/scene.h"
#include "scene/scene_index.h"
#include "accel/wide_bvh.h"

namespace laser_raycast {
namespace core {

struct KeptSlice {
  static constexpr std::uint32_t kPrimitive = std::numeric_limits<std::uint32_t>::max();
  // A segment of a mesh body's triangle, or a primitive body that may cross the plane.
  struct Item {
    Eigen::Vector2d p, q;  // a segment's ends in plane coordinates (p != q); a primitive's bounds
    int body;              // index into Scene::bodies()
    std::uint32_t slot;    // the triangle's slot in the body's mesh BVH, or kPrimitive
  };
  std::vector<Item> items;  // in the order of tree's slots: the item of slot s is items[s]
  Bvh tree;                 // over the items' boxes (plane coordinates, z = 0)
  WideBvh wide;             // the walk's layout of tree

  // The group's bodies crossing frame's plane. The WideBvh refers to the Bvh: a slice stays where
  // it was built.
  static std::unique_ptr<KeptSlice> build(const Scene& scene, const SceneIndex::Group& group,
                                           const ScanPlane& plane);
};

// The slices of the frames a caster meets, by frame and plane. A plane is sliced whole the second
// time it is met in a frame (a plane met once, such as a tilting sensor's, is not worth it). Slices
// unused for kKeepScans scans are dropped, and the least recently used beyond kMaxItems items in
// all. Thread-safe.
class KeptSlices {
 public:
  static constexpr int kKeepScans = 16;
  // About 100 bytes an item with its tree: a few hundred MB at most.
  static constexpr std::size_t kMaxItems = 4000000;

  // The slice of group by frame's plane, or null (not yet worth building, or too large to keep).
  const KeptSlice* find(const Scene& scene, const SceneIndex::Group& group,
                         const ScanPlane& plane);
  // Starts a scan: drops what was not used recently.
  void newScan();
  std::size_t slices() const;

 private:
  struct Key {
    std::uint64_t scene_version;
    const SceneIndex::Group* group;
    double n[3], offset;
    bool operator==(const Key& o) const;
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const;
  };
  struct Entry {
    std::unique_ptr<KeptSlice> slice;
    int sightings = 0;
    std::uint64_t last_scan = 0;
  };

  mutable std::mutex mutex_;
  std::unordered_map<Key, Entry, KeyHash> entries_;
  std::uint64_t scan_ = 0;
  std::size_t items_ = 0;
};

}  // namespace core
}  // namespace laser_raycast
