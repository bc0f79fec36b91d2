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
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <vector>

#include "laser_raycast/core/bvh.h"
#include "util/float_rounding.h"

namespace laser_raycast {
namespace core {

// How far apart a point can be in the frame of a tree's boxes and in the frame where the walk tests
// what the boxes hold: a traced beam's boxes are in the body's (or the plane's) coordinates, but
// its triangles are tested moved into the sensor frame, and its direction is rotated into the
// boxes' frame, each a few roundings at the magnitude of the coordinates (bound: the largest box
// coordinate) and of the sensor's position there (origin). A walk's rays widen every box by this
// much, so that the box test never drops a triangle the exact test in the other frame hits (a beam
// within an ulp of a row of vertices: the two frames can put it on either side).
inline double frameSlack(double bound, double origin) {
  return 64 * std::numeric_limits<double>::epsilon() * (bound + origin);
}

class WideBvh {
 public:
  static constexpr int kWidth = 4;
  static constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();
  // Binary subtrees of one group with at most this many triangles become one leaf.
  static constexpr std::uint32_t kMaxLeafTriangles = 2;

  // A subtree: an inner node (index into nodes(); count: kInner | the triangles below it), a leaf
  // (count triangle slots of the binary BVH from index on, 1 to kInner - 1), or nothing (index ==
  // kEmpty, count == 0). An inner node's triangle count rides in the bits a leaf's count uses, so
  // that a node holds it at no cost (the walks' heuristics read it); it saturates at kInner - 1.
  // Trivially constructible, so that a traversal's stack of them costs nothing to set up.
  static constexpr std::uint32_t kInner = std::uint32_t{1} << 31;
  struct Ref {
    std::uint32_t index;
    std::uint32_t count;
    // One signed compare, as cheap as count > 0: an inner node's count is negative as int32.
    bool isLeaf() const { return static_cast<std::int32_t>(count) > 0; }
    bool isEmpty() const { return index == kEmpty; }
    // The triangles below: a leaf's count, or an inner node's (saturated) count.
    std::uint32_t triangles() const { return count & ~kInner; }
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
      const __m128i empty = _mm_cmpeq_epi32(_mm_load_si128(reinterpret_cast<const __m128i*>(index)),
                                            _mm_set1_epi32(-1));
      return ~_mm_movemask_ps(_mm_castsi128_ps(empty)) & 0xF;
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
  // Triangles below a node's child k, and below the root (an inner node's saturate at kInner - 1).
  std::uint32_t childTriangles(std::uint32_t node, int k) const {
    return nodes_[node].child(k).triangles();
  }
  std::uint32_t rootTriangles() const { return root_.triangles(); }
  // Bytes the nodes take (not the binary BVH's slots).
  std::size_t bytes() const { return nodes_.capacity() * sizeof(Node); }

  // Depth-first walk over the subtrees whose box satisfies descend(box) (the root's: the binary
  // BVH's bounds; below it, the nodes' float boxes, which contain the exact ones); calls leaf(slot)
  // for each triangle slot of every such leaf. For queries that are not rays (a plane's slice).
  template <class Descend, class Leaf>
  void visit(Descend&& descend, Leaf&& leaf) const {
    if (empty() || !descend(bvh_->bounds())) return;
    Ref stack[64 * (kWidth - 1) + 1];
    int top = 0;
    stack[top++] = root_;
    while (top > 0) {
      const Ref ref = stack[--top];
      if (ref.isLeaf()) {
        for (std::uint32_t slot = ref.index; slot < ref.index + ref.count; ++slot) leaf(slot);
        continue;
      }
      const Node& node = nodes_[ref.index];
      for (int k = kWidth - 1; k >= 0; --k) {  // the first child on top
        if (node.index[k] == kEmpty) continue;
        Aabb box;
        for (int a = 0; a < 3; ++a) {
          box.lo[a] = node.lo[a][k];
          box.hi[a] = node.hi[a][k];
        }
        if (descend(box)) stack[top++] = node.child(k);
      }
    }
  }

 private:
  class Builder;  // the collapse of the binary BVH (wide_bvh.cpp)

