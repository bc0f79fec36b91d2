// WideBvh and WideRay: the 4-wide BVH's structure (every triangle slot in exactly one leaf, boxes
// that contain their subtrees, groups in whole subtrees) and its traversal against brute force, for
// every triangle method, with rays aimed at box faces and edges where rounding decides.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <tuple>
#include <vector>

#include "accel/wide_bvh.h"
#include "laser_raycast/core/mesh.h"
#include "mesh_builder.h"
#include "random.h"
#include "test_geometry.h"
#include "triangle_soup.h"
#include "wide_bvh_groups.h"
#include "wide_ray.h"

namespace laser_raycast_test {
namespace {

using core::Bvh;
using core::MeshHit;
using core::TriangleMethod;
using core::WideBvh;

constexpr double kInf = std::numeric_limits<double>::infinity();

// Walks the tree from the root with each subtree's box; fn(slot, box) for every slot.
template <class Fn>
void forEachSlot(const WideBvh& w, Fn&& fn) {
  struct Item {
    WideBvh::Ref ref;
    Eigen::Vector3d lo, hi;
  };
  const core::Aabb& b = w.binary().bounds();
  std::vector<Item> todo{{w.root(), b.lo, b.hi}};
  while (!todo.empty()) {
    const Item item = todo.back();
    todo.pop_back();
    if (item.ref.isLeaf()) {
      for (std::uint32_t s = item.ref.index; s < item.ref.index + item.ref.count; ++s) {
        fn(s, item.lo, item.hi);
      }
      continue;
    }
    const WideBvh::Node& node = w.nodes()[item.ref.index];
    for (int k = 0; k < WideBvh::kWidth; ++k) {
      if (node.index[k] == WideBvh::kEmpty) continue;
      const Eigen::Vector3d lo(node.lo[0][k], node.lo[1][k], node.lo[2][k]);
      const Eigen::Vector3d hi(node.hi[0][k], node.hi[1][k], node.hi[2][k]);
      // A child's box lies within its parent's (both rounded outward from exact bounds).
      EXPECT_TRUE((lo.array() >= item.lo.array() - 1e-6 * (1 + item.lo.array().abs())).all());
      todo.push_back({node.child(k), lo, hi});
    }
  }
}

TEST(WideBvh, EverySlotOnceInsideItsBoxes) {
  Rng rng(11);
  for (const int n : {1, 2, 7, 300, 5000}) {
    const Soup s = n % 2 ? spreadSoup(rng, n) : clusteredSoup(rng, n);
    const core::Mesh mesh(s.vertices, s.triangles);
    const WideBvh& w = mesh.wideBvh();
    std::vector<int> seen(mesh.bvh().triangleIds().size(), 0);
    forEachSlot(w, [&](std::uint32_t slot, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
      ++seen[slot];
      for (const auto& v : mesh.bvh().triangleVertices()[slot]) {
        EXPECT_TRUE((v.array() >= lo.array()).all() && (v.array() <= hi.array()).all())
            << "slot " << slot << " vertex " << v.transpose();
      }
    });
    for (std::size_t slot = 0; slot < seen.size(); ++slot) EXPECT_EQ(seen[slot], 1) << slot;
    if (n > 100) {
      EXPECT_LT(w.nodes().size(), seen.size());  // four-wide: fewer nodes than slots
    }
  }
}

// Prisms that do not touch: one component each. Every subtree below a node with one group holds
// only that group's triangles, and the group tags say so.
TEST(WideBvh, ComponentsFillWholeSubtrees) {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<core::TriangleIndices> triangles;
  Rng rng(5);
  for (int k = 0; k < 40; ++k) {
    const auto prism = makePrism(circle(12, uniform(rng, 0.1, 0.4)), {-1.0, 0.0, 1.0, 2.0});
    const Eigen::Vector3d at(uniform(rng, -20, 20), uniform(rng, -20, 20), 0);
    const auto base = static_cast<std::uint32_t>(vertices.size());
    for (const auto& v : prism.vertices) vertices.push_back(v + at);
    for (auto t : prism.triangles) triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  const core::Mesh mesh(vertices, triangles);
  ASSERT_EQ(mesh.componentCount(), 40u);
  const WideBvh& w = mesh.wideBvh();
  const auto& ids = mesh.bvh().triangleIds();
  const std::vector<std::uint32_t> components = mesh.components();
  int tagged = 0;
  for (std::uint32_t n = 0; n < w.nodes().size(); ++n) {
    for (int k = 0; k < WideBvh::kWidth; ++k) {
      const std::int32_t group = childGroup(mesh, components, n, k);
      if (group < 0 || w.nodes()[n].index[k] == WideBvh::kEmpty) continue;
      ++tagged;
      // Every slot below carries that group.
      std::vector<WideBvh::Ref> todo{w.nodes()[n].child(k)};
      std::uint32_t count = 0;
      while (!todo.empty()) {
        const WideBvh::Ref r = todo.back();
        todo.pop_back();
        if (r.isLeaf()) {
          for (std::uint32_t s = r.index; s < r.index + r.count; ++s, ++count) {
            EXPECT_EQ(components[ids[s]], static_cast<std::uint32_t>(group));
          }
          continue;
        }
        for (int j = 0; j < WideBvh::kWidth; ++j) {
          if (w.nodes()[r.index].index[j] != WideBvh::kEmpty) {
            todo.push_back(w.nodes()[r.index].child(j));
          }
        }
      }
      EXPECT_EQ(count, w.childTriangles(n, k));
    }
  }
  EXPECT_GT(tagged, 40);
  // The counts ride in the nodes' count fields: the root's is every slot, and an inner child is
  // never taken for a leaf.
  EXPECT_EQ(w.rootTriangles(), mesh.bvh().triangleIds().size());
  EXPECT_FALSE(w.root().isLeaf());
  for (std::int32_t g = 0; g < 40; ++g) EXPECT_FALSE(groupInMixedLeaf(mesh, components, g));
}

template <TriangleMethod M>
std::optional<MeshHit> wideHit(const core::Mesh& mesh, const core::Ray& ray) {
  const WideBvh& w = mesh.wideBvh();
  const core::WideRay<M> wide(ray, false, mesh.bvh().bounds());
  const core::Aabb& b = mesh.bvh().bounds();
  float lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = core::floatBelow(b.lo[a]);
    hi[a] = core::floatAbove(b.hi[a]);
  }
  double tmax = ray.tmax;
  std::optional<MeshHit> best;
  wide.closestHit(w, w.root(), lo, hi, &tmax, &best);
  return best;
}

// The same nearest distance as brute force (which triangle, where two are as near, may differ:
// the wide walk keeps the lower index, brute force the last one it tried).
template <TriangleMethod M>
void expectLikeBruteForce(const core::Mesh& mesh, const core::Ray& ray) {
  const auto wide = wideHit<M>(mesh, ray);
  const auto brute =
      core::bruteForceClosestHit(M, mesh.vertices().toVector(), mesh.triangles(), ray, false);
  ASSERT_EQ(wide.has_value(), brute.has_value())
      << core::toString(M) << " origin " << ray.origin.transpose() << " dir "
      << ray.dir.transpose();
  if (wide) {
    EXPECT_EQ(wide->t, brute->t) << core::toString(M);
    const auto& t = mesh.triangles()[wide->triangle];
    const auto again = core::intersectTriangle<M>(ray, mesh.vertices()[t[0]], mesh.vertices()[t[1]],
                                                  mesh.vertices()[t[2]]);
    ASSERT_TRUE(again.has_value());
    EXPECT_EQ(again->t, wide->t);
  }
}

// The collapse spreads a small subtree over its parent's free slots where that costs less than a
// node of its own: on a terrain and a wood of cylinders (what the bench's scenes are made of) the
// nodes hold over three children on average. (The greedy collapse it replaced, which opened the
// largest child until four, held 3.13 on this terrain and 2.98 on this wood; 3.17 and 3.26 now.)
TEST(WideBvh, NodesAreWellFilled) {
  std::vector<Eigen::Vector3d> terrain;
  std::vector<core::TriangleIndices> cells;
  const int n = 100;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; j <= n; ++j) {
      terrain.emplace_back(i * 0.5, j * 0.5, 0.3 * std::sin(i * 0.37) * std::cos(j * 0.23));
    }
  }
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const auto v = static_cast<std::uint32_t>(i * (n + 1) + j);
      cells.push_back({v, v + n + 1, v + n + 2});
      cells.push_back({v, v + n + 2, v + 1});
    }
  }
  std::vector<Eigen::Vector3d> wood;
  std::vector<core::TriangleIndices> trunks;
  Rng rng(11);
  for (int k = 0; k < 40; ++k) {
    const auto trunk = makePrism(circle(24, uniform(rng, 0.1, 0.4)), steps(0, 10, 20));
    const Eigen::Vector3d at(uniform(rng, -20, 20), uniform(rng, -20, 20), 0);
    const auto base = static_cast<std::uint32_t>(wood.size());
    for (const auto& v : trunk.vertices) wood.push_back(v + at);
    for (auto t : trunk.triangles) trunks.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  for (const auto& [vertices, triangles, least] :
       {std::tuple{terrain, cells, 3.05}, std::tuple{wood, trunks, 3.15}}) {
    const core::Mesh mesh(vertices, triangles);
    const WideBvh& w = mesh.wideBvh();
    std::size_t children = 0;
    for (const WideBvh::Node& node : w.nodes()) {
      for (int k = 0; k < WideBvh::kWidth; ++k) children += node.index[k] != WideBvh::kEmpty;
    }
    const double fill = static_cast<double>(children) / w.nodes().size();
    EXPECT_GT(fill, least) << triangles.size() << " triangles, " << w.nodes().size() << " nodes";
  }
}

