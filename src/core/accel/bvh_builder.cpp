#include "accel/bvh_builder.h"

#include <algorithm>
#include <numeric>
#include <optional>
#include <utility>

#include "util/thread_pool.h"

namespace laser_raycast {
namespace core {
namespace {

// The bounds of some triangles and of their centres (twice: BuildBox::twiceCenter).
struct Extent {
  BuildBox bounds, centers;
  void grow(const BuildBox& t) {
    bounds.grow(t);
    centers.grow(t.twiceCenter());
  }
};

struct Task {
  std::uint32_t node;
  std::uint32_t begin, end;  // range in the order array
  int depth;
  // The range's extent, if known (the partition that made the range measures it on the way).
  std::optional<Extent> extent;
  // Whether the range is known to hold one group (so do the ranges split from it).
  bool one_group = false;
};

struct Bin {
  BuildBox bounds;
  std::uint32_t count = 0;
};

// Where centres fall among the bins of each axis: bin (c - lo) * scale, clamped to the bins (a NaN,
// from coordinates beyond the floats, to the first).
struct Binning {
  __m128 lo, scale, last;
  Binning(const BuildBox& centers, int nbins) {
    lo = centers.lo;
    alignas(16) float s[4] = {0, 0, 0, 0};
    for (int a = 0; a < 3; ++a) {
      const float extent = centers.upper(a) - centers.lower(a);
      // A NaN or infinite extent bins every centre into the first bin: no split on that axis.
      s[a] = extent > 0 && extent <= std::numeric_limits<float>::max() ? nbins / extent : 0.0f;
    }
    scale = _mm_load_ps(s);
    last = _mm_set1_ps(static_cast<float>(nbins - 1));
  }
  bool binned(int axis) const { return BuildBox::lane(scale, axis) > 0; }
  // The bins of center on the three axes.
  __m128i bins(__m128 center) const {
    const __m128 x = _mm_mul_ps(_mm_sub_ps(center, lo), scale);
    // maxps gives its second operand when either is NaN.
    return _mm_cvttps_epi32(_mm_min_ps(_mm_max_ps(x, _mm_setzero_ps()), last));
  }
};

// Binned SAH (Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies", 2007): for
// each axis, centroids are binned and the split plane between bins with the lowest cost is chosen.
// With groups (e.g. a mesh's connected components), a group is never split between subtrees while
// the node holds more than one group: the groups are partitioned first (SAH over their centroids),
// then each group's triangles. So every subtree below some node holds exactly one group, and every
// leaf does.
//
// The builder keeps its triangles (and their groups) in the order of the tree being built, moved
// with their indices when a range is partitioned, so that every pass over a node's range reads
// memory in order: read through the indices instead, a mesh of millions of triangles spent most of
// its build waiting for memory. It bins the three axes in one pass, in float (SSE2).
class Builder {
 public:
  Builder(std::vector<BuildBox> tris, const BvhConfig& config, std::vector<std::uint32_t> groups)
      : tris_(std::move(tris)),
        config_(config),
        groups_(std::move(groups)),
        order_(tris_.size()) {
    std::iota(order_.begin(), order_.end(), 0u);
    if (groups_.empty()) return;
    std::uint32_t count = 0;
    for (const std::uint32_t g : groups_) count = std::max(count, g + 1);
    group_bounds_.resize(count);
    for (std::size_t i = 0; i < tris_.size(); ++i) group_bounds_[groups_[i]].grow(tris_[i]);
  }

  // The tree over every triangle. With config_.threads > 1 the top of the tree is built first,
  // down to subtrees of a few thousand triangles at most, which are then built on the threads,
  // each into a vector of its own, and joined. A node's split depends only on the triangles in its
  // range, so the tree (its structure, boxes and triangle order; writeTree numbers the nodes
  // afresh) is the same for any number of threads.
  void run() {
    const auto n = static_cast<std::uint32_t>(tris_.size());
    nodes_.reserve(2 * tris_.size());
    nodes_.emplace_back();
    const int threads = threadsFor(config_.threads);
    // Subtrees of at most this many triangles are left to the threads: about eight a thread, so
    // that one large subtree does not leave the others idle, and none so small that handing it
    // out costs more than building it.
    const std::uint32_t defer_below =
        threads > 1 ? std::max<std::uint32_t>(kMinParallelSubtree, n / (8 * threads)) : 0;
    std::vector<Task> deferred;
    depth_ = grow({0, 0, n, 0, std::nullopt, groups_.empty()}, defer_below, &nodes_, &deferred);
    if (deferred.empty()) return;
    std::vector<std::vector<BuildNode>> parts(deferred.size());
    std::vector<int> depths(deferred.size(), 0);
    ThreadPool pool(std::min<int>(threads, static_cast<int>(deferred.size())));
    pool.run(static_cast<int>(deferred.size()), [&](int i) {
      Task root = deferred[i];
      root.node = 0;
      parts[i].emplace_back();
      depths[i] = grow(root, 0, &parts[i], nullptr);
    });
    for (std::size_t i = 0; i < deferred.size(); ++i) {
      join(parts[i], deferred[i].node);
      depth_ = std::max(depth_, depths[i]);
    }
  }

