// The binned SAH builder behind BvhT: it orders boxes (a mesh's triangles, or any boxes) into a
// binary tree whose boxes are rounded outward to float. BvhT turns its tree into the one it stores.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include <emmintrin.h>

#include "laser_raycast/core/aabb.h"
#include "laser_raycast/core/bvh_config.h"
#include "util/float_rounding.h"

namespace laser_raycast {
namespace core {

// A triangle's (or box's) bounds as the tree stores them, rounded outward to float (lanes x, y, z;
// the fourth is 0). Rounding outward is monotonic, so the float box of a node's triangles is the
// rounding of its exact box: the tree's boxes are the same as from exact bounds rounded at the end,
// and the build works on 16 bytes a corner instead of 48.
struct BuildBox {
  __m128 lo = _mm_set1_ps(std::numeric_limits<float>::infinity());
  __m128 hi = _mm_set1_ps(-std::numeric_limits<float>::infinity());

  static BuildBox of(const Aabb& b) {
    BuildBox box;
    box.lo = _mm_setr_ps(floatBelow(b.lo.x()), floatBelow(b.lo.y()), floatBelow(b.lo.z()), 0.0f);
    box.hi = _mm_setr_ps(floatAbove(b.hi.x()), floatAbove(b.hi.y()), floatAbove(b.hi.z()), 0.0f);
    return box;
  }
  void grow(const BuildBox& b) {
    lo = _mm_min_ps(lo, b.lo);
    hi = _mm_max_ps(hi, b.hi);
  }
  void grow(__m128 p) {
    lo = _mm_min_ps(lo, p);
    hi = _mm_max_ps(hi, p);
  }
  // Twice the centre (lo + hi): what triangles are binned by.
  __m128 twiceCenter() const { return _mm_add_ps(lo, hi); }
  float lower(int axis) const { return lane(lo, axis); }
  float upper(int axis) const { return lane(hi, axis); }
  // Half the surface area of a box that is not empty, in float (infinite beyond the floats).
  float halfArea() const {
    const __m128 e = _mm_sub_ps(hi, lo);  // 0 in the fourth lane
    const __m128 p = _mm_mul_ps(e, _mm_shuffle_ps(e, e, _MM_SHUFFLE(3, 0, 2, 1)));
    // x y + y z + z x, the fourth lane's 0 * 0 added as well.
    const __m128 s = _mm_add_ps(p, _mm_movehl_ps(p, p));
    return _mm_cvtss_f32(_mm_add_ss(s, _mm_shuffle_ps(s, s, _MM_SHUFFLE(1, 1, 1, 1))));
  }
  static float lane(__m128 v, int axis) {
    alignas(16) float f[4];
    _mm_store_ps(f, v);
    return f[axis];
  }
};

struct BuildNode {
  BuildBox bounds;
  std::uint32_t first = 0;  // inner: left child; leaf: first slot
  std::uint32_t count = 0;  // leaf: triangle count
};

// A built tree: nodes[0] is the root; an inner node's children are nodes[first] and
// nodes[first + 1]. order[slot] is the index of the box in leaf slot `slot`.
struct BuiltTree {
  std::vector<BuildNode> nodes;
  std::vector<std::uint32_t> order;
  int depth = 0;
};

// The tree over boxes (none empty). groups: empty, or one per box; a group is never split between
// subtrees while a node holds more than one. The same tree for any config.threads.
BuiltTree buildTree(std::vector<BuildBox> boxes, const BvhConfig& config,
                    std::vector<std::uint32_t> groups);

}  // namespace core
}  // namespace laser_raycast
