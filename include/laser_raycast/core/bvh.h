// Bounding volume hierarchy over a triangle mesh: binned SAH build, conservative slab traversal,
// closest hit (by shrinking tmax) and any hit. Brute force over the same triangles is the test
// oracle.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "laser_raycast/core/aabb.h"
#include "laser_raycast/core/triangle.h"

namespace laser_raycast {
namespace core {

using TriangleIndices = std::array<std::uint32_t, 3>;

struct BvhConfig {
  int max_leaf_size = 8;        // a node with more triangles is always split
  int bins = 16;                // SAH candidate planes per axis, minus one
  double traversal_cost = 1.0;  // cost of visiting a node, in units of one triangle test
  int max_depth = 60;           // deeper nodes become leaves; bounds the traversal stack (64)

  // Throws std::invalid_argument naming the field and its value.
  void validate() const;
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
  struct Node {
    AabbT<T> bounds;
    std::uint32_t
        first;  // inner node: index of the left child (the right one follows); leaf: first slot
    std::uint32_t count;  // number of triangles in a leaf; 0 for an inner node
    bool isLeaf() const { return count > 0; }
  };

  BvhT() = default;

  // Builds over the non-degenerate triangles (degenerate ones can never be hit and are left out).
  // The vertices are double; a float BVH stores them rounded to float. Indices must be in range
  // (Mesh checks).
  static BvhT build(const std::vector<Eigen::Vector3d>& vertices,
                    const std::vector<TriangleIndices>& triangles, const BvhConfig& config = {});

  const std::vector<Node>& nodes() const { return nodes_; }
  // Triangle slots in leaf order: the original triangle index, and its vertices copied for
  // locality.
  const std::vector<std::uint32_t>& triangleIds() const { return triangle_ids_; }
  const std::vector<std::array<Vec3<T>, 3>>& triangleVertices() const { return vertices_; }
  AabbT<T> bounds() const { return nodes_.empty() ? AabbT<T>{} : nodes_[0].bounds; }
  bool empty() const { return nodes_.empty(); }
  int depth() const { return depth_; }

  // Nearest hit with t in [ray.tmin, ray.tmax], by method M.
  template <TriangleMethod M>
  std::optional<MeshHitT<T>> closestHit(const RayT<T>& ray, bool cull_backfaces = false) const;

  // True if any triangle is hit with t in [ray.tmin, ray.tmax]; stops at the first.
  template <TriangleMethod M>
  bool anyHit(const RayT<T>& ray, bool cull_backfaces = false) const;

  // Depth-first walk over the nodes whose box satisfies descend(bounds); calls leaf(slot) for each
  // triangle slot of every such leaf. Used by queries that are not rays (the planar fan slices
  // meshes with it).
  template <class Descend, class Leaf>
  void visit(Descend&& descend, Leaf&& leaf) const;

 private:
  template <TriangleMethod M, bool kAnyHit>
  std::optional<MeshHitT<T>> traverse(const RayT<T>& ray, bool cull_backfaces) const;

  std::vector<Node> nodes_;
  std::vector<std::uint32_t> triangle_ids_;
  std::vector<std::array<Vec3<T>, 3>> vertices_;
  int depth_ = 0;
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
  std::optional<MeshHitT<T>> best;
  if (nodes_.empty()) return best;
  const PreparedRay<T, M> prepared(ray, cull_backfaces);
  // Boxes are culled against [tmin, tmax] widened by 64 ulps of |t| plus the ray's reach (the
  // farthest root-box coordinate, in units of t); the triangle tests still use the exact interval.
  // A triangle's t is rounded differently from its box's entry and exit, with an error that scales
  // with the vertices' distance (pbrt-v4 bounds the watertight test's by a few tens of ulps of it),
  // and where a hit lies in a box face (axis-aligned walls, flat leaves) nothing else separates the
  // two: unwidened, a hit at exactly tmax or tmin, or the nearer of two hits ulps apart in
  // different leaves, was lost.
  constexpr T kWiden = 64 * std::numeric_limits<T>::epsilon();
  const AabbT<T>& root = nodes_[0].bounds;
  const T reach =
      (root.lo - ray.origin).cwiseAbs().cwiseMax((root.hi - ray.origin).cwiseAbs()).maxCoeff() /
      ray.dir.cwiseAbs().maxCoeff();
  SlabRay<T> slab(ray);
  slab.tmin = ray.tmin - (std::abs(ray.tmin) + reach) * kWiden;
  T tmax = ray.tmax;
  T cull_tmax = tmax + (std::abs(tmax) + reach) * kWiden;
  T t_root;
  if (!slabTest(slab, root, cull_tmax, &t_root)) return best;

  // Each entry remembers its box's entry distance, so a box found farther than a later hit is
  // skipped.
  struct Entry {
    std::uint32_t node;
    T t_entry;
  };
  Entry stack[64];
  int top = 0;
  stack[top++] = Entry{0, t_root};
  while (top > 0) {
    const Entry entry = stack[--top];
    if (entry.t_entry > cull_tmax) continue;
    const Node& node = nodes_[entry.node];
    if (node.isLeaf()) {
      for (std::uint32_t slot = node.first; slot < node.first + node.count; ++slot) {
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
    const std::uint32_t left = node.first, right = node.first + 1;
    T t_left, t_right;
    const bool hit_left = slabTest(slab, nodes_[left].bounds, cull_tmax, &t_left);
    const bool hit_right = slabTest(slab, nodes_[right].bounds, cull_tmax, &t_right);
    if (hit_left && hit_right) {
      if (t_left <= t_right) {
        stack[top++] = Entry{right, t_right};
        stack[top++] = Entry{left, t_left};
      } else {
        stack[top++] = Entry{left, t_left};
        stack[top++] = Entry{right, t_right};
      }
    } else if (hit_left) {
      stack[top++] = Entry{left, t_left};
    } else if (hit_right) {
      stack[top++] = Entry{right, t_right};
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
  if (nodes_.empty()) return;
  std::uint32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    if (!descend(node.bounds)) continue;
    if (node.isLeaf()) {
      for (std::uint32_t slot = node.first; slot < node.first + node.count; ++slot) leaf(slot);
    } else {
      stack[top++] = node.first + 1;
      stack[top++] = node.first;
    }
  }
}

}  // namespace core
}  // namespace laser_raycast
