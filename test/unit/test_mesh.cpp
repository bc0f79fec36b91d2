// Mesh: construction rejects bad input with a message naming it; the bounding sphere and the
// triangle normals against values computed here.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "expect_invalid.h"
#include "laser_raycast/core/mesh.h"
#include "random.h"
#include "triangle_soup.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

constexpr double kInf = std::numeric_limits<double>::infinity();

// The message with which the Mesh constructor rejects (v, t).
std::string meshMessage(std::vector<Eigen::Vector3d> v, std::vector<TriangleIndices> t) {
  return invalidMessage([&] { Mesh mesh(std::move(v), std::move(t)); });
}

TEST(Mesh, RejectsBadInput) {
  const std::vector<Eigen::Vector3d> v = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0),
                                          Eigen::Vector3d(0, 1, 0)};
  EXPECT_NE(meshMessage(v, {}).find("no triangles"), std::string::npos);

  auto with = [&](int index, double value) {
    auto bad = v;
    bad[index].y() = value;
    return bad;
  };
  const std::string nan_msg = meshMessage(with(1, std::nan("")), {{0, 1, 2}});
  EXPECT_NE(nan_msg.find("vertex 1"), std::string::npos) << nan_msg;
  EXPECT_NE(nan_msg.find("nan"), std::string::npos) << nan_msg;
  const std::string inf_msg = meshMessage(with(2, -kInf), {{0, 1, 2}});
  EXPECT_NE(inf_msg.find("vertex 2"), std::string::npos) << inf_msg;
  EXPECT_NE(inf_msg.find("inf"), std::string::npos) << inf_msg;

  const std::string range_msg = meshMessage(v, {{0, 1, 2}, {0, 3, 1}});
  EXPECT_NE(range_msg.find("triangle 1"), std::string::npos) << range_msg;
  EXPECT_NE(range_msg.find("vertex 3"), std::string::npos) << range_msg;

  const std::string degenerate_msg = meshMessage(v, {{0, 0, 1}, {2, 2, 2}});
  EXPECT_NE(degenerate_msg.find("2 triangles"), std::string::npos) << degenerate_msg;
  EXPECT_NE(degenerate_msg.find("zero area"), std::string::npos) << degenerate_msg;

  EXPECT_NO_THROW(Mesh(v, {{0, 1, 2}}));
}

// The bounding sphere holds every vertex, near the origin and far from it, small and large.
// A mesh keeps only its wide BVH's tree: the binary tree's queries throw and say where to go, and
// Mesh::visit reaches every slot once, and every slot whose triangle meets a query's region.
TEST(Mesh, KeepsOnlyTheWideTreeAndVisitsThroughIt) {
  Rng rng(61);
  const Soup s = clusteredSoup(rng, 3000);
  const Mesh mesh(s.vertices, s.triangles);
  EXPECT_FALSE(mesh.bvh().hasTree());
  EXPECT_THROW(mesh.bvh().closestHit<TriangleMethod::kWatertight>(Ray()), std::logic_error);
  try {
    mesh.bvh().visit([](const Aabb&) { return true; }, [](std::uint32_t) {});
    ADD_FAILURE() << "visit on a released tree did not throw";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("Mesh::visit"), std::string::npos) << e.what();
  }
  const std::size_t slots = mesh.bvh().triangleIds().size();
  std::vector<int> seen(slots, 0);
  mesh.visit([](const Aabb&) { return true; }, [&](std::uint32_t slot) { ++seen[slot]; });
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), static_cast<long>(slots));
  // Slabs of z: every slot whose triangle reaches into the slab is visited (the boxes contain
  // their triangles), and a thin slab skips most of the others.
  const auto& tris = mesh.bvh().triangleVertices();
  for (int i = 0; i < 20; ++i) {
    const double lo = uniform(rng, mesh.bounds().lo.z(), mesh.bounds().hi.z());
    const double hi = lo + 0.01 * (mesh.bounds().hi.z() - mesh.bounds().lo.z());
    std::vector<char> visited(slots, 0);
    mesh.visit([&](const Aabb& box) { return box.hi.z() >= lo && box.lo.z() <= hi; },
               [&](std::uint32_t slot) { visited[slot] = 1; });
    std::size_t meets = 0, missed = 0, extra = 0;
    for (std::size_t slot = 0; slot < slots; ++slot) {
      double z_lo = kInf, z_hi = -kInf;
      for (const auto& v : tris[slot]) {
        z_lo = std::min(z_lo, v.z());
        z_hi = std::max(z_hi, v.z());
      }
      const bool meet = z_hi >= lo && z_lo <= hi;
      meets += meet;
      missed += meet && !visited[slot];
      extra += !meet && visited[slot];
    }
    EXPECT_EQ(missed, 0u) << "slab " << lo << " .. " << hi;
    EXPECT_LT(extra, slots / 2) << "slab " << lo << " .. " << hi << ", " << meets << " meet it";
  }
}

