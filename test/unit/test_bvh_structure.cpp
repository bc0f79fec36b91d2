// The BVH's tree: its invariants, degenerate and empty inputs, visit(), and BvhConfig::validate().
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bvh_checks.h"
#include "expect_invalid.h"
#include "laser_raycast/core/bvh.h"
#include "laser_raycast/core/mesh.h"
#include "random.h"
#include "triangle_soup.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

constexpr double kInf = std::numeric_limits<double>::infinity();

// The tree's own invariants, checked from nodes(): each node contains its children (or its
// triangles' vertices), every non-degenerate triangle sits in exactly one leaf slot, and the copied
// vertices are the mesh's (rounded to float for BvhF).
template <typename T>
void checkStructure(const BvhT<T>& bvh, const Soup& s) {
  using Child = typename BvhT<T>::Child;
  std::vector<int> seen(s.triangles.size(), 0);
  auto contains = [](const AabbT<T>& outer, const Vec3<T>& p) {
    return (outer.lo.array() <= p.array()).all() && (p.array() <= outer.hi.array()).all();
  };
  // Walk from the root with each subtree's box (the exact bounds at the root, then the float boxes
  // stored in the parents): every vertex must lie in the box of the leaf holding it.
  std::vector<std::pair<Child, AabbT<T>>> todo{{bvh.root(), bvh.bounds()}};
  std::size_t inner = 0;
  while (!todo.empty()) {
    const auto [child, box] = todo.back();
    todo.pop_back();
    if (child.isLeaf()) {
      for (std::uint32_t slot = child.index; slot < child.index + child.count; ++slot) {
        const std::uint32_t id = bvh.triangleIds()[slot];
        ++seen[id];
        for (int k = 0; k < 3; ++k) {
          const Vec3<T> v = s.vertices[s.triangles[id][k]].cast<T>();
          EXPECT_EQ(bvh.triangleVertices()[slot][k], v);
          EXPECT_TRUE(contains(box, v));
        }
      }
      continue;
    }
    ASSERT_LT(child.index, bvh.nodes().size());
    ++inner;
    const auto& node = bvh.nodes()[child.index];
    for (int k = 0; k < 2; ++k) todo.emplace_back(node.child[k], node.box(k));
  }
  EXPECT_EQ(inner, bvh.nodes().size());  // every inner node is reached exactly once
  for (std::size_t i = 0; i < s.triangles.size(); ++i) {
    const auto& tri = s.triangles[i];
    const bool degenerate = isDegenerateTriangle<T>(
        s.vertices[tri[0]].cast<T>(), s.vertices[tri[1]].cast<T>(), s.vertices[tri[2]].cast<T>());
    EXPECT_EQ(seen[i], degenerate ? 0 : 1) << "triangle " << i;
  }
}

TEST(Bvh, StructureInvariants) {
  Rng rng(3);
  for (const int n : {1, 5, 300, 3000}) {
    const Soup s = n % 2 ? spreadSoup(rng, n) : clusteredSoup(rng, n);
    checkStructure(Bvh::build(s.vertices, s.triangles), s);
    checkStructure(BvhF::build(s.vertices, s.triangles), s);
  }
  checkStructure(Bvh::build(gridSoup().vertices, gridSoup().triangles), gridSoup());
}

// Two trees node for node: the same boxes, children, depth, triangle order and slots.
template <typename T>
void expectSameTree(const BvhT<T>& a, const BvhT<T>& b, const std::string& what) {
  ASSERT_EQ(a.nodes().size(), b.nodes().size()) << what;
  EXPECT_EQ(a.depth(), b.depth()) << what;
  EXPECT_EQ(a.root().index, b.root().index) << what;
  EXPECT_EQ(a.root().count, b.root().count) << what;
  EXPECT_EQ(a.bounds().lo, b.bounds().lo) << what;
  EXPECT_EQ(a.bounds().hi, b.bounds().hi) << what;
  for (std::size_t i = 0; i < a.nodes().size(); ++i) {
    for (int k = 0; k < 2; ++k) {
      ASSERT_EQ(a.nodes()[i].child[k].index, b.nodes()[i].child[k].index) << what << " node " << i;
      ASSERT_EQ(a.nodes()[i].child[k].count, b.nodes()[i].child[k].count) << what << " node " << i;
      ASSERT_EQ(a.nodes()[i].box(k).lo, b.nodes()[i].box(k).lo) << what << " node " << i;
      ASSERT_EQ(a.nodes()[i].box(k).hi, b.nodes()[i].box(k).hi) << what << " node " << i;
    }
  }
  EXPECT_EQ(a.triangleIds(), b.triangleIds()) << what;
  ASSERT_EQ(a.triangleVertices().size(), b.triangleVertices().size()) << what;
  for (std::size_t slot = 0; slot < a.triangleVertices().size(); ++slot) {
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(a.triangleVertices()[slot][k], b.triangleVertices()[slot][k]) << what;
    }
  }
}

