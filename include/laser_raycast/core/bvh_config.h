// How a BVH is built: BvhT's settings, and its builder's.
#pragma once

namespace laser_raycast {
namespace core {

struct BvhConfig {
  int max_leaf_size = 8;        // a node with more triangles is always split
  int bins = 16;                // SAH candidate planes per axis, minus one
  double traversal_cost = 1.0;  // cost of visiting a node, in units of one triangle test
  int max_depth = 60;           // deeper nodes become leaves; bounds the traversal stack (64)
  int threads = 1;              // building the tree (0: every core); the same tree for any number

  // Throws std::invalid_argument naming the field and its value.
  void validate() const;
};

}  // namespace core
}  // namespace laser_raycast