// Whether every slot holds, bit for bit, the vertices of its triangle.
::testing::AssertionResult slotsHoldTheVertices(const Mesh& mesh) {
  const auto& slots = mesh.bvh().triangleVertices();
  const auto& ids = mesh.bvh().triangleIds();
  for (std::uint32_t slot = 0; slot < slots.size(); ++slot) {
    const auto tri = slots[slot];
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& v = mesh.vertices()[mesh.triangles()[ids[slot]][k]];
      if (std::memcmp(tri[k].data(), v.data(), sizeof(double) * 3) != 0) {
        return ::testing::AssertionFailure() << "slot " << slot << " vertex " << k << " holds "
                                             << tri[k].transpose() << ", not " << v.transpose();
      }
    }
  }
  return ::testing::AssertionSuccess();
}

// Whether the mesh gives back exactly the vertices it was built from, bit for bit.
::testing::AssertionResult holdsTheVertices(const Mesh& mesh,
                                            const std::vector<Eigen::Vector3d>& vertices) {
  if (mesh.vertices().size() != vertices.size()) {
    return ::testing::AssertionFailure()
           << mesh.vertices().size() << " vertices, not " << vertices.size();
  }
  const std::vector<Eigen::Vector3d> all = mesh.vertices().toVector();
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const Eigen::Vector3d v = mesh.vertices()[i];
    if (std::memcmp(v.data(), vertices[i].data(), sizeof(double) * 3) != 0 ||
        std::memcmp(all[i].data(), vertices[i].data(), sizeof(double) * 3) != 0) {
      return ::testing::AssertionFailure()
             << "vertex " << i << " is " << v.transpose() << ", not " << vertices[i].transpose();
    }
  }
  return ::testing::AssertionSuccess();
}

// A mesh read from a file has float coordinates, scaled: its vertices and its slots keep them in
// float, half the bytes, and give back the same doubles; any other mesh keeps them in double.
TEST(Mesh, KeepsSlotsInFloatOnlyWhenThatLosesNothing) {
  Rng rng(73);
  const Soup s = clusteredSoup(rng, 3000);
  const Mesh doubles(s.vertices, s.triangles);
  EXPECT_FALSE(doubles.bvh().triangleVertices().packed());
  EXPECT_FALSE(doubles.vertices().packed());
  EXPECT_TRUE(slotsHoldTheVertices(doubles));
  EXPECT_TRUE(holdsTheVertices(doubles, s.vertices));

  // As an STL file gives them (floats), and scaled per axis as a URDF's <mesh scale> does.
  const Eigen::Vector3d scale(0.001, 0.0254, 2.5);
  std::vector<Eigen::Vector3d> read, scaled;
  for (const Eigen::Vector3d& v : s.vertices) {
    read.emplace_back(keptFloat(v.x()), keptFloat(v.y()), keptFloat(v.z()));
    scaled.push_back(read.back().cwiseProduct(scale));
  }
  const Mesh floats(read, s.triangles);
  EXPECT_TRUE(floats.bvh().triangleVertices().packed());
  EXPECT_TRUE(floats.vertices().packed());
  EXPECT_TRUE(slotsHoldTheVertices(floats));
  EXPECT_TRUE(holdsTheVertices(floats, read));
  const Mesh scaled_floats(scaled, s.triangles, BvhConfig{}, scale);
  EXPECT_TRUE(scaled_floats.bvh().triangleVertices().packed());
  EXPECT_TRUE(scaled_floats.vertices().packed());
  EXPECT_TRUE(slotsHoldTheVertices(scaled_floats));
  EXPECT_TRUE(holdsTheVertices(scaled_floats, scaled));

  // The same vertices with a scale they were not read with, or none that can be: in double, and
  // the only difference in bytes is the slots' (36 a slot: nine floats instead of nine doubles)
  // and the vertices' (12 a vertex).
  for (const Eigen::Vector3d& wrong :
       {Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(0.001, 0.0254, 2.6),
        Eigen::Vector3d(0.001, 0, 2.5), Eigen::Vector3d(0.001, -0.0254, 2.5),
        Eigen::Vector3d(0.001, 0.0254, std::nan(""))}) {
    const Mesh unpacked(scaled, s.triangles, BvhConfig{}, wrong);
    EXPECT_FALSE(unpacked.bvh().triangleVertices().packed()) << wrong.transpose();
    EXPECT_FALSE(unpacked.vertices().packed()) << wrong.transpose();
    EXPECT_TRUE(slotsHoldTheVertices(unpacked));
    EXPECT_TRUE(holdsTheVertices(unpacked, scaled));
    EXPECT_EQ(unpacked.bytes() - scaled_floats.bytes(),
              36 * unpacked.bvh().triangleIds().size() + 12 * scaled.size());
  }
  // A vertex that no triangle uses and that is not a float: the slots are kept in float, the
  // vertices (which hold it too) in double.
  std::vector<Eigen::Vector3d> with_unused = scaled;
  with_unused.emplace_back(0.1, 0.2, 0.3);
  const Mesh unused_double(with_unused, s.triangles, BvhConfig{}, scale);
  EXPECT_TRUE(unused_double.bvh().triangleVertices().packed());
  EXPECT_FALSE(unused_double.vertices().packed());
  EXPECT_TRUE(holdsTheVertices(unused_double, with_unused));
  // What a mesh holds, counted: 3000 triangles cannot fit in fewer bytes than their slots.
  EXPECT_GT(scaled_floats.bytes(), 36 * 3000u + 12 * 3000u);
  EXPECT_LT(scaled_floats.bytes(), doubles.bytes());
}

