// Watertightness of the triangle tests on closed meshes: a ray that starts inside a closed mesh
// must hit it. Rays are aimed exactly at shared vertices and at points on shared edges (the places
// where a non-watertight test lets a ray slip between neighbours), from interior origins, and along
// axis-aligned directions with exact zero components. Every triangle is tested (brute force), so
// the result depends on the triangle test alone.
//
// The watertight method, in double and in float, must miss nothing, hit exactly one triangle (a
// shared edge or vertex belongs to one of the triangles around it), and its closest hit must be the
// aimed point (the meshes are convex, so from inside the ray leaves exactly there). The other
// methods are reference implementations without that guarantee: their misses and double hits are
// counted and printed, not asserted.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <functional>
#include <iomanip>
#include <iostream>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "laser_raycast/core/triangle.h"
#include "random.h"
#include "test_geometry.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;
using Eigen::Vector3d;
using Triangles = std::vector<std::array<std::uint32_t, 3>>;

// ---------------------------------------------------------------------------------------------------
// Miss counts per method and precision, per test and over the whole run.

struct Tally {
  long rays = 0;
  long misses = 0;
  long double_hits = 0;      // more than one triangle hit: a ray leaves a convex mesh exactly once
  double worst_t_error = 0;  // relative, of the closest hit against the aimed point (watertight)
};
using TallyTable = std::array<std::array<Tally, 2>, kAllTriangleMethods.size()>;  // [method][float]

void printTable(const std::string& title, const TallyTable& table) {
  std::ostringstream s;
  s << title << "\n  " << std::left << std::setw(16) << "method" << std::setw(10) << "precision"
    << std::right << std::setw(10) << "rays" << std::setw(10) << "misses" << std::setw(13)
    << "double hits" << std::setw(16) << "worst t error"
    << "\n";
  for (std::size_t mi = 0; mi < table.size(); ++mi) {
    for (int f = 0; f < 2; ++f) {
      s << "  " << std::left << std::setw(16) << toString(kAllTriangleMethods[mi]) << std::setw(10)
        << (f ? "float" : "double") << std::right << std::setw(10) << table[mi][f].rays
        << std::setw(10) << table[mi][f].misses << std::setw(13) << table[mi][f].double_hits;
      if (kAllTriangleMethods[mi] == TriangleMethod::kWatertight) {
        s << std::setw(16) << table[mi][f].worst_t_error;
      }
      s << "\n";
    }
  }
  std::cout << s.str() << std::flush;
}

TallyTable& runTotal() {
  static TallyTable total{};
  return total;
}

// Prints the whole run's table once all tests are done.
class PrintTotalTable : public ::testing::Environment {
 public:
  void TearDown() override { printTable("Watertightness, all closed meshes:", runTotal()); }
};
::testing::Environment* const kPrintTotalTable =
    ::testing::AddGlobalTestEnvironment(new PrintTotalTable);

// ---------------------------------------------------------------------------------------------------
// Closed meshes and the rays aimed at them.

// A closed convex mesh in world coordinates with a region well inside it for ray origins.
struct ClosedMesh {
  std::string name;
  TriMesh mesh;
  Vector3d center;
  double radius;  // about the distance from center to the surface, for choosing origins
  std::function<bool(const Vector3d&)> is_interior;
  std::function<Vector3d(Rng&)> sample_interior;
};

// The icosphere of the given level, scaled, then moved by pose. Its inscribed radius is at least
// that of the icosahedron (0.794), so the ball of radius 0.7 (before scaling) is well inside.
ClosedMesh icosphere(int level, double scale, const Eigen::Isometry3d& pose) {
  ClosedMesh m;
  std::ostringstream name;
  name << "icosphere L" << level << " scale " << scale << " at " << pose.translation().transpose();
  m.name = name.str();
  m.mesh = transformed(makeIcosphere(level), scale, pose);
  m.center = pose.translation();
  m.radius = scale;
  const Eigen::Isometry3d inverse = pose.inverse();
  m.is_interior = [=](const Vector3d& p) { return (inverse * p).norm() < 0.7 * scale; };
  m.sample_interior = [=](Rng& rng) {
    const double r = 0.7 * scale * std::cbrt(uniform(rng, 0, 1));
    return Vector3d(pose * (r * randomUnitVector(rng)));
  };
  return m;
}

