#include "accel/wide_bvh.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <utility>
#include <vector>

namespace laser_raycast {
namespace core {
namespace {

// A binary subtree with its (float, outward-rounded) box, while a wide node gathers its children.
struct Gathered {
  Bvh::Child child;
  float lo[3], hi[3];
};

}  // namespace

// Collapses the binary BVH depth-first into wide nodes, filling the WideBvh's arrays.
class WideBvh::Builder {
 public:
  // The triangle count of a binary subtree, and its collapsed wide reference.
  struct Summary {
    Ref ref;
    std::uint32_t triangles;
  };

  Builder(WideBvh* out, const Bvh& bvh, const std::vector<std::uint32_t>& slot_group)
      : out_(*out), binary_(bvh.nodes()), slot_group_(slot_group), span_(binary_.size()) {
    computeSpans();
    computeCosts();
  }

  // The binary tree's depth is bounded (BvhConfig::max_depth), so the recursion is too.
  Summary collapse(const Bvh::Child& child) {
    if (const auto leaf = asLeaf(child)) {
      if (leaf->count >= kInner) throw std::length_error("a BVH leaf of 2^31 or more triangles");
      return Summary{Ref{leaf->index, leaf->count}, leaf->count};
    }
    const std::vector<Gathered> gathered = gather(child);
    const auto index = static_cast<std::uint32_t>(out_.nodes_.size());
    out_.nodes_.emplace_back();
    Summary summary{Ref{index, 0}, 0};
    for (int k = 0; k < kWidth; ++k) {
      if (k >= static_cast<int>(gathered.size())) {
        setEmpty(&out_.nodes_[index], k);
        continue;
      }
      const Summary sub = collapse(gathered[k].child);  // may grow nodes_
      Node& node = out_.nodes_[index];
      for (int a = 0; a < 3; ++a) {
        node.lo[a][k] = gathered[k].lo[a];
        node.hi[a][k] = gathered[k].hi[a];
      }
      node.index[k] = sub.ref.index;
      node.count[k] = sub.ref.count;
      summary.triangles += sub.triangles;
    }
    summary.ref.count = kInner | std::min<std::uint32_t>(summary.triangles, kInner - 1);
    return summary;
  }

 private:
  // A binary inner node's slot range (a subtree's slots are contiguous: the builder partitions in
  // place) and whether it holds a single group.
  struct Span {
    std::uint32_t first, count;
    bool one_group;
  };

  // Children come after their parent, so one backward pass sees every child before its parent.
  void computeSpans() {
    for (std::size_t n = binary_.size(); n-- > 0;) {
      Span out{std::numeric_limits<std::uint32_t>::max(), 0, true};
      for (int k = 0; k < 2; ++k) {
        const Bvh::Child c = binary_[n].child[k];
        const Span sub = c.isLeaf() ? Span{c.index, c.count, true} : span_[c.index];
        out.first = std::min(out.first, sub.first);
        out.count += sub.count;
        out.one_group = out.one_group && sub.one_group;
      }
      out.one_group =
          out.one_group &&
          (slot_group_.empty() ||
           std::all_of(slot_group_.begin() + out.first, slot_group_.begin() + out.first + out.count,
                       [&](std::uint32_t g) { return g == slot_group_[out.first]; }));
      span_[n] = out;
    }
  }

  // A binary leaf, or a small subtree of one group taken as one leaf: a few more triangle tests
  // cost less than the node visits they replace.
  std::optional<Bvh::Child> asLeaf(const Bvh::Child& c) const {
    if (c.isLeaf()) return c;
    const Span& sub = span_[c.index];
    if (sub.count <= kMaxLeafTriangles && sub.one_group) return Bvh::Child{sub.first, sub.count};
    return std::nullopt;
  }

  // How a binary subtree is spread over a wide node's child slots, chosen by surface area cost
  // (the expected cost of a ray through the subtree's box: a wide node visited costs one, a leaf
  // its triangles, each weighted by its box's area) over every way to collapse it, bottom up (a
  // dynamic programme over the binary nodes, as for compressed wide BVHs on GPUs). Taking a small
  // subtree's children into its parent's free slots saves the node it would have been: the greedy
  // collapse this replaced (open the largest child until four) left 37% of the nodes of a
  // height field and of a forest of trunks with two children only.
  //
  // For binary inner node n and k = 2..4: cost_[n].spread[k] is the least cost of n's subtree
  // spread over k slots (its two children sharing them), and cost_[n].split[k] how many of them
  // its first child takes; cost_[n].best is the k that costs least (the fewest slots among equal
  // costs), and 1 + spread[best] n's cost in one slot, a wide node of its own. Each is per unit of
  // n's box's area (the chance that a ray through n's box enters a child's is the ratio of their
  // areas).
  struct Cost {
    double spread[kWidth + 1];
    std::int8_t split[kWidth + 1];
    std::int8_t best;
    double own() const { return 1 + spread[best]; }
  };

  static float halfArea(const float lo[3], const float hi[3]) {
    const float x = hi[0] - lo[0], y = hi[1] - lo[1], z = hi[2] - lo[2];
    return x * y + y * z + z * x;
  }

  // The least cost of child k of binary node n in at most `slots` slots, and how many it uses.
  std::pair<double, int> childCost(std::uint32_t n, int k, int slots) const {
    const Bvh::Child c = binary_[n].child[k];
    const double area = halfArea(binary_[n].lo[k], binary_[n].hi[k]);
    if (const auto leaf = asLeaf(c)) return {area * leaf->count, 1};
    const Cost& sub = cost_[c.index];
    std::pair<double, int> best{area * sub.own(), 1};
    for (int j = 2; j <= slots; ++j) {
      if (area * sub.spread[j] < best.first) best = {area * sub.spread[j], j};
    }
    return best;
  }