TEST(Mesh, BoundingSphereContainsEveryVertex) {
  Rng rng(17);
  for (const double offset : {0.0, 1e6, -3.7e7}) {
    for (const double scale : {1e-4, 1.0, 1e3}) {
      Soup s = clusteredSoup(rng, 200);
      for (auto& p : s.vertices) p = p * scale + Eigen::Vector3d::Constant(offset);
      const Mesh mesh(s.vertices, s.triangles);
      ASSERT_GT(mesh.sphereRadius(), 0);
      double farthest = 0;
      for (const auto& p : s.vertices) {
        const double d = (p - mesh.sphereCenter()).norm();
        farthest = std::max(farthest, d);
        EXPECT_LE(d, mesh.sphereRadius()) << "offset " << offset << " scale " << scale;
      }
      // Radius to the farthest vertex, not some loose bound: within 1e-12 relative.
      EXPECT_LE(mesh.sphereRadius(), farthest * (1 + 1e-12));
      for (int k = 0; k < 3; ++k) {
        EXPECT_LE(mesh.bounds().lo[k], mesh.sphereCenter()[k]);
        EXPECT_GE(mesh.bounds().hi[k], mesh.sphereCenter()[k]);
      }
    }
  }
}

// normal(): (b - a) x (c - a) normalised; the winding decides the side.
TEST(Mesh, Normal) {
  const std::vector<Eigen::Vector3d> v = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2, 0, 0),
                                          Eigen::Vector3d(0, 3, 0), Eigen::Vector3d(0, 0, 5)};
  const Mesh mesh(v, {{0, 1, 2}, {0, 2, 1}, {0, 1, 3}, {0, 3, 2}});
  EXPECT_EQ(mesh.normal(0), Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(mesh.normal(1), Eigen::Vector3d(0, 0, -1));
  EXPECT_EQ(mesh.normal(2), Eigen::Vector3d(0, -1, 0));
  EXPECT_EQ(mesh.normal(3), Eigen::Vector3d(-1, 0, 0));

  Rng rng(4);
  const Soup s = spreadSoup(rng, 100);
  const Mesh random(s.vertices, s.triangles);
  for (std::uint32_t i = 0; i < s.triangles.size(); ++i) {
    const auto& t = s.triangles[i];
    const Eigen::Vector3d n = random.normal(i);
    EXPECT_NEAR(n.norm(), 1.0, 1e-15);
    const Eigen::Vector3d e1 = s.vertices[t[1]] - s.vertices[t[0]];
    const Eigen::Vector3d e2 = s.vertices[t[2]] - s.vertices[t[0]];
    EXPECT_NEAR(n.dot(e1), 0.0, 1e-12 * e1.norm());
    EXPECT_NEAR(n.dot(e2), 0.0, 1e-12 * e2.norm());
    EXPECT_GT(n.dot(e1.cross(e2)), 0);
  }
}

}  // namespace
}  // namespace laser_raycast_test