// The box room of the given size and grid, scaled, then moved by pose; origins stay inside the box
// shrunk to 90%.
ClosedMesh boxRoom(const Vector3d& size, int cells, double scale, const Eigen::Isometry3d& pose) {
  ClosedMesh m;
  std::ostringstream name;
  name << "box room " << size.transpose() << " cells " << cells << " scale " << scale << " at "
       << pose.translation().transpose();
  m.name = name.str();
  m.mesh = transformed(makeBoxRoom(size, cells), scale, pose);
  m.center = pose.translation();
  m.radius = 0.5 * scale * size.maxCoeff();
  const Vector3d inner_half = 0.45 * scale * size;
  const Eigen::Isometry3d inverse = pose.inverse();
  m.is_interior = [=](const Vector3d& p) {
    return ((inverse * p).cwiseAbs().array() < inner_half.array()).all();
  };
  m.sample_interior = [=](Rng& rng) {
    return Vector3d(pose * uniformInBox(rng, -inner_half, inner_half));
  };
  return m;
}

// A ray from `origin` aimed at the point (1 - s) v_i + s v_j of the mesh (a vertex when i == j),
// with direction (target - origin) * dir_scale. Built separately in double and in float from that
// precision's vertices, so that in both the ray aims at the stored vertex or edge.
struct AimedRay {
  Vector3d origin;
  std::uint32_t i, j;
  double s;
  double dir_scale;
};

template <typename T>
RayT<T> buildRay(const AimedRay& aim, const std::vector<Vec3<T>>& vertices, Vec3<T>* target) {
  const Vec3<T>& vi = vertices[aim.i];
  const Vec3<T>& vj = vertices[aim.j];
  *target = aim.i == aim.j ? vi : Vec3<T>(vi + T(aim.s) * (vj - vi));
  RayT<T> ray;
  ray.origin = aim.origin.cast<T>();
  ray.dir = (*target - ray.origin) * T(aim.dir_scale);
  return ray;
}

std::string describe(const ClosedMesh& m, const AimedRay& aim) {
  std::ostringstream s;
  s << std::setprecision(17) << m.name << ": origin " << aim.origin.transpose() << " aimed at "
    << (aim.i == aim.j ? "vertex " : "edge ") << aim.i << (aim.i == aim.j ? "" : "-")
    << (aim.i == aim.j ? "" : std::to_string(aim.j)) << " s " << aim.s << " dir scale "
    << aim.dir_scale;
  return s.str();
}

// Every ray of the test, for one mesh: from a few interior origins (the centre and random ones) at
// every vertex and at three points of every edge (its midpoint and two random ones); then from
// each vertex back along the 26 directions with components in {-1, 0, 1} that point into the mesh,
// to an interior origin on that line (so the direction has exact zeros and, for the 6 axes, is
// exactly axis-aligned).
std::vector<AimedRay> aimedRays(const ClosedMesh& m, int random_origins, Rng& rng) {
  std::vector<AimedRay> rays;
  std::vector<Vector3d> origins = {m.center};
  for (int k = 0; k < random_origins; ++k) origins.push_back(m.sample_interior(rng));
  const auto edges = uniqueEdges(m.mesh);
  for (const Vector3d& origin : origins) {
    for (std::uint32_t v = 0; v < m.mesh.vertices.size(); ++v) {
      rays.push_back({origin, v, v, 0.0, logUniform(rng, -1, 1)});
    }
    for (const auto& e : edges) {
      rays.push_back({origin, e[0], e[1], 0.5, logUniform(rng, -1, 1)});
      for (int k = 0; k < 2; ++k) {
        rays.push_back({origin, e[0], e[1], uniform(rng, 0, 1), logUniform(rng, -1, 1)});
      }
    }
  }
  for (std::uint32_t v = 0; v < m.mesh.vertices.size(); ++v) {
    const Vector3d& vertex = m.mesh.vertices[v];
    for (int code = 0; code < 27; ++code) {
      const Vector3d u(code % 3 - 1, code / 3 % 3 - 1, code / 9 - 1);
      if (u.dot(vertex - m.center) <= 0) continue;  // origin = vertex - k u must be inside
      for (int attempt = 0; attempt < 8; ++attempt) {
        const Vector3d origin = vertex - uniform(rng, 0, 2 * m.radius) * u;
        if (m.is_interior(origin)) {
          rays.push_back({origin, v, v, 0.0, 1.0});
          break;
        }
      }
    }
  }
  return rays;
}