TEST(WideRay, NearestHitEqualsBruteForceForEveryMethod) {
  Rng rng(17);
  int hits = 0;
  for (int scene = 0; scene < 6; ++scene) {
    const Soup s = scene % 2 ? spreadSoup(rng, 800) : clusteredSoup(rng, 800);
    const core::Mesh mesh(s.vertices, s.triangles);
    for (int i = 0; i < 300; ++i) {
      core::Ray ray;
      ray.origin = uniformInCube(rng, 14);
      // Aim at a vertex or a point of a triangle half of the time: hits, edges and corners.
      const auto& tri = s.triangles[static_cast<std::size_t>(i) % s.triangles.size()];
      const Eigen::Vector2d uv = randomBarycentrics(rng);
      const Eigen::Vector3d target = i % 3 == 0 ? s.vertices[tri[0]]
                                                : (1 - uv.x() - uv.y()) * s.vertices[tri[0]] +
                                                      uv.x() * s.vertices[tri[1]] +
                                                      uv.y() * s.vertices[tri[2]];
      ray.dir = i % 2 ? (target - ray.origin).normalized() : randomUnitVector(rng);
      ray.tmin = i % 5 == 0 ? uniform(rng, 0, 3) : 0.0;
      ray.tmax = i % 4 == 0 ? uniform(rng, 1, 40) : kInf;
      expectLikeBruteForce<TriangleMethod::kWatertight>(mesh, ray);
      expectLikeBruteForce<TriangleMethod::kMollerTrumbore>(mesh, ray);
      expectLikeBruteForce<TriangleMethod::kCramer>(mesh, ray);
      expectLikeBruteForce<TriangleMethod::kSeedPlane>(mesh, ray);
      expectLikeBruteForce<TriangleMethod::kSeedUv>(mesh, ray);
      hits += wideHit<TriangleMethod::kWatertight>(mesh, ray).has_value();
      if (HasFailure()) return;
    }
  }
  EXPECT_GT(hits, 600);
}

