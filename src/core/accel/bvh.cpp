#include "laser_raycast/core/bvh.h"

#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

#include "accel/bvh_builder.h"

namespace laser_raycast {
namespace core {
namespace {

template <typename T>
AabbT<T> castBounds(const Aabb& b) {
  // Rounding to nearest is monotonic, so these are exactly the bounds of the rounded vertices.
  AabbT<T> out;
  out.lo = b.lo.cast<T>();
  out.hi = b.hi.cast<T>();
  return out;
}

// The builder's tree as BvhT stores it: inner nodes depth first, each holding its children's boxes
// (float, rounded outward); the two children of a node get adjacent indices. bounds: the exact
// bounds of every triangle.
template <typename T>
typename BvhT<T>::Tree writeTree(const std::vector<BuildNode>& tree, const Aabb& bounds) {
  using Child = typename BvhT<T>::Child;
  typename BvhT<T>::Tree out;
  out.bounds = castBounds<T>(bounds);
  if (tree[0].count > 0) {
    out.root = Child{tree[0].first, tree[0].count};
    return out;
  }
  out.nodes.reserve(tree.size() / 2);
  out.nodes.emplace_back();
  out.root = Child{0, 0};
  std::vector<std::pair<std::uint32_t, std::uint32_t>> todo{{0, 0}};  // (build node, node)
  while (!todo.empty()) {
    const auto [from, to] = todo.back();
    todo.pop_back();
    for (int k = 0; k < 2; ++k) {
      const std::uint32_t build_child = tree[from].first + k;
      const BuildNode& child = tree[build_child];
      Child ref{child.first, child.count};
      if (child.count == 0) {
        ref.index = static_cast<std::uint32_t>(out.nodes.size());
        out.nodes.emplace_back();
        todo.emplace_back(build_child, ref.index);
      }
      auto& node = out.nodes[to];
      node.child[k] = ref;
      for (int a = 0; a < 3; ++a) {
        node.lo[k][a] = child.bounds.lower(a);
        node.hi[k][a] = child.bounds.upper(a);
      }
    }
  }
  return out;
}

}  // namespace

template <typename T>
void BvhT<T>::adoptTree(Tree tree, int depth) {
  nodes_ = std::move(tree.nodes);
  root_ = tree.root;
  bounds_ = tree.bounds;
  depth_ = depth;
}

template <typename T>
void BvhT<T>::releaseTree() {
  std::vector<Node>().swap(nodes_);
  tree_released_ = true;
}

template <typename T>
void BvhT<T>::requireTree() const {
  if (tree_released_) {
    throw std::logic_error(
        "this BVH's tree was released (a Mesh keeps only its wide BVH): walk it with Mesh::visit");
  }
}


template <typename T>
BvhT<T> BvhT<T>::build(const std::vector<Eigen::Vector3d>& vertices,
                       const std::vector<TriangleIndices>& triangles, const BvhConfig& config,
                       const std::vector<std::uint32_t>& groups) {
  config.validate();
  if (!groups.empty() && groups.size() != triangles.size()) {
    throw std::invalid_argument("BVH build: " + std::to_string(groups.size()) + " groups for " +
                                std::to_string(triangles.size()) + " triangles");
  }
  std::vector<BuildBox> build_tris;
  std::vector<std::uint32_t> kept;  // original index of each build triangle
  Aabb bounds;                      // exactly
  build_tris.reserve(triangles.size());
  kept.reserve(triangles.size());
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    const TriangleIndices& tri = triangles[i];
    // Test degeneracy on the vertices the BVH will store (float rounding can collapse a sliver).
    const Vec3<T> a = vertices[tri[0]].cast<T>(), b = vertices[tri[1]].cast<T>(),
                  c = vertices[tri[2]].cast<T>();
    if (isDegenerateTriangle(a, b, c)) continue;
    Aabb box;
    for (const auto v : tri) box.grow(vertices[v]);
    bounds.grow(box);
    build_tris.push_back(BuildBox::of(box));
    kept.push_back(static_cast<std::uint32_t>(i));
  }
  BvhT<T> bvh;
  if (build_tris.empty()) return bvh;

  std::vector<std::uint32_t> build_groups;
  if (!groups.empty()) {
    build_groups.reserve(kept.size());
    for (const std::uint32_t i : kept) build_groups.push_back(groups[i]);
  }
  const BuiltTree built = buildTree(std::move(build_tris), config, std::move(build_groups));
  bvh.adoptTree(writeTree<T>(built.nodes, bounds), built.depth);
  bvh.triangle_ids_.reserve(kept.size());
  bvh.vertices_.reserve(kept.size());
  for (const std::uint32_t i : built.order) {
    const TriangleIndices& tri = triangles[kept[i]];
    bvh.triangle_ids_.push_back(kept[i]);
    bvh.vertices_.push_back(
        {vertices[tri[0]].cast<T>(), vertices[tri[1]].cast<T>(), vertices[tri[2]].cast<T>()});
  }
  return bvh;
}

template <typename T>
BvhT<T> BvhT<T>::buildOverBoxes(const std::vector<Aabb>& boxes, const BvhConfig& config) {
  config.validate();
  std::vector<BuildBox> items;
  std::vector<std::uint32_t> kept;
  Aabb bounds;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    if (boxes[i].empty()) continue;
    bounds.grow(boxes[i]);
    items.push_back(BuildBox::of(boxes[i]));
    kept.push_back(static_cast<std::uint32_t>(i));
  }
  BvhT<T> bvh;
  if (items.empty()) return bvh;
  const BuiltTree built = buildTree(std::move(items), config, {});
  bvh.adoptTree(writeTree<T>(built.nodes, bounds), built.depth);
  for (const std::uint32_t i : built.order) bvh.triangle_ids_.push_back(kept[i]);
  return bvh;
}

template <typename T>
std::optional<MeshHitT<T>> bruteForceClosestHit(TriangleMethod method,
                                                const std::vector<Eigen::Vector3d>& vertices,
                                                const std::vector<TriangleIndices>& triangles,
                                                const RayT<T>& ray, bool cull_backfaces) {
  std::optional<MeshHitT<T>> best;
  RayT<T> r = ray;
  for (std::size_t i = 0; i < triangles.size(); ++i) {
    const TriangleIndices& tri = triangles[i];
    const auto hit = intersectTriangle(method, r, vertices[tri[0]].cast<T>().eval(),
                                       vertices[tri[1]].cast<T>().eval(),
                                       vertices[tri[2]].cast<T>().eval(), cull_backfaces);
    if (hit) {
      best = MeshHitT<T>{hit->t, hit->u, hit->v, static_cast<std::uint32_t>(i)};
      r.tmax = hit->t;
    }
  }
  return best;
}

template class BvhT<double>;
template class BvhT<float>;
template std::optional<MeshHitT<double>> bruteForceClosestHit(TriangleMethod,
                                                              const std::vector<Eigen::Vector3d>&,
                                                              const std::vector<TriangleIndices>&,
                                                              const Ray&, bool);
template std::optional<MeshHitT<float>> bruteForceClosestHit(TriangleMethod,
                                                             const std::vector<Eigen::Vector3d>&,
                                                             const std::vector<TriangleIndices>&,
                                                             const RayF&, bool);

}  // namespace core
}  // namespace laser_raycast
