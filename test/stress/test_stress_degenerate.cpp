// Stress case 4, degenerate triangles: zero-area ones (repeated or collinear vertices) never hit,
// rounded-collinear needles and triangles ~1e-155 m across yield no NaN or Inf; also through the
// BVH (Mesh keeps zero-area triangles out of it) and the Caster. test_stress_slivers.cpp has the
// thin but proper triangles.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/mesh.h"
#include "random.h"
#include "stress_report.h"

namespace laser_raycast_test {
namespace {

using core::Vec3;
using Eigen::Vector3d;
constexpr double kInf = std::numeric_limits<double>::infinity();

// ---------------------------------------------------------------------------------------------------
// 4c, 4d. Zero-area and tiny triangles.

enum Kind { kRepeated, kAllEqual, kCollinearExact, kCollinearRounded, kTiny, kKinds };
const char* const kKindNames[kKinds] = {"repeated vertex", "three equal vertices",
                                        "collinear (exact)", "collinear (rounded)",
                                        "tiny (1e-155 m)"};
constexpr double kTinyScale = 1e-155;

// Zero area in any arithmetic for the first three kinds (a repeated vertex, or a midpoint of
// dyadic points: b - a = (c - a) / 2 exactly); the rounded third point of the fourth is off the
// line by rounding, so that triangle is a needle of area ~1e-17 rather than zero. The tiny one is
// well shaped but ~1e-155 m across, so its edge functions are subnormal and 1 / det overflows.
std::array<Vector3d, 3> degenerate(Kind kind, Rng& rng) {
  const auto dyadic = [&] { return Vector3d((uniformInCube(rng, 1.0) * 64).array().round() / 64); };
  std::array<Vector3d, 3> v;
  switch (kind) {
    case kRepeated:
      v = {uniformInCube(rng, 1.0), Vector3d::Zero(), uniformInCube(rng, 1.0)};
      v[1] = v[0];
      break;
    case kAllEqual:
      v[0] = v[1] = v[2] = uniformInCube(rng, 1.0);
      break;
    case kCollinearExact:
      v[0] = dyadic();
      v[2] = dyadic();
      v[1] = v[0] + 0.5 * (v[2] - v[0]);
      break;
    case kCollinearRounded:
      v[0] = uniformInCube(rng, 1.0);
      v[2] = uniformInCube(rng, 1.0);
      v[1] = v[0] + (v[2] - v[0]) / 3.0;
      break;
    default: {
      const Eigen::Isometry3d pose = randomPose(rng, 0.0);
      for (int k = 0; k < 3; ++k) {
        const double a = 2 * M_PI * k / 3 + uniform(rng, -0.3, 0.3);
        v[k] = kTinyScale * (pose * Vector3d(std::cos(a), std::sin(a), 0));
      }
    }
  }
  std::shuffle(v.begin(), v.end(), rng);
  return v;
}

struct KindTally {
  long rays = 0, hits = 0, impossible = 0;
};

// Rays at the vertices, edge midpoints and centroid (the tiny kind: three points well inside, so
// that each must hit at t = 1, as the direction is target - origin).
template <TriangleMethod M, typename T>
void castDegenerate(Kind kind, const std::array<Vector3d, 3>& tri, Rng& rng, KindTally* tally) {
  const Vec3<T> a = tri[0].cast<T>(), b = tri[1].cast<T>(), c = tri[2].cast<T>();
  std::vector<Vec3<T>> targets;
  if (kind == kTiny) {
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d uv = 0.1 * Eigen::Vector2d::Ones() + 0.7 * randomBarycentrics(rng);
      targets.push_back(a + T(uv.x()) * (b - a) + T(uv.y()) * (c - a));
    }
  } else {
    targets = {a, b, c, (a + b) / T(2), (b + c) / T(2), (c + a) / T(2), (a + b + c) / T(3)};
  }
  const double scale = kind == kTiny ? kTinyScale : 1.0;
  for (const Vec3<T>& target : targets) {
    core::RayT<T> ray;
    ray.origin = target + (scale * uniform(rng, 0.5, 2.0) * randomUnitVector(rng)).cast<T>();
    ray.dir = target - ray.origin;
    const auto hit = core::intersectTriangle<M>(ray, a, b, c);
    ++tally->rays;
    if (!hit) continue;
    ++tally->hits;
    const bool possible = std::isfinite(hit->t) && std::isfinite(hit->u) && std::isfinite(hit->v) &&
                          hit->t >= 0 && (kind != kTiny || std::abs(hit->t - 1) <= 1e-6);
    tally->impossible += !possible;
  }
}

TEST(StressDegenerate, ZeroAreaAndTinyTriangles) {
  std::vector<std::vector<KindTally>> tallies(variants().size(), std::vector<KindTally>(kKinds));
  for (int kind = 0; kind < kKinds; ++kind) {
    Rng rng(4300 + kind);
    for (int n = 0; n < 300; ++n) {
      const auto tri = degenerate(static_cast<Kind>(kind), rng);
      const std::uint32_t seed = rng();
      for (std::size_t vi = 0; vi < variants().size(); ++vi) {
        Rng ray_rng(seed);  // the same rays for every variant
        dispatchVariant(variants()[vi], [&](auto m, auto x) {
          castDegenerate<decltype(m)::value, decltype(x)>(static_cast<Kind>(kind), tri, ray_rng,
                                                          &tallies[vi][kind]);
        });
      }
    }
  }
  std::vector<std::string> header = {"method"};
  for (const char* name : kKindNames) header.push_back(name);
  Table t{"4c",
          "4c. Zero-area and tiny triangles: hits / impossible results",
          "300 triangles per kind; rays at their vertices, edge midpoints and centroid (" +
              count(tallies[0][0].rays) +
              " per kind), or for the tiny kind (everything, origin included, scaled by 1e-155) at "
              "three points well inside (" +
              count(tallies[0][kTiny].rays) +
              " rays, each must hit at t = 1). Impossible: t, u or v NaN or Inf, t < 0, or (tiny) "
              "|t - 1| > 1e-6. Asserted on production: no hit on the three zero-area kinds, every "
              "tiny ray hit, nothing impossible.",
          header,
          {}};
  for (std::size_t vi = 0; vi < variants().size(); ++vi) {
    std::vector<std::string> row = {variantName(variants()[vi])};
    for (int kind = 0; kind < kKinds; ++kind) {
      row.push_back(count(tallies[vi][kind].hits) + " / " + count(tallies[vi][kind].impossible));
    }
    t.addRow(row);
  }
  record(t);
  ASSERT_TRUE(isProduction(variants()[0]));
  for (const int kind : {kRepeated, kAllEqual, kCollinearExact}) {
    EXPECT_EQ(tallies[0][kind].hits, 0) << kKindNames[kind];
  }
  EXPECT_EQ(tallies[0][kTiny].hits, tallies[0][kTiny].rays);
  for (int kind = 0; kind < kKinds; ++kind) {
    EXPECT_EQ(tallies[0][kind].impossible, 0) << kKindNames[kind];
  }
}

// Regression: a ray hitting a triangle ~1e-155 m across (seen from as close) made 1 / det overflow,
// and watertight returned t = +Inf and u = +Inf, which tmax = +Inf accepted.
TEST(StressDegenerate, WatertightTinyTriangleHitIsFinite) {
  const double s = 1e-155;
  core::Ray ray;
  ray.origin = Vector3d(0.25 * s, 0.25 * s, 1.0);
  ray.dir = Vector3d(0, 0, -1);
  const auto hit = core::intersectTriangle<TriangleMethod::kWatertight>(
      ray, Vector3d(0, 0, 0), Vector3d(s, 0, 0), Vector3d(0, s, 0));
  ASSERT_TRUE(hit.has_value());
  EXPECT_EQ(hit->t, 1.0);
  // The edge functions are subnormal (~2.5e-311, spaced 4.9e-324): ~2e-13 relative precision.
  EXPECT_NEAR(hit->u, 0.25, 1e-12);
  EXPECT_NEAR(hit->v, 0.25, 1e-12);
}

// 4d. Zero-area triangles in a Mesh: kept out of the BVH, never reported by it or by the Caster,
// and no NaN or Inf range (the room around them is closed, so every beam hits something).
TEST(StressDegenerate, ZeroAreaTrianglesThroughBvhAndCaster) {
  Rng rng(4401);
  TriMesh cloud;
  std::vector<char> zero_area;
  for (int n = 0; n < 400; ++n) {
    const Kind kind = static_cast<Kind>(n % 4);
    const auto tri = degenerate(kind, rng);
    const auto base = static_cast<std::uint32_t>(cloud.vertices.size());
    for (const Vector3d& v : tri) cloud.vertices.push_back(v);
    cloud.triangles.push_back({base, base + 1, base + 2});
    zero_area.push_back(kind != kCollinearRounded);
  }
  const long zero_area_count = std::count(zero_area.begin(), zero_area.end(), 1);
  auto mesh = std::make_shared<const core::Mesh>(cloud.vertices, cloud.triangles);
  EXPECT_GE(static_cast<long>(mesh->degenerateTriangleCount()), zero_area_count);
  for (const auto id : mesh->bvh().triangleIds()) EXPECT_FALSE(zero_area[id]) << id;

  // Rays at the triangles' vertices and centroids through the BVH, built as the mesh builds it (the
  // mesh keeps only the slots of its own and walks its wide BVH, which the Caster below tests).
  const core::Bvh bvh = core::Bvh::build(cloud.vertices, cloud.triangles, {}, mesh->components());
  EXPECT_EQ(bvh.triangleIds(), mesh->bvh().triangleIds());
  long bvh_rays = 0, bvh_bad = 0;
  for (std::size_t k = 0; k < cloud.triangles.size(); ++k) {
    const auto& tri = cloud.triangles[k];
    for (const Vector3d& target :
         {cloud.vertices[tri[0]], cloud.vertices[tri[2]],
          Vector3d((cloud.vertices[tri[0]] + cloud.vertices[tri[1]] + cloud.vertices[tri[2]]) /
                   3)}) {
      core::Ray ray;
      ray.origin = target + uniform(rng, 0.5, 2.0) * randomUnitVector(rng);
      ray.dir = target - ray.origin;
      const auto hit = bvh.closestHit<TriangleMethod::kWatertight>(ray);
      ++bvh_rays;
      bvh_bad += hit && (zero_area[hit->triangle] || !std::isfinite(hit->t) ||
                         !std::isfinite(hit->u) || !std::isfinite(hit->v));
    }
  }

  // The Caster, with the cloud inside a closed room: planar fan (fast path and per-beam) and rings.
  core::Scene scene;
  scene.addLabel("thing");
  core::Body room, thing;
  room.frame = thing.frame = scene.addFrame("world");
  const TriMesh room_mesh = makeBoxRoom(Vector3d(8, 6, 3), 2);
  room.shape = std::make_shared<const core::Mesh>(room_mesh.vertices, room_mesh.triangles);
  thing.shape = mesh;
  scene.addBody(room);
  const int thing_index = scene.addBody(thing);
  const core::FramePoses poses = core::FramePoses::identity(scene);
  const core::ScanPattern planar(core::FanSpec{-M_PI, M_PI, 0, 3600});
  const core::ScanPattern rings(core::FanSpec{-M_PI, M_PI, 0, 720}, {-0.4, -0.2, 0.2, 0.4});
  long beams = 0, non_finite = 0, on_zero_area = 0;
  for (int s = 0; s < 4; ++s) {
    Eigen::Isometry3d sensor = Eigen::Isometry3d::Identity();
    sensor.translation() = uniformInBox(rng, Vector3d(-0.5, -0.5, -0.3), Vector3d(0.5, 0.5, 0.3));
    for (const core::ScanPattern* pattern : {&planar, &rings}) {
      for (const bool fast : {true, false}) {
        if (!pattern->planar() && !fast) continue;
        core::CastConfig config;
        config.planar_fast_path = fast;
        core::Caster caster;
        const core::ScanResult& r = caster.cast(scene, poses, sensor, *pattern, config);
        for (int i = 0; i < pattern->size(); ++i) {
          ++beams;
          non_finite += !std::isfinite(r.range[i]);
          on_zero_area += r.body[i] == thing_index && zero_area[r.triangle[i]];
        }
      }
    }
  }
  Table t{"4d",
          "4d. Zero-area triangles through the BVH and the Caster (production)",
          "A mesh of 400 triangles, 300 of them zero-area (repeated, equal or exactly collinear "
          "vertices) and 100 rounded-collinear needles, in a cube of 2 m; inside a closed room.",
          {"path", "rays or beams", "zero-area triangles hit", "NaN or Inf"},
          {}};
  t.addRow({"BVH closest hit (watertight double)", count(bvh_rays), count(bvh_bad), "-"});
  t.addRow({"Caster, fast path, per-beam and rings", count(beams), count(on_zero_area),
            count(non_finite)});
  record(t);
  EXPECT_EQ(bvh_bad, 0);
  EXPECT_EQ(non_finite, 0);
  EXPECT_EQ(on_zero_area, 0);
}

}  // namespace
}  // namespace laser_raycast_test