  // What run() built, moved out.
  BuiltTree take() { return {std::move(nodes_), std::move(order_), depth_}; }

 private:
  // Subtrees with fewer triangles are never handed to a thread of their own.
  static constexpr std::uint32_t kMinParallelSubtree = 4096;

  // What one thread's splits reuse: the bins of the three axes and the sweep's sums.
  struct Scratch {
    explicit Scratch(int nbins) : bins(3 * nbins), right_area(nbins), right_count(nbins) {}
    std::vector<Bin> bins;  // axis a's bin b at a * nbins + b
    std::vector<double> right_area;
    std::vector<std::uint32_t> right_count;
  };

  // Builds the subtree of `root` (its node already in *nodes) into *nodes, children after their
  // parents; with `deferred`, a task below the root with at most defer_below triangles is left
  // there instead (its node stays empty). Returns the deepest depth built.
  int grow(const Task& root, std::uint32_t defer_below, std::vector<BuildNode>* nodes,
           std::vector<Task>* deferred) {
    int depth = 0;
    Scratch scratch(config_.bins);
    std::vector<Task> tasks{root};
    while (!tasks.empty()) {
      const Task task = tasks.back();
      tasks.pop_back();
      const std::uint32_t count = task.end - task.begin;
      if (deferred && task.depth > 0 && count <= defer_below) {
        deferred->push_back(task);
        continue;
      }
      depth = std::max(depth, task.depth);
      BuildNode& node = (*nodes)[task.node];
      Extent extent;
      if (task.extent) {
        extent = *task.extent;
      } else {
        for (std::uint32_t i = task.begin; i < task.end; ++i) extent.grow(tris_[i]);
      }
      node.bounds = extent.bounds;
      Sides sides;
      const bool by_group = !task.one_group && holdsSeveralGroups(task);
      const std::uint32_t mid = split(task, extent, by_group, &scratch, &sides);
      if (mid == task.begin || mid == task.end) {
        node.first = task.begin;
        node.count = count;
        continue;
      }
      const auto left = static_cast<std::uint32_t>(nodes->size());
      node.first = left;
      node.count = 0;
      nodes->emplace_back();  // invalidates `node`
      nodes->emplace_back();
      tasks.push_back({left + 1, mid, task.end, task.depth + 1, sides.right, !by_group});
      tasks.push_back({left, task.begin, mid, task.depth + 1, sides.left, !by_group});
    }
    return depth;
  }

  // A subtree built on its own (its root part[0], the inner nodes' children indices into part)
  // put in place of the empty node `at`.
  void join(const std::vector<BuildNode>& part, std::uint32_t at) {
    // part[j] for j >= 1 goes to base + j - 1.
    const auto base = static_cast<std::uint32_t>(nodes_.size());
    auto placed = [&](BuildNode node) {
      if (node.count == 0) node.first = base + node.first - 1;
      return node;
    };
    nodes_[at] = placed(part[0]);
    for (std::size_t j = 1; j < part.size(); ++j) nodes_.push_back(placed(part[j]));
  }

  // The centre (twice) the triangle at position i of the order is binned by: its own, or its
  // group's while groups are split apart.
  __m128 binCenter(std::uint32_t i, bool by_group) const {
    return (by_group ? group_bounds_[groups_[i]] : tris_[i]).twiceCenter();
  }

  bool holdsSeveralGroups(const Task& task) const {
    if (groups_.empty()) return false;
    const std::uint32_t first = groups_[task.begin];
    for (std::uint32_t i = task.begin + 1; i < task.end; ++i) {
      if (groups_[i] != first) return true;
    }
    return false;
  }

  // The extents of a split's two sides, where the split measured them.
  struct Sides {
    std::optional<Extent> left, right;
  };

  // Moves the positions of [begin, end) for which goes_left(i) holds before the others (the
  // triangles, their indices and groups together) and returns where the others start; each side's
  // extent into *sides, measured as every position is looked at once.
  template <class Pred>
  std::uint32_t partition(std::uint32_t begin, std::uint32_t end, Pred&& goes_left,
                          Sides* sides) {
    Extent left, right;
    std::uint32_t i = begin, j = end;
    while (true) {
      for (; i < j && goes_left(i); ++i) left.grow(tris_[i]);
      for (; i < j && !goes_left(j - 1); --j) right.grow(tris_[j - 1]);
      if (i + 1 >= j) {
        sides->left = left;
        sides->right = right;
        return i;
      }
      --j;
      left.grow(tris_[j]);
      right.grow(tris_[i]);
      std::swap(tris_[i], tris_[j]);
      std::swap(order_[i], order_[j]);
      if (!groups_.empty()) std::swap(groups_[i], groups_[j]);
      ++i;
    }
  }