// Two rays walked side by side (traceWidePair) visit the same leaves in the same order, and keep
// the same nearest hits, as each walked alone (traceWide).
TEST(WideWalk, APairOfWalksVisitsWhatEachWalkAloneVisits) {
  Rng rng(29);
  int hits = 0;
  for (int scene = 0; scene < 4; ++scene) {
    const Soup s = scene % 2 ? spreadSoup(rng, 800) : clusteredSoup(rng, 800);
    const core::Mesh mesh(s.vertices, s.triangles);
    const WideBvh& w = mesh.wideBvh();
    const auto& slots = mesh.bvh().triangleVertices();
    struct Walked {
      std::vector<std::uint32_t> visits;
      double tmax;
      std::optional<double> t;
    };
    for (int i = 0; i < 200; ++i) {
      core::Ray rays[2];
      const Eigen::Vector3d origin = uniformInCube(rng, 14);
      for (core::Ray& ray : rays) {
        ray.origin = origin;
        ray.dir = randomUnitVector(rng);
        ray.tmin = 0;
        ray.tmax = i % 4 == 0 ? uniform(rng, 1, 40) : kInf;
      }
      // (The boxes' rays are built from each ray alone: the pair shares nothing but the tree.)
      const core::WideBoxRay box[2] = {core::WideBoxRay(rays[0], mesh.bvh().bounds()),
                                       core::WideBoxRay(rays[1], mesh.bvh().bounds())};
      const core::PreparedRay<double, TriangleMethod::kWatertight> prepared[2] = {
          core::PreparedRay<double, TriangleMethod::kWatertight>(rays[0], false),
          core::PreparedRay<double, TriangleMethod::kWatertight>(rays[1], false)};
      auto leaf = [&](int k, Walked* walked) {
        return [&, k, walked](std::uint32_t slot) {
          walked->visits.push_back(slot);
          const auto& v = slots[slot];
          const auto hit = prepared[k].intersect(v[0], v[1], v[2], walked->tmax);
          if (hit && (!walked->t || hit->t < *walked->t)) {
            walked->t = hit->t;
            walked->tmax = hit->t;
          }
        };
      };
      Walked alone[2], paired[2];
      for (int k = 0; k < 2; ++k) {
        alone[k].tmax = paired[k].tmax = rays[k].tmax;
        core::traceWide(w, w.root(), box[k], &alone[k].tmax, leaf(k, &alone[k]));
      }
      core::traceWidePair(w, w.root(), box[0], &paired[0].tmax, leaf(0, &paired[0]), box[1],
                          &paired[1].tmax, leaf(1, &paired[1]));
      for (int k = 0; k < 2; ++k) {
        ASSERT_EQ(alone[k].visits, paired[k].visits) << "ray " << k << " of pair " << i;
        ASSERT_EQ(alone[k].t, paired[k].t) << "ray " << k << " of pair " << i;
        hits += alone[k].t.has_value();
      }
    }
  }
  EXPECT_GT(hits, 100);
}

