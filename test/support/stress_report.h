// Shared by the numerical stress suite (test/stress/test_stress_*.cpp, one executable): the figures
// table and the method variants it compares.
//
// Each stress case measures a figure for every variant (the five triangle methods, in double and
// in float) and asserts a bound only on the production path (watertight, double, through the BVH
// and the Caster). The figures are recorded as markdown tables: printed as each case finishes and,
// when LASER_RAYCAST_STRESS_REPORT names a file, written there after the last test
// (docs/stress.md is such a run; docs/testing.md describes the suite).
#pragma once

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "laser_raycast/core/bvh.h"
#include "laser_raycast/core/mesh.h"
#include "laser_raycast/core/triangle.h"
#include "laser_raycast/loader/scene_loader.h"
#include "shared_data.h"
#include "test_geometry.h"

namespace laser_raycast_test {

namespace core = laser_raycast::core;

using core::TriangleMethod;

// ---------------------------------------------------------------------------------------------------
// Variants: watertight double (production) first, then watertight float, then the reference
// methods, each in double and float.

struct Variant {
  TriangleMethod method;
  bool is_float;
};

inline const std::vector<Variant>& variants() {
  static const std::vector<Variant> all = [] {
    std::vector<Variant> v = {{TriangleMethod::kWatertight, false},
                              {TriangleMethod::kWatertight, true}};
    for (const TriangleMethod m : core::kAllTriangleMethods) {
      if (m == TriangleMethod::kWatertight) continue;
      v.push_back({m, false});
      v.push_back({m, true});
    }
    return v;
  }();
  return all;
}

inline std::string variantName(const Variant& v) {
  std::string name = std::string(core::toString(v.method)) + (v.is_float ? " float" : " double");
  if (v.method == TriangleMethod::kWatertight && !v.is_float) name += " (production)";
  return name;
}

inline bool isProduction(const Variant& v) {
  return v.method == TriangleMethod::kWatertight && !v.is_float;
}

// Calls f(std::integral_constant<TriangleMethod, M>{}, T{}) with T = double or float, so that the
// body is compiled per method and precision.
template <typename F>
void dispatchVariant(const Variant& v, F&& f) {
  core::dispatchTriangleMethod(v.method, [&](auto m) {
    if (v.is_float) {
      f(m, float{});
    } else {
      f(m, double{});
    }
  });
}

// The unit roundoff of T (half an ulp of 1).
template <typename T>
constexpr double unitRoundoff() {
  return std::numeric_limits<T>::epsilon() / 2;
}

// ---------------------------------------------------------------------------------------------------
// Brute force over every triangle: the oracle the cases count with (no BVH, no culling).

using Triangles = std::vector<std::array<std::uint32_t, 3>>;

template <typename T>
std::vector<core::Vec3<T>> castVertices(const std::vector<Eigen::Vector3d>& vertices) {
  std::vector<core::Vec3<T>> out;
  out.reserve(vertices.size());
  for (const auto& v : vertices) out.push_back(v.cast<T>());
  return out;
}

// The BVH of the precision T (tag argument).
inline const core::Bvh& pick(const core::Bvh& d, const core::BvhF&, double) { return d; }
inline const core::BvhF& pick(const core::Bvh&, const core::BvhF& f, float) { return f; }

// How many triangles the ray hits (degenerate ones never do: intersectTriangle rejects them).
template <TriangleMethod M, typename T>
int countHits(const core::RayT<T>& ray, const std::vector<core::Vec3<T>>& v,
              const Triangles& triangles) {
  int hits = 0;
  for (const auto& tri : triangles) {
    if (core::intersectTriangle<M>(ray, v[tri[0]], v[tri[1]], v[tri[2]])) ++hits;
  }
  return hits;
}

// A mesh of ../shared/data/tb3_world_data (path under meshes/) as the loader reads it, with the
// URDF scale, and its vertices joined by exact position (assimp and STL repeat a vertex per face),
// so that shared edges are found by index. Call from a test that began with REQUIRE_SHARED_DATA().
inline TriMesh loadSharedMesh(const std::string& file, double scale) {
  const std::string dir = tb3WorldData();
  laser_raycast::SceneLoader loader(
      [dir](const std::string& package) -> std::optional<std::string> {
        if (package == "tb3_world_data") return dir;
        return std::nullopt;
      });
  const auto mesh = loader.loadMesh("package://tb3_world_data/meshes/" + file, "",
                                    Eigen::Vector3d::Constant(scale), core::BvhConfig{});
  TriMesh out;
  std::map<std::array<double, 3>, std::uint32_t> index_of;
  std::vector<std::uint32_t> joined(mesh->vertices().size());
  for (std::size_t i = 0; i < mesh->vertices().size(); ++i) {
    const Eigen::Vector3d& p = mesh->vertices()[i];
    const auto found = index_of.emplace(std::array<double, 3>{p.x(), p.y(), p.z()},
                                        static_cast<std::uint32_t>(out.vertices.size()));
    if (found.second) out.vertices.push_back(p);
    joined[i] = found.first->second;
  }
  for (const auto& tri : mesh->triangles()) {
    out.triangles.push_back({joined[tri[0]], joined[tri[1]], joined[tri[2]]});
  }
  EXPECT_TRUE(isClosedAndConsistentlyWound(out)) << file << " is not closed";
  return out;
}

// ---------------------------------------------------------------------------------------------------
// Tables.

struct Table {
  std::string key;    // orders the tables in the report ("1a", "2", ...)
  std::string title;  // "1a. Leaks: rays at shared vertices and edges of convex closed meshes"
  std::string text;   // what is measured, and the bound asserted on the production path
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;