// ---------------------------------------------------------------------------------------------------
// Brute force over every triangle.

// How many triangles the ray hits.
template <TriangleMethod M, typename T>
int countHits(const RayT<T>& ray, const std::vector<Vec3<T>>& v, const Triangles& triangles) {
  int hits = 0;
  for (const auto& tri : triangles) {
    if (intersectTriangle<M>(ray, v[tri[0]], v[tri[1]], v[tri[2]])) ++hits;
  }
  return hits;
}

template <TriangleMethod M, typename T>
std::optional<T> closestHit(RayT<T> ray, const std::vector<Vec3<T>>& v,
                            const Triangles& triangles) {
  std::optional<T> best;
  for (const auto& tri : triangles) {
    if (const auto hit = intersectTriangle<M>(ray, v[tri[0]], v[tri[1]], v[tri[2]])) {
      best = hit->t;
      ray.tmax = hit->t;
    }
  }
  return best;
}

// Relative tolerance on the watertight method's closest hit against |target - origin| / |dir|. The
// target is a rounded vertex or edge point, within a few ulps of the surface, and the origin is at
// least ~0.1 radius from the surface, so the true exit is ~1e-15 (double) or ~1e-6 (float)
// relative from the target. The bounds below are far above that and far below any wrong hit.
template <typename T>
constexpr double kDistanceTolerance = std::is_same<T, double>::value ? 1e-9 : 1e-4;

// Casts the ray in one precision with every method, counts the misses, checks the watertight
// method's distance, and returns descriptions of watertight misses.
template <typename T>
void castWithEveryMethod(const ClosedMesh& m, const std::vector<Vec3<T>>& vertices,
                         const AimedRay& aim, TallyTable* table, std::vector<std::string>* errors) {
  const int f = std::is_same<T, float>::value ? 1 : 0;
  Vec3<T> target;
  const RayT<T> ray = buildRay<T>(aim, vertices, &target);
  for (std::size_t mi = 0; mi < kAllTriangleMethods.size(); ++mi) {
    Tally& tally = (*table)[mi][f];
    ++tally.rays;
    dispatchTriangleMethod(kAllTriangleMethods[mi], [&](auto method) {
      constexpr TriangleMethod M = decltype(method)::value;
      // The origin is inside a convex closed mesh: the ray crosses its surface exactly once.
      const int hits = countHits<M>(ray, vertices, m.mesh.triangles);
      if (hits > 1) ++tally.double_hits;
      if (hits > 1 && M == TriangleMethod::kWatertight && errors->size() < 10) {
        errors->push_back(std::string(f ? "float " : "double ") + describe(m, aim) + ": " +
                          std::to_string(hits) + " triangles hit");
      }
      if constexpr (M == TriangleMethod::kWatertight) {
        const std::optional<T> t = closestHit<M>(ray, vertices, m.mesh.triangles);
        if (!t) {
          ++tally.misses;
          if (errors->size() < 10) {
            errors->push_back(std::string(f ? "float " : "double ") + describe(m, aim));
          }
          return;
        }
        using L = long double;
        const L expected = (target.template cast<L>() - ray.origin.template cast<L>()).norm() /
                           ray.dir.template cast<L>().norm();
        const double error = double(std::abs((L(*t) - expected) / expected));
        tally.worst_t_error = std::max(tally.worst_t_error, error);
        if (!(error <= kDistanceTolerance<T>)&&errors->size() < 10) {
          std::ostringstream s;
          s << (f ? "float " : "double ") << describe(m, aim) << ": t = " << *t << ", expected "
            << double(expected) << " (relative error " << error << ")";
          errors->push_back(s.str());
        }
      } else {
        if (hits == 0) ++tally.misses;
      }
    });
  }
}