  const Bvh* bvh_ = nullptr;
  std::vector<Node> nodes_;
  Ref root_{kEmpty, 0};
};

// A ray prepared for conservative box tests against a wide node's four children in its first kAxes
// axes: the origin rounded to float both ways, the reciprocal direction, and the ray's reach (how
// far a box coordinate can be from the origin, in units of t), which scales the widening of the
// cull limit. Conservative: a box the exact ray enters is never skipped. The boxes contain the
// exact ones; each slab plane is measured from the origin rounded the way that moves it towards the
// ray (the near plane can only come nearer, the far plane only farther); the remaining rounding of
// the subtraction, the reciprocal and the product is covered by widening the exit by 1 + 2 gamma(3)
// (Ize, "Robust BVH Ray Traversal", JCGT 2013).
template <int kAxes>
class WideSlabRay {
 public:
  using Vector = Eigen::Matrix<double, kAxes, 1>;
  // What the rays of one walk share: they start at one point (rounded once each way, after moving
  // it by frameSlack(), which widens every box by that much), and a bound on how far a box
  // coordinate of the tree is from it, in units of t of a unit direction (for the cull limit's
  // widening). bounds: the tree's box (its first kAxes coordinates are the tree's). widen: the rays
  // start anywhere within that distance of origin (a rotating sweep's block, each column from its
  // own pose): the interval the box tests take the origin in is that much wider each way.
  struct Origin {
    float up[kAxes], down[kAxes];
    double reach;
    float tnear0;  // the rays' tmin, widened as the cull limit is
    Origin(const Vector& origin, const Aabb& bounds, double tmin, double widen = 0) {
      const Vector lo = bounds.lo.template head<kAxes>(), hi = bounds.hi.template head<kAxes>();
      const double slack = frameSlack(lo.cwiseAbs().cwiseMax(hi.cwiseAbs()).maxCoeff(),
                                      origin.cwiseAbs().maxCoeff()) +
                           widen;
      for (int k = 0; k < kAxes; ++k) {
        up[k] = floatAbove(origin[k] + slack);
        down[k] = floatBelow(origin[k] - slack);
      }
      // A unit direction's largest component is at least 1/sqrt(kAxes) >= 1/2: twice the largest
      // coordinate distance bounds the reach of every direction.
      reach = 2 * ((lo - origin).cwiseAbs().cwiseMax((hi - origin).cwiseAbs()).maxCoeff() + widen);
      tnear0 = floatBelow(tmin - (std::abs(tmin) + reach) * kWiden);
    }
  };

  WideSlabRay() = default;
  // A unit direction from a walk's origin.
  WideSlabRay(const Origin& origin, const Vector& dir) {
    reach_ = origin.reach;
    tnear0_ = origin.tnear0;
    for (int k = 0; k < kAxes; ++k) setAxis(k, dir[k], origin.up[k], origin.down[k]);
  }

  // The box cull limit for a far limit tmax: widened as BvhT::traverse does (a hit's t and its
  // box's entry and exit round differently), then taken to float no nearer than that: widened
  // once more by 2^-23 relative (twice a float's relative rounding) and 2^-140 (above the
  // subnormals' rounding of 2^-150) and rounded to nearest, which cannot land below it. Cheaper
  // than floatAbove's bit step.
  LASER_RAYCAST_HOT_INLINE float cullLimit(double tmax) const {
    const double widened = tmax + (std::abs(tmax) + reach_) * kWiden;
    return static_cast<float>(widened + std::abs(widened) * 0x1p-23 + 0x1p-140);
  }
  // The children of node that the ray enters at or before `cull` (bit k for child k), and where
  // (t_entry[k]; meaningful for the children entered).
  LASER_RAYCAST_HOT_INLINE int enter(const WideBvh::Node& node, float cull,
                                     float t_entry[4]) const {
    const char* base = reinterpret_cast<const char*>(&node);
    __m128 tnear = _mm_set1_ps(tnear0_);
    __m128 tfar = _mm_set1_ps(std::numeric_limits<float>::infinity());
    for (int k = 0; k < kAxes; ++k) {
      const __m128 near_plane = _mm_load_ps(reinterpret_cast<const float*>(base + near_offset_[k]));
      const __m128 far_plane = _mm_load_ps(reinterpret_cast<const float*>(base + far_offset_[k]));
      const __m128 inv = _mm_set1_ps(inv_dir_[k]);
      // maxps/minps return their second operand when either is NaN (a ray lying in a slab plane):
      // it never narrows the interval, as in slabTest.
      tnear =
          _mm_max_ps(_mm_mul_ps(_mm_sub_ps(near_plane, _mm_set1_ps(origin_near_[k])), inv), tnear);
      tfar = _mm_min_ps(_mm_mul_ps(_mm_sub_ps(far_plane, _mm_set1_ps(origin_far_[k])), inv), tfar);
    }
    tfar = _mm_min_ps(_mm_mul_ps(tfar, _mm_set1_ps(kWidenExit)), _mm_set1_ps(cull));
    _mm_storeu_ps(t_entry, tnear);
    return _mm_movemask_ps(_mm_cmple_ps(tnear, tfar)) & node.presentMask();
  }