  void addRow(std::vector<std::string> row) { rows.push_back(std::move(row)); }
};

inline std::string markdown(const Table& t) {
  std::ostringstream s;
  s << "### " << t.title << "\n\n" << t.text << "\n\n|";
  for (const auto& h : t.header) s << " " << h << " |";
  s << "\n|";
  for (std::size_t i = 0; i < t.header.size(); ++i) s << (i == 0 ? " --- |" : " ---: |");
  s << "\n";
  for (const auto& row : t.rows) {
    s << "|";
    for (const auto& cell : row) s << " " << cell << " |";
    s << "\n";
  }
  return s.str();
}

inline std::map<std::string, Table>& tables() {
  static std::map<std::string, Table> all;
  return all;
}

// Records a table (replacing one with the same key) and prints it.
inline void record(const Table& t) {
  tables()[t.key] = t;
  std::cout << "\n" << markdown(t) << std::flush;
}

inline std::string reportIntro() {
  return "# Numerical stress suite: figures\n\n"
         "Written by the gtest executable `test_stress` (`test/stress/test_stress_*.cpp`, run "
         "in CI with the other tests); what the suite asserts, and a summary of these tables, "
         "are in [testing.md](testing.md). To regenerate this file, from the catkin workspace "
         "that holds the package (`.ws/` after `quickstart/test.sh`), with `../shared/data` "
         "beside the clone:\n\n"
         "```sh\n"
         "catkin_make -j2 test_stress\n"
         "LASER_RAYCAST_STRESS_REPORT=$PWD/src/laser_raycast/docs/stress.md "
         "./devel/lib/laser_raycast/test_stress\n"
         "```\n\n"
         "Every case measures one figure for each triangle method in double and in float, and "
         "asserts a bound only on the production path: `watertight` in double, through the BVH "
         "(`Mesh`, `Bvh::closestHit`) and the `Caster` (planar fast path and per-beam path) with "
         "the `MeasurementModel` for REP 117 output. The other rows are recorded, not asserted. "
         "Expected values never come from the code under test: analytic values, long double "
         "arithmetic, brute force, or topology (a ray from inside a convex closed mesh crosses it "
         "exactly once). Randomness is seeded, so a run repeats these figures exactly on the "
         "same platform and build.\n\n"
         "`u` is the unit roundoff of the variant's precision (2^-53 in double, 2^-24 in "
         "float).\n";
}

inline std::string renderReport() {
  std::string out = reportIntro();
  for (const auto& entry : tables()) out += "\n" + markdown(entry.second);
  return out;
}

// Writes the report after the last test when LASER_RAYCAST_STRESS_REPORT is set.
class ReportEnvironment : public ::testing::Environment {
 public:
  void TearDown() override {
    const char* path = std::getenv("LASER_RAYCAST_STRESS_REPORT");
    if (!path || !*path || tables().empty()) return;
    std::ofstream file(path);
    file << renderReport();
    std::cout << "stress report written to " << path << "\n";
  }
};

inline ::testing::Environment* const kReportEnvironment =
    ::testing::AddGlobalTestEnvironment(new ReportEnvironment);

// ---------------------------------------------------------------------------------------------------
// Cell formatting.

inline std::string count(long n) { return std::to_string(n); }

// "0", or two significant digits in scientific notation; "inf" and "nan" as such.
inline std::string sci(double x) {
  if (x == 0) return "0";
  if (std::isnan(x)) return "nan";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.1e", x);
  return buffer;
}

inline std::string fixed(double x, int decimals) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, x);
  return buffer;
}

}  // namespace laser_raycast_test
