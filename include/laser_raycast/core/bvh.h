// Bounding volume hierarchy over a triangle mesh: binned SAH build, conservative slab traversal,
// closest hit (by shrinking tmax) and any hit. Brute force over the same triangles is the test
// oracle.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <vector>

#include "laser_raycast/core/aabb.h"
#include "laser_raycast/core/bvh_config.h"
#include "laser_raycast/core/triangle.h"

namespace laser_raycast {
namespace core {

using TriangleIndices = std::array<std::uint32_t, 3>;

// x rounded to float, kept a float: GCC 12's SLP vectorizer folds a double taken to float and back
// into the double itself (at -O2, a vectorised (double)(float)x gave x unrounded); the empty asm
// hides the float's value from it.
inline float keptFloat(double x) {
  float f = static_cast<float>(x);
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
  asm("" : "+x"(f));
#endif
  return f;
}

// Whether a per-axis scale can be one that float coordinates were read with: positive and finite.
template <typename T>
inline bool packableScale(const Vec3<T>& scale) {
  return (scale.array() > 0).all() && scale.allFinite();
}

// Whether coordinate c is, bit for bit, T(float(c / s)) * s (s: its axis' scale, positive and
// finite): a mesh file's float coordinate scaled as the URDF says. If so, *f is that float, from
// which T(*f) * s gives c back exactly.
template <typename T>
inline bool floatTimesScale(T c, T s, float* f) {
  *f = keptFloat(c / s);
  const T back = static_cast<T>(*f) * s;
  return std::memcmp(&back, &c, sizeof(T)) == 0;
}

// The vertices of a BVH's triangle slots, copied in slot order so that a leaf's triangles are the
// next bytes. For T = double they can be kept in float (36 bytes a slot instead of 72): pack(scale)
// does so when every coordinate is exactly a float times that axis' scale (a mesh file's float
// coordinates, scaled as the URDF says), and operator[] then gives back those same doubles, bit for
// bit: what reads the slots cannot tell the difference.
template <typename T>
class SlotVertices {
 public:
  using Triangle = std::array<Vec3<T>, 3>;

  std::size_t size() const { return packed_.empty() ? full_.size() : packed_.size(); }
  bool empty() const { return size() == 0; }
  // Whether the slots are kept in float.
  bool packed() const { return !packed_.empty(); }
  // Bytes the slots take (what the vectors hold).
  std::size_t bytes() const {
    return full_.capacity() * sizeof(Triangle) + packed_.capacity() * sizeof(packed_[0]);
  }

  LASER_RAYCAST_HOT_INLINE Triangle operator[](std::uint32_t slot) const {
    if (packed_.empty()) return full_[slot];
    const float* f = packed_[slot].data();
    Triangle tri;
    for (int k = 0; k < 3; ++k) {
      for (int a = 0; a < 3; ++a) tri[k][a] = static_cast<T>(f[3 * k + a]) * scale_[a];
    }
    return tri;
  }

  // Asks the cache for slots [slot, slot + count) ahead of their use (a leaf's, before it is
  // walked): at most kPrefetchLines cache lines from the first.
  void prefetch(std::uint32_t slot, std::uint32_t count) const {
    constexpr std::size_t kLine = 64, kPrefetchLines = 8;
    const char* begin = packed_.empty() ? reinterpret_cast<const char*>(full_.data() + slot)
                                        : reinterpret_cast<const char*>(packed_.data() + slot);
    const std::size_t bytes = count * (packed_.empty() ? sizeof(Triangle) : sizeof(packed_[0]));
    const std::size_t lines = std::min(kPrefetchLines, (bytes + kLine - 1) / kLine);
    for (std::size_t k = 0; k < lines; ++k) __builtin_prefetch(begin + k * kLine);
  }

  void reserve(std::size_t n) { full_.reserve(n); }
  void push_back(const Triangle& tri) { full_.push_back(tri); }

  // Keeps the slots in float if every coordinate c on axis a is, bit for bit, T(float(c / s_a)) *
  // s_a (scale: s, positive and finite); returns whether they are. A no-op for T = float.
  bool pack(const Vec3<T>& scale) {
    if (sizeof(T) == sizeof(float) || full_.empty() || packed()) return packed();
    if (!packableScale(scale)) return false;
    std::vector<std::array<float, 9>> packed(full_.size());
    for (std::size_t slot = 0; slot < full_.size(); ++slot) {
      for (int k = 0; k < 3; ++k) {
        for (int a = 0; a < 3; ++a) {
          if (!floatTimesScale(full_[slot][k][a], scale[a], &packed[slot][3 * k + a])) return false;
        }
      }
    }
    packed_ = std::move(packed);
    scale_ = scale;
    std::vector<Triangle>().swap(full_);
    return true;
  }