 protected:
  static constexpr double kWiden = 64 * std::numeric_limits<double>::epsilon();
  static constexpr float kWidenExit = 1 + 2 * roundingGamma<float>(3);

  // Axis k from the direction's component and the origin's coordinate rounded up and down.
  void setAxis(int k, double dir, float origin_up, float origin_down) {
    constexpr std::uint32_t kLo = offsetof(WideBvh::Node, lo), kHi = offsetof(WideBvh::Node, hi);
    // Adding +0 turns -0 into +0, so a zero component gives +inf and counts as positive (see
    // SlabRay): a ray lying in a slab plane then gives NaN there, which never narrows the interval.
    const double d = dir + 0.0;
    // Picked by indexing with the sign, not by branches (the signs of a fan's beams alternate).
    const int positive = !(d < 0);
    const auto axis = static_cast<std::uint32_t>(k * WideBvh::kWidth * sizeof(float));
    const std::uint32_t planes[2] = {kHi + axis, kLo + axis};
    near_offset_[k] = planes[positive];
    far_offset_[k] = planes[1 - positive];
    // The near plane minus the origin must not come out larger than exact, nor the far one
    // smaller: for a positive direction that is the origin rounded up for the near plane (lo) and
    // down for the far plane (hi); for a negative one the other way round.
    const float origins[2] = {origin_down, origin_up};
    origin_near_[k] = origins[positive];
    origin_far_[k] = origins[1 - positive];
    inv_dir_[k] = static_cast<float>(1.0 / d);
  }

  double reach_ = 0;
  float tnear0_ = 0;  // the entry limit: tmin, widened like the cull limit
  // Per axis, the slab plane the ray meets first (near) and last (far), chosen by the sign of the
  // direction: byte offsets into a Node's lo/hi arrays, and the origin rounded the way that moves
  // each plane outward.
  std::uint32_t near_offset_[kAxes] = {}, far_offset_[kAxes] = {};
  float origin_near_[kAxes] = {}, origin_far_[kAxes] = {}, inv_dir_[kAxes] = {};
};

// A ray prepared for the wide BVH's box tests in 3D.
class WideBoxRay : public WideSlabRay<3> {
 public:
  WideBoxRay() = default;
  using WideSlabRay<3>::WideSlabRay;  // from a walk's Origin
  // bounds: the box of everything the ray will be tested against (a mesh's), for the reach.
  WideBoxRay(const Ray& ray, const Aabb& bounds);

  // The same test for one box given by its float corners.
  bool enters(const float lo[3], const float hi[3], float cull) const;
};

// Orders a node's children (entries with a `near` distance) farthest first, so that pushed onto a
// stack in this order the nearest is walked next. Insertion sort: a walk has at most a dozen.
template <class Entry>
void sortFarthestFirst(Entry* entries, int n) {
  for (int j = 1; j < n; ++j) {
    const Entry moving = entries[j];
    int i = j;
    for (; i > 0 && entries[i - 1].near < moving.near; --i) entries[i] = entries[i - 1];
    entries[i] = moving;
  }
}

// The same order as indices into near[0, n) (order[0] the farthest), for entries kept field by
// field: sorting whole entries just written reads them back across their fields' stores, which the
// processor cannot forward and waits for.
inline void sortFarthestFirst(const float* near, int* order, int n) {
  for (int j = 0; j < n; ++j) {
    int i = j;
    for (; i > 0 && near[order[i - 1]] < near[j]; --i) order[i] = order[i - 1];
    order[i] = j;
  }
}

// The order a ray visits the children it enters, nearest first, without branches: the children's
// sort keys (t_entry's bits, children not entered after every one entered; the low two bits hold
// the child, so that keys differ) sorted farthest first by a network of five exchanges. Which of
// two boxes is entered first is a coin toss that a branch would mispredict.
LASER_RAYCAST_HOT_INLINE void orderChildren(int mask, const float t_entry[4],
                                            std::uint32_t key[4]) {
  constexpr std::uint32_t kNotEntered = 0xFFFFFFFCu;
  for (int k = 0; k < 4; ++k) {
    std::uint32_t bits;
    std::memcpy(&bits, &t_entry[k], sizeof bits);
    // Positive floats order as their bits; the rest count as 0. Masks, not selects: GCC branches.
    bits &= ~3u & (0u - static_cast<std::uint32_t>(t_entry[k] > 0));
    const std::uint32_t entered = 0u - static_cast<std::uint32_t>((mask >> k) & 1);
    key[k] = (bits & entered) | (kNotEntered & ~entered) | static_cast<std::uint32_t>(k);
  }
  auto exchange = [&](int i, int j) {
    const std::uint32_t a = key[i], b = key[j];
    key[i] = a > b ? a : b;
    key[j] = a > b ? b : a;
  };
  exchange(0, 1);
  exchange(2, 3);
  exchange(0, 2);
  exchange(1, 3);
  exchange(1, 2);
}

// One ray's walk of a subtree, nearest box first, a step at a time (traceWide, traceWidePair): each
// step visits a node or a leaf, calling leaf(slot) for every triangle slot of a leaf the ray enters
// before the cull limit of *tmax. leaf may lower *tmax (an improving hit), which culls the boxes
// beyond. The start's own box is not tested. BoxRay: a WideBoxRay, or a ray with the same two
// members (cullLimit, enter) for other boxes.
template <class BoxRay>
class WideWalk {
 public:
  WideWalk(const WideBvh& bvh, WideBvh::Ref start, const BoxRay& ray, double* tmax)
      : nodes_(bvh.nodes().data()), ray_(ray), tmax_(tmax), current_(start) {
    cull_ = ray.cullLimit(*tmax);
  }