// Casts every aimed ray at every mesh in both precisions; asserts that watertight (double and
// float) missed nothing and hit at the aimed point, and prints the table.
void runClosedMeshes(const std::string& title, const std::vector<ClosedMesh>& meshes,
                     const std::vector<int>& random_origins, std::uint32_t seed,
                     long minimum_rays) {
  Rng rng(seed);
  TallyTable table{};
  std::vector<std::string> errors;
  long axis_aligned = 0, with_zero_component = 0;
  for (std::size_t k = 0; k < meshes.size(); ++k) {
    const ClosedMesh& m = meshes[k];
    ASSERT_TRUE(isClosedAndConsistentlyWound(m.mesh)) << m.name;
    std::vector<Eigen::Vector3f> vertices_f;
    for (const Vector3d& v : m.mesh.vertices) vertices_f.push_back(v.cast<float>());
    for (const AimedRay& aim : aimedRays(m, random_origins[k], rng)) {
      const Vector3d dir = m.mesh.vertices[aim.i] - aim.origin;
      const long zeros = (dir.array() == 0.0).count();
      axis_aligned += zeros == 2;
      with_zero_component += zeros >= 1;
      castWithEveryMethod<double>(m, m.mesh.vertices, aim, &table, &errors);
      castWithEveryMethod<float>(m, vertices_f, aim, &table, &errors);
    }
  }
  printTable(title, table);
  std::cout << "  (" << axis_aligned << " rays exactly axis-aligned, " << with_zero_component
            << " with a zero direction component)\n";
  for (std::size_t mi = 0; mi < table.size(); ++mi) {
    for (int f = 0; f < 2; ++f) {
      runTotal()[mi][f].rays += table[mi][f].rays;
      runTotal()[mi][f].misses += table[mi][f].misses;
      runTotal()[mi][f].double_hits += table[mi][f].double_hits;
      runTotal()[mi][f].worst_t_error =
          std::max(runTotal()[mi][f].worst_t_error, table[mi][f].worst_t_error);
    }
  }

  const std::size_t wt = kAllTriangleMethods.size() - 1;
  ASSERT_EQ(kAllTriangleMethods[wt], TriangleMethod::kWatertight);
  EXPECT_GE(table[wt][0].rays, minimum_rays);
  // The direction families were generated (a sanity check on the generator; roughly half of what
  // the current seeds give).
  EXPECT_GT(axis_aligned, 300);
  EXPECT_GT(with_zero_component, 1500);
  EXPECT_EQ(table[wt][0].misses, 0) << "watertight (double) let rays out of a closed mesh";
  EXPECT_EQ(table[wt][1].misses, 0) << "watertight (float) let rays out of a closed mesh";
  EXPECT_EQ(table[wt][0].double_hits, 0) << "watertight (double) hit two triangles at one point";
  EXPECT_EQ(table[wt][1].double_hits, 0) << "watertight (float) hit two triangles at one point";
  EXPECT_TRUE(errors.empty()) << "first problems:\n"
                              << [&] {
                                   std::string all;
                                   for (const auto& e : errors) all += e + "\n";
                                   return all;
                                 }();
}

// ---------------------------------------------------------------------------------------------------
// The meshes themselves: closed, wound outwards, convex (the distance check relies on it).