 private:
  std::vector<Triangle> full_;
  std::vector<std::array<float, 9>> packed_;
  Vec3<T> scale_ = Vec3<T>::Ones();
};

template <typename T>
struct MeshHitT {
  T t;
  T u, v;                  // barycentric weights of the triangle's second and third vertex
  std::uint32_t triangle;  // index into the mesh's triangle list
};
using MeshHit = MeshHitT<double>;

template <typename T>
class BvhT {
 public:
  // A subtree: an inner node (count == 0, index into nodes()) or a leaf (count triangle slots from
  // index on).
  // Trivially constructible, so that a traversal's stack of them costs nothing to set up.
  struct Child {
    std::uint32_t index;
    std::uint32_t count;
    bool isLeaf() const { return count > 0; }
  };

  // An inner node holds its two children's boxes, so that deciding where to go next reads one cache
  // line (traversal is memory-bound). The boxes are float, rounded outward: they contain the exact
  // boxes, so a slab test in double against them is as conservative as against the exact ones.
  struct alignas(64) Node {
    float lo[2][3];
    float hi[2][3];
    Child child[2];
    AabbT<T> box(int k) const {
      AabbT<T> b;
      for (int a = 0; a < 3; ++a) {
        b.lo[a] = static_cast<T>(lo[k][a]);
        b.hi[a] = static_cast<T>(hi[k][a]);
      }
      return b;
    }
  };

  BvhT() = default;

  // Builds over the non-degenerate triangles (degenerate ones can never be hit and are left out).
  // The vertices are double; a float BVH stores them rounded to float. Indices must be in range
  // (Mesh checks). With groups (one id per triangle, e.g. its connected component), each group
  // fills whole subtrees: a node holding several groups never splits one of them, so every leaf
  // holds one group (unless max_depth stops the split first).
  static BvhT build(const std::vector<Eigen::Vector3d>& vertices,
                    const std::vector<TriangleIndices>& triangles, const BvhConfig& config = {},
                    const std::vector<std::uint32_t>& groups = {});

  // A tree over boxes instead of triangles (the bodies of a frame, the segments of a slice): the
  // same build; triangleIds() holds the boxes' indices in leaf order and triangleVertices() is
  // empty, so only visit() and the node arrays apply. Empty boxes are left out.
  static BvhT buildOverBoxes(const std::vector<Aabb>& boxes, const BvhConfig& config = {});

  // The inner nodes, depth first (a parent before its children); the tree starts at root().
  const std::vector<Node>& nodes() const { return nodes_; }
  Child root() const { return root_; }
  // Triangle slots in leaf order: the original triangle index, and its vertices copied for
  // locality (in float where packSlots could).
  const std::vector<std::uint32_t>& triangleIds() const { return triangle_ids_; }
  const SlotVertices<T>& triangleVertices() const { return vertices_; }
  // Keeps the slots' vertices in float if that loses nothing (SlotVertices::pack); returns whether.
  bool packSlots(const Vec3<T>& scale) { return vertices_.pack(scale); }
  // The exact bounds of every stored vertex.
  const AabbT<T>& bounds() const { return bounds_; }
  bool empty() const { return triangle_ids_.empty(); }
  int depth() const { return depth_; }

  // Nearest hit with t in [ray.tmin, ray.tmax], by method M.
  template <TriangleMethod M>
  std::optional<MeshHitT<T>> closestHit(const RayT<T>& ray, bool cull_backfaces = false) const;

  // True if any triangle is hit with t in [ray.tmin, ray.tmax]; stops at the first.
  template <TriangleMethod M>
  bool anyHit(const RayT<T>& ray, bool cull_backfaces = false) const;

  // Depth-first walk over the subtrees whose box satisfies descend(box); calls leaf(slot) for each
  // triangle slot of every such leaf. Used by queries that are not rays.
  template <class Descend, class Leaf>
  void visit(Descend&& descend, Leaf&& leaf) const;

  // Frees the tree's nodes, keeping the triangle slots, their ids and the bounds: for an owner that
  // walks the slots through a tree of its own (a Mesh keeps only its wide BVH, built from this
  // tree). After it, hasTree() is false, and closestHit, anyHit and visit throw std::logic_error.
  void releaseTree();
  bool hasTree() const { return !tree_released_; }
  // Bytes the nodes and slots take (what the vectors hold).
  std::size_t bytes() const {
    return nodes_.capacity() * sizeof(Node) + triangle_ids_.capacity() * sizeof(std::uint32_t) +
           vertices_.bytes();
  }

 private:
  template <TriangleMethod M, bool kAnyHit>
  std::optional<MeshHitT<T>> traverse(const RayT<T>& ray, bool cull_backfaces) const;

 public:
  // The nodes, root and bounds a build produces (bvh.cpp).
  struct Tree {
    std::vector<Node> nodes;
    Child root{0, 0};
    AabbT<T> bounds;
  };

 private:
  void adoptTree(Tree tree, int depth);

  std::vector<Node> nodes_;
  Child root_{0, 0};
  AabbT<T> bounds_;
  std::vector<std::uint32_t> triangle_ids_;
  SlotVertices<T> vertices_;
  int depth_ = 0;
  bool tree_released_ = false;