// BvhConfig::threads builds subtrees on several threads: the tree is the one a single thread
// builds, for any number of threads, with and without groups (a mesh's components), for soups
// spread out and clustered, large enough that several subtrees go to the threads.
TEST(Bvh, TheTreeIsTheSameForAnyNumberOfThreads) {
  Rng rng(71);
  for (const int n : {3000, 40000, 150000}) {
    const Soup s = n % 2 ? spreadSoup(rng, n) : clusteredSoup(rng, n);
    std::vector<std::uint32_t> groups(s.triangles.size());
    for (std::size_t i = 0; i < groups.size(); ++i) groups[i] = static_cast<std::uint32_t>(i / 997);
    for (const bool grouped : {false, true}) {
      const std::vector<std::uint32_t> g = grouped ? groups : std::vector<std::uint32_t>{};
      const Bvh one = Bvh::build(s.vertices, s.triangles, BvhConfig{}, g);
      for (const int threads : {0, 2, 3, 8}) {
        BvhConfig config;
        config.threads = threads;
        const std::string what = std::to_string(n) + " triangles, " +
                                 std::to_string(threads) + " threads" +
                                 (grouped ? ", grouped" : "");
        expectSameTree(one, Bvh::build(s.vertices, s.triangles, config, g), what);
        if (n == 40000) checkStructure(Bvh::build(s.vertices, s.triangles, config, g), s);
      }
    }
  }
}

// Degenerate triangles (repeated vertex, collinear, a sliver that is collinear only once rounded to
// float) are left out of the BVH, counted by Mesh, and never hit.
TEST(Bvh, DegenerateTrianglesAreExcluded) {
  const ExemptionBudget budget;
  Rng rng(11);
  Soup s = spreadSoup(rng, 200);
  const auto n0 = static_cast<std::uint32_t>(s.vertices.size());
  s.vertices.push_back(Eigen::Vector3d(0, 0, 0));
  s.vertices.push_back(Eigen::Vector3d(1, 1, 1));
  s.vertices.push_back(Eigen::Vector3d(2, 2, 2));        // collinear with the two above
  s.vertices.push_back(Eigen::Vector3d(0.5, 1e-50, 0));  // off the x axis only in double
  s.vertices.push_back(Eigen::Vector3d(1, 0, 0));
  s.triangles.push_back({n0, n0, n0 + 1});          // repeated vertex
  s.triangles.push_back({n0, n0 + 1, n0 + 2});      // collinear
  s.triangles.push_back({n0 + 2, n0 + 1, n0 + 1});  // repeated vertex again
  s.triangles.push_back({n0, n0 + 4, n0 + 3});      // a sliver, degenerate in float only
  // Shuffle them into the middle so that indices past them are checked too.
  std::swap(s.triangles[10], s.triangles[s.triangles.size() - 1]);
  std::swap(s.triangles[20], s.triangles[s.triangles.size() - 2]);

  const Mesh mesh(s.vertices, s.triangles);
  EXPECT_EQ(mesh.degenerateTriangleCount(), 3u);
  EXPECT_EQ(mesh.triangles().size(), s.triangles.size());
  // The mesh's slots, and its tree as it built it (the mesh keeps only its wide BVH's).
  EXPECT_FALSE(mesh.bvh().hasTree());
  const Bvh bvh = Bvh::build(s.vertices, s.triangles, {}, mesh.components());
  EXPECT_EQ(bvh.triangleIds(), mesh.bvh().triangleIds());
  const BvhF bvhf = BvhF::build(s.vertices, s.triangles);
  EXPECT_EQ(bvh.triangleIds().size(), s.triangles.size() - 3);
  EXPECT_EQ(bvhf.triangleIds().size(), s.triangles.size() - 4);
  checkStructure(bvh, s);
  checkStructure(bvhf, s);
  for (int i = 0; i < 300; ++i) {
    Ray ray = randomRay(rng, s.bounds(), s);
    if (i % 3 == 0) {
      // Straight through the degenerate ones' line and the sliver.
      ray.origin = Eigen::Vector3d(0.25, 1e-60, -1);
      ray.dir = Eigen::Vector3d(0.3 * (i % 7), 0, 1);
    }
    checkRayBothPrecisions(bvh, bvhf, s, ray);
    if (HasFatalFailure()) return;
  }
}

// No triangles, or only degenerate ones: an empty BVH that hits nothing.
TEST(Bvh, EmptyBuildHitsNothing) {
  const std::vector<Eigen::Vector3d> v = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0)};
  for (const auto& tris :
       {std::vector<TriangleIndices>{}, std::vector<TriangleIndices>{{0, 1, 1}, {0, 0, 0}}}) {
    const Bvh bvh = Bvh::build(v, tris);
    EXPECT_TRUE(bvh.empty());
    EXPECT_TRUE(bvh.bounds().empty());
    Ray ray;
    EXPECT_FALSE(bvh.closestHit<TriangleMethod::kWatertight>(ray));
    EXPECT_FALSE(bvh.anyHit<TriangleMethod::kWatertight>(ray));
    int visited = 0;
    bvh.visit([](const Aabb&) { return true; }, [&](std::uint32_t) { ++visited; });
    EXPECT_EQ(visited, 0);
  }
}