  // Children come after their parent, so one backward pass sees every child before its parent. A
  // child's cost, per unit of its own area, is multiplied by that area (childCost), and the sum
  // over the node's children divided by the node's area.
  void computeCosts() {
    cost_.resize(binary_.size());
    for (std::size_t n = binary_.size(); n-- > 0;) {
      Cost& c = cost_[n];
      float lo[3], hi[3];
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(binary_[n].lo[0][a], binary_[n].lo[1][a]);
        hi[a] = std::max(binary_[n].hi[0][a], binary_[n].hi[1][a]);
      }
      // A box of no area (a point or a segment) would divide by 0: the floor changes only which
      // tree is built, never what a walk finds.
      const double area = std::max(halfArea(lo, hi), std::numeric_limits<float>::min());
      c.best = 2;
      for (int k = 2; k <= kWidth; ++k) {
        c.spread[k] = std::numeric_limits<double>::infinity();
        c.split[k] = 1;
        for (int j = 1; j < k; ++j) {
          const double total = childCost(static_cast<std::uint32_t>(n), 0, j).first +
                               childCost(static_cast<std::uint32_t>(n), 1, k - j).first;
          if (total < c.spread[k]) {
            c.spread[k] = total;
            c.split[k] = static_cast<std::int8_t>(j);
          }
        }
        c.spread[k] /= area;
        if (c.spread[k] < c.spread[c.best]) c.best = static_cast<std::int8_t>(k);
      }
    }
  }

  // Child k of binary node n spread over at most `slots` slots, appended to out.
  void spread(std::uint32_t n, int k, int slots, std::vector<Gathered>* out) const {
    const int used = childCost(n, k, slots).second;
    const Bvh::Child c = binary_[n].child[k];
    if (used == 1) {
      Gathered g;
      g.child = c;
      for (int a = 0; a < 3; ++a) {
        g.lo[a] = binary_[n].lo[k][a];
        g.hi[a] = binary_[n].hi[k][a];
      }
      out->push_back(g);
      return;
    }
    spreadNode(c.index, used, out);
  }
  // Binary inner node n spread over exactly `slots` slots (2 to kWidth).
  void spreadNode(std::uint32_t n, int slots, std::vector<Gathered>* out) const {
    const int first = cost_[n].split[slots];
    spread(n, 0, first, out);
    spread(n, 1, slots - first, out);
  }

  // A wide node's children for binary inner node n: its subtree spread over the number of slots
  // that costs least.
  std::vector<Gathered> gather(const Bvh::Child& inner) const {
    std::vector<Gathered> gathered;
    spreadNode(inner.index, cost_[inner.index].best, &gathered);
    return gathered;
  }

  static void setEmpty(Node* node, int k) {
    for (int a = 0; a < 3; ++a) {
      node->lo[a][k] = std::numeric_limits<float>::infinity();
      node->hi[a][k] = -std::numeric_limits<float>::infinity();
    }
    node->index[k] = kEmpty;
    node->count[k] = 0;
  }

  WideBvh& out_;
  const std::vector<Bvh::Node>& binary_;
  const std::vector<std::uint32_t>& slot_group_;
  std::vector<Span> span_;
  std::vector<Cost> cost_;
};

WideBvh::WideBvh(const Bvh& bvh, const std::vector<std::uint32_t>& slot_group) : bvh_(&bvh) {
  if (bvh.empty()) return;
  Builder builder(this, bvh, slot_group);
  root_ = builder.collapse(bvh.root()).ref;
  // Grown one node at a time, the nodes hold up to twice what they use (38 bytes a triangle of a
  // 20M-triangle terrain): given back once the tree is whole.
  nodes_.shrink_to_fit();
}

WideBoxRay::WideBoxRay(const Ray& ray, const Aabb& bounds) {
  reach_ =
      (bounds.lo - ray.origin).cwiseAbs().cwiseMax((bounds.hi - ray.origin).cwiseAbs()).maxCoeff() /
      ray.dir.cwiseAbs().maxCoeff();
  tnear0_ = floatBelow(ray.tmin - (std::abs(ray.tmin) + reach_) * kWiden);
  for (int k = 0; k < 3; ++k) {
    setAxis(k, ray.dir[k], floatAbove(ray.origin[k]), floatBelow(ray.origin[k]));
  }
}

// The four-wide test's arithmetic on one box.
bool WideBoxRay::enters(const float lo[3], const float hi[3], float cull) const {
  constexpr std::uint32_t kLo = offsetof(WideBvh::Node, lo);
  float tnear = tnear0_, tfar = std::numeric_limits<float>::infinity();
  for (int k = 0; k < 3; ++k) {
    const bool positive = near_offset_[k] == kLo + k * WideBvh::kWidth * sizeof(float);
    const float t0 = ((positive ? lo : hi)[k] - origin_near_[k]) * inv_dir_[k];
    const float t1 = ((positive ? hi : lo)[k] - origin_far_[k]) * inv_dir_[k];
    tnear = t0 > tnear ? t0 : tnear;  // NaN never replaces tnear
    tfar = t1 < tfar ? t1 : tfar;     // nor tfar
  }
  tfar *= kWidenExit;
  return tnear <= (tfar < cull ? tfar : cull);
}

}  // namespace core
}  // namespace laser_raycast
