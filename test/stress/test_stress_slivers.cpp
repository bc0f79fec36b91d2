// Stress case 4, slivers: strips and fans of thin triangles (aspect ratios 10^0..10^8), hit exactly
// at their shared edges and vertices, must neither leak nor double-hit nor yield NaN or Inf; also
// through the BVH, and through the Caster (a sliver wall across the scan plane).
// test_stress_degenerate.cpp has the zero-area and tiny triangles.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "laser_raycast/core/caster.h"
#include "slice_mesh.h"
#include "laser_raycast/core/mesh.h"
#include "laser_raycast/core/pose.h"
#include "random.h"
#include "stress_report.h"

namespace laser_raycast_test {
namespace {

using core::Vec3;
using Eigen::Vector3d;
constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------------------------------
// 4a. Sliver strips and fans.

// A flat mesh with its interior (shared by two triangles) edges and interior vertices (all of whose
// edges are interior): a ray through those crosses the surface exactly once.
struct Sliver {
  TriMesh mesh;
  std::vector<std::array<std::uint32_t, 2>> interior_edges;
  std::vector<std::uint32_t> interior_vertices;
  Vector3d normal;
};

void classify(Sliver* s) {
  std::map<std::array<std::uint32_t, 2>, int> uses;
  for (const auto& tri : s->mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      ++uses[{std::min(tri[k], tri[(k + 1) % 3]), std::max(tri[k], tri[(k + 1) % 3])}];
    }
  }
  std::vector<char> on_boundary(s->mesh.vertices.size(), 0);
  for (const auto& e : uses) {
    if (e.second == 2) s->interior_edges.push_back(e.first);
    if (e.second == 1) on_boundary[e.first[0]] = on_boundary[e.first[1]] = 1;
  }
  for (std::uint32_t v = 0; v < on_boundary.size(); ++v) {
    if (!on_boundary[v]) s->interior_vertices.push_back(v);
  }
}

// Three rows (y = -h, 0, h) of 17 vertices 1/16 apart, two triangles per cell (the diagonal
// alternating): 64 triangles of aspect ratio ~ (1/16) / h, the middle row's vertices interior.
Sliver sliverStrip(double aspect, const Eigen::Isometry3d& pose) {
  const int n = 16;
  const double w = 1.0 / n, h = w / aspect;
  Sliver s;
  for (int r = 0; r < 3; ++r) {
    for (int i = 0; i <= n; ++i) s.mesh.vertices.push_back(pose * Vector3d(i * w, (r - 1) * h, 0));
  }
  auto at = [&](int r, int i) { return static_cast<std::uint32_t>(r * (n + 1) + i); };
  for (int r = 0; r < 2; ++r) {
    for (int i = 0; i < n; ++i) {
      if ((r + i) % 2) {
        s.mesh.triangles.push_back({at(r, i), at(r, i + 1), at(r + 1, i + 1)});
        s.mesh.triangles.push_back({at(r, i), at(r + 1, i + 1), at(r + 1, i)});
      } else {
        s.mesh.triangles.push_back({at(r, i), at(r, i + 1), at(r + 1, i)});
        s.mesh.triangles.push_back({at(r, i + 1), at(r + 1, i + 1), at(r + 1, i)});
      }
    }
  }
  s.normal = pose.linear() * Vector3d::UnitZ();
  classify(&s);
  return s;
}

// 16 triangles fanned around an apex out to radius 1: the whole turn for aspect 1 (the apex
// interior), else a wedge of 16 / aspect rad (the spokes interior).
Sliver sliverFan(double aspect, const Eigen::Isometry3d& pose) {
  const int n = 16;
  const bool full = aspect <= 1;
  const double width = full ? 2 * M_PI : n / aspect;
  Sliver s;
  s.mesh.vertices.push_back(pose * Vector3d::Zero());
  const int rim = full ? n : n + 1;
  for (int j = 0; j < rim; ++j) {
    const double a = -width / 2 + width * j / n;
    s.mesh.vertices.push_back(pose * Vector3d(std::cos(a), std::sin(a), 0));
  }
  for (int j = 0; j < n; ++j) {
    s.mesh.triangles.push_back(
        {0, static_cast<std::uint32_t>(1 + j), static_cast<std::uint32_t>(1 + (j + 1) % rim)});
  }
  s.normal = pose.linear() * Vector3d::UnitZ();
  classify(&s);
  return s;
}

struct SliverTally {
  long rays = 0, leaks = 0, double_hits = 0, bvh_misses = 0, non_finite = 0;
};

// From two origins per target, 0.5..2 away and at least ~17 degrees off the surface: every
// interior vertex, and the midpoint and two random points of every interior edge.
template <TriangleMethod M, typename T>
void castSliver(const Sliver& s, const core::BvhT<T>& bvh, Rng& rng, SliverTally* t) {
  const auto v = castVertices<T>(s.mesh.vertices);
  auto cast = [&](const Vector3d& target_d, const Vec3<T>& target) {
    for (int k = 0; k < 2; ++k) {
      Vector3d e = randomUnitVector(rng);
      if (std::abs(e.dot(s.normal)) < 0.3)
        e = (e + s.normal * (e.dot(s.normal) < 0 ? -1 : 1)).normalized();
      core::RayT<T> ray;
      ray.origin = (target_d + uniform(rng, 0.5, 2.0) * e).cast<T>();
      ray.dir = target - ray.origin;
      int hits = 0;
      for (const auto& tri : s.mesh.triangles) {
        const auto hit = core::intersectTriangle<M>(ray, v[tri[0]], v[tri[1]], v[tri[2]]);
        if (!hit) continue;
        ++hits;
        t->non_finite += !(std::isfinite(hit->t) && std::isfinite(hit->u) && std::isfinite(hit->v));
      }
      ++t->rays;
      t->leaks += hits == 0;
      t->double_hits += hits > 1;
      t->bvh_misses += !bvh.template closestHit<M>(ray).has_value();
    }
  };
  for (const auto i : s.interior_vertices) cast(s.mesh.vertices[i], v[i]);
  for (const auto& e : s.interior_edges) {
    for (const double f : {0.5, uniform(rng, 0, 1), uniform(rng, 0, 1)}) {
      cast((1 - f) * s.mesh.vertices[e[0]] + f * s.mesh.vertices[e[1]],
           Vec3<T>(v[e[0]] + T(f) * (v[e[1]] - v[e[0]])));
    }
  }
}

TEST(StressSlivers, StripsAndFansNeitherLeakNorDoubleHit) {
  Rng rng(4001);
  const int kExponents = 9;
  std::vector<std::vector<SliverTally>> tallies(variants().size(),
                                                std::vector<SliverTally>(kExponents));
  for (int a = 0; a < kExponents; ++a) {
    const double aspect = std::pow(10.0, a);
    std::vector<Sliver> slivers;
    for (int p = 0; p < 3; ++p) {
      // The first pose is the identity (exact coordinates), the others random.
      const Eigen::Isometry3d pose = p == 0 ? Eigen::Isometry3d::Identity() : randomPose(rng, 2.0);
      slivers.push_back(sliverStrip(aspect, pose));
      slivers.push_back(sliverFan(aspect, pose));
    }
    for (const Sliver& s : slivers) {
      const core::Bvh bvh = core::Bvh::build(s.mesh.vertices, s.mesh.triangles);
      const core::BvhF bvh_f = core::BvhF::build(s.mesh.vertices, s.mesh.triangles);
      for (std::size_t vi = 0; vi < variants().size(); ++vi) {
        Rng ray_rng(4100 + a);  // the same rays for every variant
        dispatchVariant(variants()[vi], [&](auto m, auto x) {
          using T = decltype(x);
          castSliver<decltype(m)::value, T>(s, pick(bvh, bvh_f, T{}), ray_rng, &tallies[vi][a]);
        });
      }
    }
  }
  std::vector<std::string> header = {"method"};
  for (int a = 0; a < kExponents; ++a) header.push_back("10^" + std::to_string(a));
  header.push_back("BVH misses");
  header.push_back("NaN/Inf");
  Table t{"4a",
          "4a. Slivers: leaks / double hits by aspect ratio",
          "Per aspect ratio: 3 strips (2 rows of 16 cells, 64 slivers) and 3 fans (16 slivers "
          "round an apex), at the identity and two random poses; " +
              count(tallies[0][8].rays) +
              " rays per aspect ratio, from two origins per target at every interior vertex and "
              "three points of every interior edge, brute force. Asserted on production: 0 leaks, "
              "0 double hits, "
              "0 BVH misses, no NaN or Inf.",
          header,
          {}};
  for (std::size_t vi = 0; vi < variants().size(); ++vi) {
    std::vector<std::string> row = {variantName(variants()[vi])};
    long bvh_misses = 0, non_finite = 0;
    for (int a = 0; a < kExponents; ++a) {
      const SliverTally& s = tallies[vi][a];
      row.push_back(count(s.leaks) + " / " + count(s.double_hits));
      bvh_misses += s.bvh_misses;
      non_finite += s.non_finite;
    }
    row.push_back(count(bvh_misses));
    row.push_back(count(non_finite));
    t.addRow(row);
  }
  record(t);
  ASSERT_TRUE(isProduction(variants()[0]));
  for (int a = 0; a < kExponents; ++a) {
    const SliverTally& p = tallies[0][a];
    EXPECT_EQ(p.leaks, 0) << "aspect 1e" << a;
    EXPECT_EQ(p.double_hits, 0) << "aspect 1e" << a;
    EXPECT_EQ(p.bvh_misses, 0) << "aspect 1e" << a;
    EXPECT_EQ(p.non_finite, 0) << "aspect 1e" << a;
  }
}

// ---------------------------------------------------------------------------------------------------
// 4b. A wall of vertical slivers across the scan plane.

// Vertical slivers at x = 2: columns dy apart, rows at z = -1, 0 (the scan plane), 1.
TriMesh sliverWall(double dy, int columns) {
  TriMesh m;
  for (const double z : {-1.0, 0.0, 1.0}) {
    for (int i = 0; i <= columns; ++i) m.vertices.emplace_back(2.0, (i - columns / 2.0) * dy, z);
  }
  auto at = [&](int r, int i) { return static_cast<std::uint32_t>(r * (columns + 1) + i); };
  for (int r = 0; r < 2; ++r) {
    for (int i = 0; i < columns; ++i) {
      const std::uint32_t p00 = at(r, i), p10 = at(r, i + 1), p01 = at(r + 1, i),
                          p11 = at(r + 1, i + 1);
      if ((r + i) % 2) {  // the diagonal alternates, so vertex valences vary
        m.triangles.push_back({p00, p10, p11});
        m.triangles.push_back({p00, p11, p01});
      } else {
        m.triangles.push_back({p00, p10, p01});
        m.triangles.push_back({p10, p11, p01});
      }
    }
  }
  return m;
}

// The fan spans the inner 98% of the wall's angular width, so every beam must hit it: the fast
// path's slice is a polyline of sliver cuts (with the middle row exactly in the plane), the
// per-beam path tests the slivers themselves.
TEST(StressSlivers, WallAcrossTheScanPlane) {
  Rng rng(4201);
  const int kExponents = 9, columns = 32;
  std::vector<long> fast(kExponents), crossing_errors(kExponents);
  std::vector<std::vector<long>> per_beam(core::kAllTriangleMethods.size(),
                                          std::vector<long>(kExponents));
  long beams = 0;
  for (int a = 0; a < kExponents; ++a) {
    const double dy = std::pow(10.0, -a);  // aspect ratio (height 1) / dy
    const TriMesh wall = sliverWall(dy, columns);
    auto mesh = std::make_shared<const core::Mesh>(wall.vertices, wall.triangles);
    core::Scene scene;
    core::Body body;
    body.frame = scene.addFrame("wall");
    body.label = scene.addLabel("wall");
    body.shape = mesh;
    scene.addBody(body);
    for (int s = 0; s < 4; ++s) {
      // Yaw only, so the middle row stays exactly in the plane z = 0.
      const double yaw = s == 0 ? 0.0 : uniform(rng, -M_PI, M_PI);
      core::FramePoses poses = core::FramePoses::identity(scene);
      poses.pose[0].linear() = Eigen::AngleAxisd(yaw, Vector3d::UnitZ()).toRotationMatrix();
      const double half = 0.98 * std::atan(columns * dy / 2 / 2.0);
      const core::ScanPattern pattern(core::FanSpec{yaw - half, yaw + half, 0, 501});
      const Eigen::Isometry3d sensor = Eigen::Isometry3d::Identity();
      core::Caster caster;
      core::CastConfig config;
      const core::ScanResult& r = caster.cast(scene, poses, sensor, pattern, config);
      std::vector<double> range(pattern.size(), kInf);
      std::vector<int> body_hit(pattern.size(), -1), triangle(pattern.size(), -1),
          crossings(pattern.size(), 0);
      core::sliceMesh(*mesh, core::relativePose(sensor, poses.pose[0]), pattern, 0.0, kInf, false,
                      0, core::DepthBuffer{&range, &body_hit, &triangle, &crossings});
      for (int i = 0; i < pattern.size(); ++i) {
        fast[a] += !std::isfinite(r.range[i]);
        crossing_errors[a] += crossings[i] != 1;
      }
      beams += pattern.size();
      for (std::size_t mi = 0; mi < core::kAllTriangleMethods.size(); ++mi) {
        config.method = core::kAllTriangleMethods[mi];
        config.planar_fast_path = false;
        const core::ScanResult& b = caster.cast(scene, poses, sensor, pattern, config);
        for (int i = 0; i < pattern.size(); ++i) per_beam[mi][a] += !std::isfinite(b.range[i]);
      }
    }
  }
  std::vector<std::string> header = {"method"};
  for (int a = 0; a < kExponents; ++a) header.push_back("10^" + std::to_string(a));
  Table t{"4b",
          "4b. Slivers through the Caster: beams that miss a sliver wall",
          "A wall of 32 columns x 2 rows of vertical slivers (height 1 m, width 10^-a m) 2 m away, "
          "its middle vertex row in the scan plane, at 4 yaws; 501 beams over the inner 98% of "
          "its width (" +
              count(beams / kExponents) +
              " beams per aspect ratio). Fast path: misses, and beams whose sliceMesh crossing "
              "count is not exactly 1 (in brackets). Per-beam Caster: misses, each method in "
              "double. Asserted on production: all 0.",
          header,
          {}};
  std::vector<std::string> row = {"Caster fast path (production)"};
  for (int a = 0; a < kExponents; ++a)
    row.push_back(count(fast[a]) + " (" + count(crossing_errors[a]) + ")");
  t.addRow(row);
  for (std::size_t mi = 0; mi < core::kAllTriangleMethods.size(); ++mi) {
    const TriangleMethod m = core::kAllTriangleMethods[mi];
    row = {std::string(core::toString(m)) + " double, Caster per-beam" +
           (m == TriangleMethod::kWatertight ? " (production)" : "")};
    for (int a = 0; a < kExponents; ++a) row.push_back(count(per_beam[mi][a]));
    t.addRow(row);
  }
  record(t);
  const std::size_t wt = core::kAllTriangleMethods.size() - 1;
  ASSERT_EQ(core::kAllTriangleMethods[wt], TriangleMethod::kWatertight);
  for (int a = 0; a < kExponents; ++a) {
    EXPECT_EQ(fast[a], 0) << "aspect 1e" << a;
    EXPECT_EQ(crossing_errors[a], 0) << "aspect 1e" << a;
    EXPECT_EQ(per_beam[wt][a], 0) << "aspect 1e" << a;
  }
}

}  // namespace
}  // namespace laser_raycast_test