TEST(ClosedMeshGeometry, IcosphereIsClosedConvexAndOutward) {
  for (int level = 0; level <= 4; ++level) {
    const TriMesh m = makeIcosphere(level);
    const std::size_t four_l = std::size_t(1) << (2 * level);
    EXPECT_EQ(m.vertices.size(), 10 * four_l + 2) << level;
    EXPECT_EQ(m.triangles.size(), 20 * four_l) << level;
    EXPECT_EQ(uniqueEdges(m).size(), 30 * four_l) << level;
    EXPECT_TRUE(isClosedAndConsistentlyWound(m)) << level;
    for (const Vector3d& v : m.vertices) EXPECT_NEAR(v.norm(), 1.0, 1e-15) << level;
    const double volume = signedVolume(m);
    EXPECT_GT(volume, 0.6 * 4 / 3 * M_PI) << level;  // the icosahedron holds 61% of the ball
    EXPECT_LT(volume, 4 / 3.0 * M_PI) << level;
    EXPECT_LT(maxConvexityViolation(m), 1e-12) << level;
  }
}

TEST(ClosedMeshGeometry, BoxRoomIsClosedConvexAndOutward) {
  for (const int cells : {1, 2, 3, 4, 8}) {
    const Vector3d size(4, 3, 2.5);
    const TriMesh m = makeBoxRoom(size, cells);
    EXPECT_EQ(m.vertices.size(), std::size_t((cells + 1) * (cells + 1) * (cells + 1) -
                                             (cells - 1) * (cells - 1) * (cells - 1)))
        << cells;
    EXPECT_EQ(m.triangles.size(), std::size_t(12 * cells * cells)) << cells;
    EXPECT_TRUE(isClosedAndConsistentlyWound(m)) << cells;
    EXPECT_NEAR(signedVolume(m), 4 * 3 * 2.5, 1e-12) << cells;
    EXPECT_LT(maxConvexityViolation(m), 1e-12) << cells;
    for (const Vector3d& v : m.vertices) {
      EXPECT_NEAR((v.cwiseAbs() - 0.5 * size).maxCoeff(), 0.0, 0.0)
          << "on a wall: " << v.transpose();
    }
  }
}

// ---------------------------------------------------------------------------------------------------
// Rays from inside.

// The minimum ray counts of the two tests add up to over 100,000 rays per method and precision.
TEST(Watertight, RaysFromInsideAnIcosphereNeverEscape) {
  Rng rng(101);
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  const Vector3d off_axis(2.5, -1.5, 0.75);
  // Levels 0 to 3 at the origin (many exact zeros in the vertices); level 2 rotated and moved at
  // scales 1, 1e-3 and 1e3; level 1 moved off-axis, unrotated, at 1e3 and 1e-3.
  const std::vector<ClosedMesh> meshes = {
      icosphere(0, 1.0, identity),
      icosphere(1, 1.0, identity),
      icosphere(2, 1.0, identity),
      icosphere(3, 1.0, identity),
      icosphere(2, 1.0, randomPose(rng, 3.0)),
      icosphere(2, 1e-3, randomPose(rng, 3e-3)),
      icosphere(2, 1e3, randomPose(rng, 3e3)),
      icosphere(1, 1e3, Eigen::Isometry3d(Eigen::Translation3d(1e3 * off_axis))),
      icosphere(1, 1e-3, Eigen::Isometry3d(Eigen::Translation3d(1e-3 * off_axis))),
  };
  runClosedMeshes("Watertightness, icospheres:", meshes, {30, 20, 6, 0, 6, 6, 6, 8, 8}, 102, 70000);
}

TEST(Watertight, RaysFromInsideABoxRoomNeverEscape) {
  Rng rng(201);
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  const Vector3d room(4, 3, 2.5);
  // Axis-aligned rooms (walls in coordinate planes, grid vertices at exact coordinates) at scales
  // 1, 1e-3 and 1e3; one rotated and moved; a finer cube.
  const std::vector<ClosedMesh> meshes = {
      boxRoom(room, 4, 1.0, identity),
      boxRoom(room, 4, 1e-3, identity),
      boxRoom(room, 4, 1e3, identity),
      boxRoom(room, 3, 1.0, randomPose(rng, 2.0)),
      boxRoom(Vector3d(1, 1, 1), 6, 1.0, identity),
  };
  runClosedMeshes("Watertightness, box rooms:", meshes, {12, 6, 6, 8, 3}, 202, 40000);
}

}  // namespace
}  // namespace laser_raycast_test