  // One node or leaf; false once the walk is over.
  template <class Leaf>
  LASER_RAYCAST_HOT_INLINE bool step(Leaf&& leaf) {
    if (current_.isLeaf()) {
      const double before = *tmax_;
      for (std::uint32_t slot = current_.index; slot < current_.index + current_.count; ++slot) {
        leaf(slot);
      }
      if (*tmax_ != before) cull_ = ray_.cullLimit(*tmax_);
    } else {
      const WideBvh::Node& node = nodes_[current_.index];
      alignas(16) float t_entry[4];
      const int mask = ray_.enter(node, cull_, t_entry);
      // One child entered (most steps of a beam that goes on into one box): straight into it, with
      // none of the ordering below. The same visit as the ordering's; a branch, but a cheaper one
      // to mispredict than the ordering is to run.
      if (mask && !(mask & (mask - 1))) {
        current_ = node.child(__builtin_ctz(static_cast<unsigned>(mask)));
        return true;
      }
      if (mask) {
        // Go on into the nearest child entered; push the others farthest first, so that the
        // nearest of them comes next. Keys of children not entered sort first and are not kept.
        std::uint32_t key[4];
        orderChildren(mask, t_entry, key);
        for (int j = 0; j < 3; ++j) {
          const int k = static_cast<int>(key[j] & 3);
          stack_[top_] = Entry{node.child(k), t_entry[k]};
          top_ += (mask >> k) & 1;
        }
        current_ = node.child(static_cast<int>(key[3] & 3));
        return true;
      }
    }
    // Next, the nearest pushed child still before the cull limit.
    for (;;) {
      if (top_ == 0) return false;
      const Entry& entry = stack_[--top_];
      if (!(entry.t_entry > cull_)) {
        current_ = entry.ref;
        return true;
      }
    }
  }

 private:
  struct Entry {
    WideBvh::Ref ref;
    float t_entry;
  };
  const WideBvh::Node* nodes_;
  const BoxRay& ray_;
  double* tmax_;
  float cull_;
  WideBvh::Ref current_;
  int top_ = 0;
  // A node pushes at most three children (it goes on into the fourth): three a level, and room
  // for the three unconditional stores of the deepest level.
  Entry stack_[64 * (WideBvh::kWidth - 1) + 1];
};

// Walks the subtree `start` for one ray (WideWalk).
template <class BoxRay, class Leaf>
void traceWide(const WideBvh& bvh, WideBvh::Ref start, const BoxRay& ray, double* tmax,
               Leaf&& leaf) {
  if (start.isEmpty()) return;
  WideWalk<BoxRay> walk(bvh, start, ray, tmax);
  while (walk.step(leaf)) {
  }
}

// Two rays' walks of one subtree, a step of each in turn: each is a chain of dependent loads and
// tests, and side by side the processor overlaps them. The same visits as two traceWide calls.
template <class BoxRay, class LeafA, class LeafB>
void traceWidePair(const WideBvh& bvh, WideBvh::Ref start, const BoxRay& ray_a, double* tmax_a,
                   LeafA&& leaf_a, const BoxRay& ray_b, double* tmax_b, LeafB&& leaf_b) {
  if (start.isEmpty()) return;
  WideWalk<BoxRay> a(bvh, start, ray_a, tmax_a), b(bvh, start, ray_b, tmax_b);
  bool more_a = true, more_b = true;
  while (more_a & more_b) {
    more_a = a.step(leaf_a);
    more_b = b.step(leaf_b);
  }
  while (more_a) more_a = a.step(leaf_a);
  while (more_b) more_b = b.step(leaf_b);
}

}  // namespace core
}  // namespace laser_raycast