// Axis-aligned rays and rays lying exactly in box faces (the float boxes are rounded outward, and
// a ray in a slab plane gives NaN there): a grid of axis-aligned squares, rays along the grid
// lines.
TEST(WideRay, AxisAlignedRaysInBoxFacesFindTheirHits) {
  const auto grid = gridBox(steps(-2, 2, 9), steps(-2, 2, 9), steps(-1, 1, 5), false);
  int hits = 0;
  for (const double y : steps(-2, 2, 9)) {
    for (const double z : steps(-1, 1, 5)) {
      for (const double sign : {1.0, -1.0}) {
        core::Ray ray;
        ray.origin = Eigen::Vector3d(0, y, z);
        ray.dir = Eigen::Vector3d(sign, 0, 0);
        expectLikeBruteForce<TriangleMethod::kWatertight>(*grid, ray);
        ray.origin = Eigen::Vector3d(y, 0.5 * z, 0);
        ray.dir = Eigen::Vector3d(0, 0, sign);
        expectLikeBruteForce<TriangleMethod::kWatertight>(*grid, ray);
        hits += wideHit<TriangleMethod::kWatertight>(*grid, ray).has_value();
      }
    }
  }
  EXPECT_GT(hits, 50);
}

// Regression (found by test/fuzz/fuzz_core, through a body scaled far down): a direction component
// beyond ~1e45 has a float reciprocal of 0, an empty child's box test gave NaN, which the test
// ignores, and the traversal went into the empty child (index kEmpty: far past the nodes). Long
// directions, in every axis and sign, against brute force on a tree with empty children.
TEST(WideRay, LongDirectionsNeverEnterEmptyChildren) {
  Rng rng(29);
  const Soup s = spreadSoup(rng, 300);
  const core::Mesh mesh(s.vertices, s.triangles);
  const auto& nodes = mesh.wideBvh().nodes();
  ASSERT_TRUE(std::any_of(nodes.begin(), nodes.end(), [](const WideBvh::Node& n) {
    return n.presentMask() != 0xF;
  })) << "the case needs a node with an empty child";
  int hits = 0;
  for (int i = 0; i < 400; ++i) {
    core::Ray ray;
    ray.origin = uniformInCube(rng, 14);
    const auto& tri = s.triangles[static_cast<std::size_t>(i) % s.triangles.size()];
    const Eigen::Vector3d target = i % 2 ? s.vertices[tri[0]] : uniformInCube(rng, 14);
    ray.dir = (target - ray.origin).normalized() * (i % 4 < 2 ? 1e50 : 1e300);
    if (i % 8 == 0) ray.dir[i / 8 % 3] = 0;  // zero components too: NaN from a slab plane
    expectLikeBruteForce<TriangleMethod::kWatertight>(mesh, ray);
    expectLikeBruteForce<TriangleMethod::kMollerTrumbore>(mesh, ray);
    hits += wideHit<TriangleMethod::kWatertight>(mesh, ray).has_value();
    if (HasFailure()) return;
  }
  EXPECT_GT(hits, 100);
}

