// A 4-wide BVH for the caster: each node holds four children's boxes in float, rounded outward, and
// a ray tests all four with one set of SSE2 instructions (the x86-64 baseline, so no run-time check
// is needed). It is built by collapsing a mesh's binary SAH BVH and its leaves are that BVH's
// triangle slots, so the triangle tests are the same exact double tests.
//
// Conservative box tests: a box the exact ray enters is never skipped. The boxes contain the exact
// ones; the ray origin is rounded to float once down and once up, and each slab plane uses the one
// that moves it towards the ray (the near plane can only come nearer, the far plane only farther);
// the remaining error is the relative rounding of the subtraction, the reciprocal and the product,
// which widening the exit distance by 1 + 2 gamma(3) covers (Ize, "Robust BVH Ray Traversal", JCGT
// 2013).
#pragma once

#include <emmintrin.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <vector>

#include "laser_raycast/core/bvh.h"

namespace laser_raycast {
namespace core {

// The float nearest to x in the direction of -inf (floatBelow) or +inf (floatAbove) that is not
// beyond x: x itself if it is a float. Finite x only (infinities and NaN pass through).
inline float floatBelow(double x) {
  const float f = static_cast<float>(x);
  if (!(f > x)) return f;
  // f > x: step one float towards -inf (f is finite and not -max here).
  std::uint32_t bits;
  std::memcpy(&bits, &f, sizeof bits);
  if (f > 0) {
    --bits;
  } else if (f < 0) {
    ++bits;
  } else {
    bits = 0x80000001u;  // -0 and +0 step to the negative smallest subnormal
  }
  float g;
  std::memcpy(&g, &bits, sizeof g);
  return g;
}
inline float floatAbove(double x) { return -floatBelow(-x); }

class WideBvh {
 public:
  static constexpr int kWidth = 4;
  static constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();
  // Binary subtrees of one group with at most this many triangles become one leaf.
  static constexpr std::uint32_t kMaxLeafTriangles = 2;

  // A subtree: an inner node (count == 0, index into nodes()), a leaf (count triangle slots of the
  // binary BVH from index on), or nothing (index == kEmpty).
  // Trivially constructible, so that a traversal's stack of them costs nothing to set up.
  struct Ref {
    std::uint32_t index;
    std::uint32_t count;
    bool isLeaf() const { return count > 0; }
    bool isEmpty() const { return index == kEmpty; }
  };

  // Four children. An empty child has lo = +inf and hi = -inf, but a box test alone cannot be
  // trusted to miss it: a direction component beyond ~1e45 has a float reciprocal of 0, and
  // (+inf - origin) * 0 is NaN, which the tests ignore (found by test/fuzz/fuzz_core: the
  // traversal pushed an empty child and read past the nodes). Every traversal masks its box tests
  // with presentMask().
  struct alignas(64) Node {
    float lo[3][kWidth];  // [axis][child]
    float hi[3][kWidth];
    std::uint32_t index[kWidth];
    std::uint32_t count[kWidth];
    Ref child(int k) const { return Ref{index[k], count[k]}; }
    // Bit k set iff child k exists.
    int presentMask() const {
      int mask = 0;
      for (int k = 0; k < kWidth; ++k) mask |= int(index[k] != kEmpty) << k;
      return mask;
    }
  };

  WideBvh() = default;
  // Collapses bvh (which must outlive this and not move). slot_group: the group of each of bvh's
  // triangle slots (e.g. the connected component of its triangle), or empty.
  WideBvh(const Bvh& bvh, const std::vector<std::uint32_t>& slot_group);

  const Bvh& binary() const { return *bvh_; }
  const std::vector<Node>& nodes() const { return nodes_; }
  Ref root() const { return root_; }
  bool empty() const { return root_.isEmpty(); }
  // The group all triangles below a node's child k belong to, or -1 if they are mixed; the root's.
  std::int32_t childGroup(std::uint32_t node, int k) const {
    return child_group_[node * kWidth + k];
  }
  std::int32_t rootGroup() const { return root_group_; }
  // Triangles below a node's child k, and below the root.
  std::uint32_t childTriangles(std::uint32_t node, int k) const {
    return child_triangles_[node * kWidth + k];
  }
  std::uint32_t rootTriangles() const { return root_triangles_; }
  // True if some of the group's triangles share a leaf with another group's (only where the binary
  // BVH's depth limit stopped it from separating groups).
  bool groupInMixedLeaf(std::int32_t group) const {
    return group >= 0 && static_cast<std::size_t>(group) < group_in_mixed_leaf_.size() &&
           group_in_mixed_leaf_[group];
  }

 private:
  class Builder;  // the collapse of the binary BVH (wide_bvh.cpp)

  const Bvh* bvh_ = nullptr;
  std::vector<Node> nodes_;
  Ref root_{kEmpty, 0};
  std::vector<std::int32_t> child_group_;
  std::vector<std::uint32_t> child_triangles_;
  std::vector<char> group_in_mixed_leaf_;
  std::int32_t root_group_ = -1;
  std::uint32_t root_triangles_ = 0;
};

// A ray prepared for the wide BVH's box tests (the origin rounded both ways, the reciprocal
// direction) together with the exact triangle test. Every test of one ray against one mesh goes
// through the same PreparedRay, whether it is reached by closestHit or by the caster's window walk
// (body_traversal.h), so that a ray exactly on a shared edge is decided the same way everywhere.
template <TriangleMethod M>
class WideRay {
 public:
  // bounds: the box of everything the ray will be tested against (a mesh's), for the reach.
  WideRay(const Ray& ray, bool cull_backfaces, const Aabb& bounds);

  const PreparedRay<double, M>& prepared() const { return prepared_; }

  // Nearest hit with t in [ray.tmin, *tmax] in the subtree `start` whose box is start_box (float
  // corners lo[3], hi[3], rounded outward), skipping triangles that do not improve *best: a hit
  // improves it if it is nearer, or as near with a smaller triangle index (so the result does not
  // depend on the order the tree is walked in). Shrinks *tmax to each improving hit. Returns true
  // if *best changed. The ray's reach (see BvhT::traverse) is taken from the bounds the ray was
  // made with.
  bool closestHit(const WideBvh& bvh, WideBvh::Ref start, const float* start_lo,
                  const float* start_hi, double* tmax, std::optional<MeshHit>* best) const;

 private:
  PreparedRay<double, M> prepared_;
  double tmin_;
  double reach_;  // the farthest a box coordinate is from the origin, in units of t
  // Per axis, the slab plane the ray meets first (near) and last (far), chosen by the sign of the
  // direction: byte offsets into a Node's lo/hi arrays, and the origin rounded the way that moves
  // each plane outward (the near plane nearer, the far plane farther).
  std::uint32_t near_offset_[3], far_offset_[3];
  float origin_near_[3], origin_far_[3], inv_dir_[3];
};

}  // namespace core
}  // namespace laser_raycast