  // Partitions [begin, end) and returns the split point; begin or end means "make a leaf". The
  // sides' extents into *sides where the partition measured them.
  // by_group: the range holds several groups, to be split apart.
  std::uint32_t split(const Task& task, const Extent& range, bool by_group, Scratch* scratch,
                      Sides* sides) {
    const std::uint32_t count = task.end - task.begin;
    if (count <= 1 || task.depth >= config_.max_depth) return task.begin;
    BuildBox centers = range.centers;
    if (by_group) {
      centers = BuildBox{};
      for (std::uint32_t i = task.begin; i < task.end; ++i) centers.grow(binCenter(i, true));
    }
    // No more bins than triangles: a small node's few centres need no more planes between them,
    // and its bins are what its split costs (most nodes are small).
    const int nbins = static_cast<int>(std::min<std::uint32_t>(config_.bins, count));
    const Binning binning(centers, nbins);
    // Every axis binned in one pass over the range (an axis without an extent puts everything in
    // its first bin and is not costed).
    Bin* bins = scratch->bins.data();
    std::fill(scratch->bins.begin(), scratch->bins.begin() + 3 * nbins, Bin{});
    for (std::uint32_t i = task.begin; i < task.end; ++i) {
      alignas(16) std::int32_t b[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(b), binning.bins(binCenter(i, by_group)));
      const BuildBox& box = tris_[i];
      for (int axis = 0; axis < 3; ++axis) {
        Bin& bin = bins[axis * nbins + b[axis]];
        bin.bounds.grow(box);
        ++bin.count;
      }
    }
    const double leaf_cost = count;
    double best_cost = std::numeric_limits<double>::infinity();
    int best_axis = -1, best_bin = 0;
    double* right_area = scratch->right_area.data();
    std::uint32_t* right_count = scratch->right_count.data();
    for (int axis = 0; axis < 3; ++axis) {
      if (!binning.binned(axis)) continue;
      const Bin* axis_bins = bins + axis * nbins;
      // Sweep from the right, then from the left, to cost each of the nbins - 1 planes.
      BuildBox acc;
      std::uint32_t n = 0;
      for (int b = nbins - 1; b > 0; --b) {
        acc.grow(axis_bins[b].bounds);
        n += axis_bins[b].count;
        right_area[b] = acc.halfArea();
        right_count[b] = n;
      }
      acc = BuildBox{};
      n = 0;
      for (int b = 0; b < nbins - 1; ++b) {
        acc.grow(axis_bins[b].bounds);
        n += axis_bins[b].count;
        if (n == 0 || right_count[b + 1] == 0) continue;
        const double cost = n * acc.halfArea() + right_count[b + 1] * right_area[b + 1];
        if (cost < best_cost) {
          best_cost = cost;
          best_axis = axis;
          best_bin = b;
        }
      }
    }
    const double area = range.bounds.halfArea();
    const double split_cost = area > 0 ? config_.traversal_cost + best_cost / area
                                       : std::numeric_limits<double>::infinity();
    if (best_axis < 0) {
      if (by_group) return splitGroupsByIndex(task, sides);
      // All centroids coincide: no plane separates them. Halve by count if the leaf would be too
      // big.
      if (count <= static_cast<std::uint32_t>(config_.max_leaf_size)) return task.begin;
      return task.begin + count / 2;
    }
    const bool leaf_is_cheaper =
        split_cost >= leaf_cost && count <= static_cast<std::uint32_t>(config_.max_leaf_size);
    if (leaf_is_cheaper && !by_group) return task.begin;
    return partition(
        task.begin, task.end,
        [&](std::uint32_t i) {
          alignas(16) std::int32_t b[4];
          _mm_store_si128(reinterpret_cast<__m128i*>(b), binning.bins(binCenter(i, by_group)));
          return b[best_axis] <= best_bin;
        },
        sides);
  }

  // Several groups whose centroids coincide: the lower half of their indices goes left.
  std::uint32_t splitGroupsByIndex(const Task& task, Sides* sides) {
    std::vector<std::uint32_t> present(groups_.begin() + task.begin, groups_.begin() + task.end);
    std::sort(present.begin(), present.end());
    present.erase(std::unique(present.begin(), present.end()), present.end());
    const std::uint32_t pivot = present[present.size() / 2];
    return partition(
        task.begin, task.end, [&](std::uint32_t i) { return groups_[i] < pivot; }, sides);
  }

  std::vector<BuildBox> tris_;         // in the order of order_
  const BvhConfig& config_;
  std::vector<std::uint32_t> groups_;  // per triangle in the order of order_, or empty
  std::vector<BuildBox> group_bounds_;
  std::vector<std::uint32_t> order_;
  std::vector<BuildNode> nodes_;
  int depth_ = 0;
};

}  // namespace

BuiltTree buildTree(std::vector<BuildBox> boxes, const BvhConfig& config,
                    std::vector<std::uint32_t> groups) {
  Builder builder(std::move(boxes), config, std::move(groups));
  builder.run();
  return builder.take();
}

}  // namespace core
}  // namespace laser_raycast