  void requireTree() const;
};

using Bvh = BvhT<double>;
using BvhF = BvhT<float>;

// The oracle: every non-degenerate triangle tested, nearest kept.
template <typename T>
std::optional<MeshHitT<T>> bruteForceClosestHit(TriangleMethod method,
                                                const std::vector<Eigen::Vector3d>& vertices,
                                                const std::vector<TriangleIndices>& triangles,
                                                const RayT<T>& ray, bool cull_backfaces = false);

// ---------------------------------------------------------------------------------------------------
// Traversal (in the header so that each method's test is inlined into the loop).

template <typename T>
template <TriangleMethod M, bool kAnyHit>
std::optional<MeshHitT<T>> BvhT<T>::traverse(const RayT<T>& ray, bool cull_backfaces) const {
  requireTree();
  std::optional<MeshHitT<T>> best;
  if (empty()) return best;
  const PreparedRay<T, M> prepared(ray, cull_backfaces);
  // Boxes are culled against [tmin, tmax] widened by 64 ulps of |t| plus the ray's reach (the
  // farthest root-box coordinate, in units of t); the triangle tests still use the exact interval.
  // A triangle's t is rounded differently from its box's entry and exit, with an error that scales
  // with the vertices' distance (pbrt-v4 bounds the watertight test's by a few tens of ulps of it),
  // and where a hit lies in a box face (axis-aligned walls, flat leaves) nothing else separates the
  // two: unwidened, a hit at exactly tmax or tmin, or the nearer of two hits ulps apart in
  // different leaves, was lost.
  constexpr T kWiden = 64 * std::numeric_limits<T>::epsilon();
  const T reach = (bounds_.lo - ray.origin)
                      .cwiseAbs()
                      .cwiseMax((bounds_.hi - ray.origin).cwiseAbs())
                      .maxCoeff() /
                  ray.dir.cwiseAbs().maxCoeff();
  SlabRay<T> slab(ray);
  slab.tmin = ray.tmin - (std::abs(ray.tmin) + reach) * kWiden;
  T tmax = ray.tmax;
  T cull_tmax = tmax + (std::abs(tmax) + reach) * kWiden;
  T t_root;
  if (!slabTest(slab, bounds_, cull_tmax, &t_root)) return best;

  // Each entry remembers its box's entry distance, so a box found farther than a later hit is
  // skipped.
  struct Entry {
    Child child;
    T t_entry;
  };
  Entry stack[64];
  int top = 0;
  stack[top++] = Entry{root_, t_root};
  while (top > 0) {
    const Entry entry = stack[--top];
    if (entry.t_entry > cull_tmax) continue;
    if (entry.child.isLeaf()) {
      const std::uint32_t end = entry.child.index + entry.child.count;
      for (std::uint32_t slot = entry.child.index; slot < end; ++slot) {
        const auto& tri = vertices_[slot];
        const auto hit = prepared.intersect(tri[0], tri[1], tri[2], tmax);
        if (hit) {
          best = MeshHitT<T>{hit->t, hit->u, hit->v, triangle_ids_[slot]};
          if (kAnyHit) return best;
          tmax = hit->t;
          cull_tmax = tmax + (std::abs(tmax) + reach) * kWiden;
        }
      }
      continue;
    }
    // Visit the nearer child first; push the farther one underneath it.
    const Node& node = nodes_[entry.child.index];
    T t0, t1;
    bool hit0, hit1;
    slabTestPair(slab, node.lo, node.hi, cull_tmax, &t0, &t1, &hit0, &hit1);
    if (hit0 && hit1) {
      if (t0 <= t1) {
        stack[top++] = Entry{node.child[1], t1};
        stack[top++] = Entry{node.child[0], t0};
      } else {
        stack[top++] = Entry{node.child[0], t0};
        stack[top++] = Entry{node.child[1], t1};
      }
    } else if (hit0) {
      stack[top++] = Entry{node.child[0], t0};
    } else if (hit1) {
      stack[top++] = Entry{node.child[1], t1};
    }
  }
  return best;
}

template <typename T>
template <TriangleMethod M>
std::optional<MeshHitT<T>> BvhT<T>::closestHit(const RayT<T>& ray, bool cull_backfaces) const {
  return traverse<M, false>(ray, cull_backfaces);
}

template <typename T>
template <TriangleMethod M>
bool BvhT<T>::anyHit(const RayT<T>& ray, bool cull_backfaces) const {
  return traverse<M, true>(ray, cull_backfaces).has_value();
}

template <typename T>
template <class Descend, class Leaf>
void BvhT<T>::visit(Descend&& descend, Leaf&& leaf) const {
  requireTree();
  if (empty() || !descend(bounds_)) return;
  Child stack[64];
  int top = 0;
  stack[top++] = root_;
  while (top > 0) {
    const Child child = stack[--top];
    if (child.isLeaf()) {
      for (std::uint32_t slot = child.index; slot < child.index + child.count; ++slot) leaf(slot);
      continue;
    }
    const Node& node = nodes_[child.index];
    for (const int k : {1, 0}) {  // the first child on top
      if (descend(node.box(k))) stack[top++] = node.child[k];
    }
  }
}

}  // namespace core
}  // namespace laser_raycast