// visit() calls leaf() for exactly the slots of the leaves whose box passes the predicate, once
// each. An overlap test is monotone (a child overlaps only if its parent does: the float boxes
// stored in the nodes nest, being outward roundings of nested boxes), so the expected set is read
// straight from nodes(), plus the root's exact box, which a child's rounded box may exceed by an
// ulp.
TEST(Bvh, VisitReachesExactlyTheLeavesThatPass) {
  Rng rng(8);
  const Soup s = spreadSoup(rng, 2000);
  const Bvh bvh = Bvh::build(s.vertices, s.triangles);
  for (int q = 0; q < 50; ++q) {
    const Eigen::Vector3d c =
        uniformInBox(rng, Eigen::Vector3d::Constant(-12), Eigen::Vector3d::Constant(12));
    const Eigen::Vector3d h =
        uniformInBox(rng, Eigen::Vector3d::Constant(0), Eigen::Vector3d::Constant(6));
    auto overlaps = [&](const Aabb& box) {
      return (box.lo.array() <= (c + h).array()).all() && (box.hi.array() >= (c - h).array()).all();
    };
    std::multiset<std::uint32_t> expected, visited;
    ASSERT_FALSE(bvh.root().isLeaf());
    for (const auto& node : bvh.nodes()) {
      for (int k = 0; k < 2; ++k) {
        const auto leaf = node.child[k];
        if (!leaf.isLeaf() || !overlaps(bvh.bounds()) || !overlaps(node.box(k))) continue;
        for (std::uint32_t slot = leaf.index; slot < leaf.index + leaf.count; ++slot) {
          expected.insert(slot);
        }
      }
    }
    int calls = 0;
    bvh.visit(
        [&](const Aabb& box) {
          ++calls;
          return overlaps(box);
        },
        [&](std::uint32_t slot) { visited.insert(slot); });
    EXPECT_EQ(visited, expected);
    EXPECT_GT(calls, 0);
  }
  // Everything / nothing.
  std::multiset<std::uint32_t> all;
  bvh.visit([](const Aabb&) { return true; }, [&](std::uint32_t slot) { all.insert(slot); });
  EXPECT_EQ(all.size(), s.triangles.size());
  EXPECT_EQ(std::set<std::uint32_t>(all.begin(), all.end()).size(), s.triangles.size());
  int none = 0;
  bvh.visit([](const Aabb&) { return false; }, [&](std::uint32_t) { ++none; });
  EXPECT_EQ(none, 0);
}

void expectInvalid(const BvhConfig& config, const std::string& field, const std::string& value) {
  expectMentions(invalidMessage([&] { config.validate(); }), {field, value});
  // build() validates too.
  const std::vector<Eigen::Vector3d> v = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0),
                                          Eigen::Vector3d(0, 1, 0)};
  EXPECT_THROW(Bvh::build(v, {{0, 1, 2}}, config), std::invalid_argument);
}

TEST(BvhConfig, ValidateNamesFieldAndValue) {
  BvhConfig ok;
  EXPECT_NO_THROW(ok.validate());
  BvhConfig c;
  c.max_leaf_size = 0;
  expectInvalid(c, "max_leaf_size", "0");
  c = BvhConfig{};
  c.max_leaf_size = -3;
  expectInvalid(c, "max_leaf_size", "-3");
  c = BvhConfig{};
  c.bins = 1;
  expectInvalid(c, "bins", "1");
  c.bins = 257;
  expectInvalid(c, "bins", "257");
  c = BvhConfig{};
  c.traversal_cost = -0.5;
  expectInvalid(c, "traversal_cost", "-0.5");
  c.traversal_cost = std::nan("");
  expectInvalid(c, "traversal_cost", "nan");
  c.traversal_cost = kInf;
  expectInvalid(c, "traversal_cost", "inf");
  c = BvhConfig{};
  c.max_depth = 0;
  expectInvalid(c, "max_depth", "0");
  c.max_depth = 63;
  expectInvalid(c, "max_depth", "63");
  // The boundaries are accepted.
  for (const int bins : {2, 256}) {
    c = BvhConfig{};
    c.bins = bins;
    EXPECT_NO_THROW(c.validate());
  }
  for (const int depth : {1, 62}) {
    c = BvhConfig{};
    c.max_depth = depth;
    EXPECT_NO_THROW(c.validate());
  }
  c = BvhConfig{};
  c.threads = -1;
  expectInvalid(c, "threads", "-1");
  c.threads = -2;
  expectInvalid(c, "threads", "-2");
  c.threads = 1025;
  expectInvalid(c, "threads", "1025");
  c = BvhConfig{};
  c.max_leaf_size = 1;
  c.traversal_cost = 0;
  c.threads = 1024;
  EXPECT_NO_THROW(c.validate());
  c.threads = 0;  // every core
  EXPECT_NO_THROW(c.validate());
}

}  // namespace
}  // namespace laser_raycast_test
