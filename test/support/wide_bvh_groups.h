// Which connected component (group) the triangles below a mesh's wide BVH node belong to, read off
// the tree's leaves: the wide BVH tests check that components fill whole subtrees. The core does
// not keep these tags; only its builder's choice of leaves depends on the components.
#pragma once

#include <cstdint>
#include <set>
#include <vector>

#include "accel/wide_bvh.h"
#include "laser_raycast/core/mesh.h"

namespace laser_raycast_test {

// The component of every triangle below ref, or -1 if they are of several.
inline std::int32_t subtreeGroup(const laser_raycast::core::Mesh& mesh,
                                 const std::vector<std::uint32_t>& components,
                                 laser_raycast::core::WideBvh::Ref ref) {
  using laser_raycast::core::WideBvh;
  const WideBvh& w = mesh.wideBvh();
  const auto& ids = mesh.bvh().triangleIds();
  std::set<std::uint32_t> groups;
  std::vector<WideBvh::Ref> todo{ref};
  while (!todo.empty()) {
    const WideBvh::Ref r = todo.back();
    todo.pop_back();
    if (r.isLeaf()) {
      for (std::uint32_t s = r.index; s < r.index + r.count; ++s) {
        groups.insert(components[ids[s]]);
      }
      continue;
    }
    for (int j = 0; j < WideBvh::kWidth; ++j) {
      if (w.nodes()[r.index].index[j] != WideBvh::kEmpty) todo.push_back(w.nodes()[r.index].child(j));
    }
  }
  return groups.size() == 1 ? static_cast<std::int32_t>(*groups.begin()) : -1;
}

// The same for child k of node (-1 for an empty child).
inline std::int32_t childGroup(const laser_raycast::core::Mesh& mesh,
                               const std::vector<std::uint32_t>& components, std::uint32_t node,
                               int k) {
  const auto& w = mesh.wideBvh();
  if (w.nodes()[node].index[k] == laser_raycast::core::WideBvh::kEmpty) return -1;
  return subtreeGroup(mesh, components, w.nodes()[node].child(k));
}

// Whether some of the group's triangles share a leaf with another group's.
inline bool groupInMixedLeaf(const laser_raycast::core::Mesh& mesh,
                             const std::vector<std::uint32_t>& components, std::int32_t group) {
  using laser_raycast::core::WideBvh;
  const WideBvh& w = mesh.wideBvh();
  const auto& ids = mesh.bvh().triangleIds();
  bool mixed = false;
  auto leaf = [&](WideBvh::Ref r) {
    std::set<std::uint32_t> groups;
    for (std::uint32_t s = r.index; s < r.index + r.count; ++s) {
      groups.insert(components[ids[s]]);
    }
    if (groups.size() > 1 && groups.count(static_cast<std::uint32_t>(group))) mixed = true;
  };
  std::vector<WideBvh::Ref> todo{w.root()};
  while (!todo.empty()) {
    const WideBvh::Ref r = todo.back();
    todo.pop_back();
    if (r.isEmpty()) continue;
    if (r.isLeaf()) {
      leaf(r);
      continue;
    }
    for (int j = 0; j < WideBvh::kWidth; ++j) {
      if (w.nodes()[r.index].index[j] != WideBvh::kEmpty) todo.push_back(w.nodes()[r.index].child(j));
    }
  }
  return mixed;
}

}  // namespace laser_raycast_test
