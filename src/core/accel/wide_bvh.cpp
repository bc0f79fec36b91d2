#include "accel/wide_bvh.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>

namespace laser_raycast {
namespace core {
namespace {

// A binary subtree with its (float, outward-rounded) box, while a wide node gathers its children.
struct Gathered {
  Bvh::Child child;
  float lo[3], hi[3];
  float halfArea() const {
    const float x = hi[0] - lo[0], y = hi[1] - lo[1], z = hi[2] - lo[2];
    return x * y + y * z + z * x;
  }
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

  // The inner node's children, opening the largest inner one until there are kWidth or only
  // leaves.
  std::vector<Gathered> gather(const Bvh::Child& inner) const {
    std::vector<Gathered> gathered;
    auto open = [&](const Bvh::Child& c) {
      const auto& node = binary_[c.index];
      for (int k = 0; k < 2; ++k) {
        Gathered g;
        g.child = node.child[k];
        for (int a = 0; a < 3; ++a) {
          g.lo[a] = node.lo[k][a];
          g.hi[a] = node.hi[k][a];
        }
        gathered.push_back(g);
      }
    };
    open(inner);
    while (static_cast<int>(gathered.size()) < kWidth) {
      int best = -1;
      for (int k = 0; k < static_cast<int>(gathered.size()); ++k) {
        if (asLeaf(gathered[k].child)) continue;
        if (best < 0 || gathered[k].halfArea() > gathered[best].halfArea()) best = k;
      }
      if (best < 0) break;
      const Bvh::Child opened = gathered[best].child;
      gathered.erase(gathered.begin() + best);
      open(opened);
    }
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