TEST(FloatRounding, BelowAndAboveBracketTheDouble) {
  Rng rng(3);
  for (int i = 0; i < 100000; ++i) {
    const double x = (i % 2 ? 1 : -1) * std::pow(10.0, uniform(rng, -40, 38));
    const float lo = core::floatBelow(x), hi = core::floatAbove(x);
    EXPECT_LE(double(lo), x);
    EXPECT_GE(double(hi), x);
    EXPECT_LE(std::nextafter(lo, std::numeric_limits<float>::infinity()), hi);
  }
  EXPECT_EQ(core::floatBelow(0.0), 0.0f);
  EXPECT_EQ(core::floatBelow(1.0), 1.0f);
  EXPECT_LT(core::floatBelow(0.1), 0.1);
  EXPECT_GT(core::floatAbove(0.1), 0.1);
  EXPECT_TRUE(std::isnan(core::floatBelow(std::numeric_limits<double>::quiet_NaN())));
}

// floatBelow is the float nearest below, as std::nextafter steps to it, across every range of
// magnitudes: subnormals, signed zeros, beyond the largest float, infinities.
TEST(FloatRounding, BelowIsTheNearestFloatNotAbove) {
  const float kInf = std::numeric_limits<float>::infinity();
  auto reference = [&](double x) {
    const float f = static_cast<float>(x);
    return f > x ? std::nextafter(f, -kInf) : f;
  };
  auto same = [](float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  Rng rng(5);
  std::vector<double> xs = {0.0,
                            -0.0,
                            1e-46,
                            -1e-46,
                            1e-300,
                            -1e-300,
                            1e39,
                            -1e39,
                            3.5e38,
                            -3.5e38,
                            1e-38,
                            -1e-38,
                            0.1,
                            -0.1,
                            HUGE_VAL,
                            -HUGE_VAL,
                            double(std::numeric_limits<float>::max()),
                            double(std::numeric_limits<float>::denorm_min())};
  for (int i = 0; i < 200000; ++i) {
    xs.push_back((i % 2 ? 1 : -1) * std::pow(10.0, uniform(rng, -48, 40)));
  }
  for (double x : xs) {
    EXPECT_TRUE(same(core::floatBelow(x), reference(x))) << x;
    EXPECT_TRUE(same(core::floatAbove(x), -reference(-x))) << x;
  }
}

// A walk's cull limit (WideSlabRay::cullLimit) is never nearer than the far limit it is given,
// widened as the box tests need (by 64 epsilon of the limit and of the ray's reach), and at most a
// few floats beyond that: across subnormal, tiny, huge (beyond the floats: +inf) and negative
// limits.
TEST(FloatRounding, CullLimitIsNeverNearerThanTheWidenedLimit) {
  const float kFloatInf = std::numeric_limits<float>::infinity();
  const Eigen::Vector3d half(3, 2, 1);
  core::Ray ray;
  ray.origin = Eigen::Vector3d(0.5, -0.25, 0.125);
  ray.dir = Eigen::Vector3d(1, 2, 2).normalized();
  ray.tmin = 0;
  ray.tmax = kInf;
  core::Aabb bounds;
  bounds.grow(-half);
  bounds.grow(half);
  const core::WideBoxRay box(ray, bounds);
  // The reach the ray works with: the largest coordinate distance from its origin to the box (3.5,
  // along x) over the largest component of its direction.
  const double reach = 3.5 / ray.dir.cwiseAbs().maxCoeff();
  Rng rng(9);
  std::vector<double> ts = {0.0, -0.0, 1e-46, -1e-46, 1e-300, 1e-38, 0.1, 1.0, 3e38, -5.0};
  for (int i = 0; i < 100000; ++i) {
    // (Negative limits below the largest float's negative round to -inf: nothing is entered.)
    ts.push_back(i % 8 ? std::pow(10.0, uniform(rng, -48, 39))
                       : -std::pow(10.0, uniform(rng, -48, 38)));
  }
  for (const double t : ts) {
    const double widened = t + (std::abs(t) + reach) * 64 * std::numeric_limits<double>::epsilon();
    const float cull = box.cullLimit(t);
    ASSERT_GE(double(cull), widened) << t;
    // Not looser than four floats above the widened limit.
    float bound = core::floatAbove(widened);
    for (int k = 0; k < 4; ++k) bound = std::nextafter(bound, kFloatInf);
    ASSERT_LE(cull, bound) << t;
  }
  EXPECT_EQ(box.cullLimit(kInf), kFloatInf);
  EXPECT_TRUE(std::isnan(box.cullLimit(std::numeric_limits<double>::quiet_NaN())));
}

// The children's order as indices (sortFarthestFirst over their distances) is the order a stable
// sort, farthest first, gives: ties keep their order, every index appears once. Random distances
// with many ties, 0 to 12 children.
TEST(ChildOrder, IndicesAreFarthestFirstAndStable) {
  Rng rng(17);
  for (int trial = 0; trial < 20000; ++trial) {
    const int n = trial % 13;
    float near[12];
    for (int j = 0; j < n; ++j) near[j] = static_cast<float>(std::floor(uniform(rng, 0, 4)));
    int order[12];
    core::sortFarthestFirst(near, order, n);
    std::vector<int> expected(n);
    for (int j = 0; j < n; ++j) expected[j] = j;
    std::stable_sort(expected.begin(), expected.end(),
                     [&](int a, int b) { return near[a] > near[b]; });
    ASSERT_TRUE(std::equal(expected.begin(), expected.end(), order)) << "trial " << trial;
  }
}

}  // namespace
}  // namespace laser_raycast_test
