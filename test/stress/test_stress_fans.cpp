// Stress case 1, leaks in the plane: planar fans whose scan plane runs exactly through rings of
// vertices, through the Caster's fast path (sliceMesh, whose crossing counter must count exactly
// one outline segment per beam from inside a closed star-shaped outline), its per-beam path, and
// brute force per method and precision.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
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

using Eigen::Vector3d;

// ---------------------------------------------------------------------------------------------------
// Planar fans through rings of vertices.

core::ScanPattern fan(double angle_min, double span, int samples) {
  core::FanSpec spec;
  spec.angle_min = angle_min;
  spec.angle_max = angle_min + span;
  spec.samples = samples;
  return core::ScanPattern(spec);
}

// A closed mesh and sensor poses inside it whose scan plane runs through a ring of its vertices.
struct FanCase {
  TriMesh mesh;
  std::vector<Eigen::Isometry3d> sensors;
  std::vector<core::ScanPattern> patterns;  // one per sensor
};

struct FanTally {
  long beams = 0, caster_misses = 0, missing = 0, doubled = 0;
};

// Casts every sensor's fan: the fast path (misses, and sliceMesh's crossing count, which must be
// exactly one per beam), the per-beam Caster with each method in double, and brute force per
// variant. Returns one tally for the fast path, then one per variant.
std::vector<FanTally> runFans(const std::vector<FanCase>& cases) {
  std::vector<FanTally> out(variants().size() + 1);
  for (const FanCase& c : cases) {
    auto mesh = std::make_shared<const core::Mesh>(c.mesh.vertices, c.mesh.triangles);
    core::Scene scene;
    scene.addFrame("mesh");
    scene.addLabel("mesh");
    scene.addBody(core::Body{mesh});
    const core::FramePoses poses = core::FramePoses::identity(scene);
    for (std::size_t s = 0; s < c.sensors.size(); ++s) {
      const Eigen::Isometry3d& sensor = c.sensors[s];
      const core::ScanPattern& pattern = c.patterns[s];
      const int n = pattern.size();
      core::Caster caster;
      core::CastConfig config;
      const core::ScanResult& fast = caster.cast(scene, poses, sensor, pattern, config);
      std::vector<double> range(n, std::numeric_limits<double>::infinity());
      std::vector<int> body_hit(n, -1), triangle(n, -1), crossings(n, 0);
      core::sliceMesh(*mesh, core::relativePose(sensor, Eigen::Isometry3d::Identity()), pattern,
                      0.0, std::numeric_limits<double>::infinity(), false, 0,
                      core::DepthBuffer{&range, &body_hit, &triangle, &crossings});
      for (int i = 0; i < n; ++i) {
        ++out[0].beams;
        out[0].caster_misses += !std::isfinite(fast.range[i]);
        out[0].missing += crossings[i] == 0;
        out[0].doubled += crossings[i] > 1;
      }
      for (std::size_t k = 0; k < variants().size(); ++k) {
        const Variant& v = variants()[k];
        FanTally& tally = out[k + 1];
        if (!v.is_float) {
          config.method = v.method;
          config.planar_fast_path = false;
          const core::ScanResult& per_beam = caster.cast(scene, poses, sensor, pattern, config);
          for (int i = 0; i < n; ++i) tally.caster_misses += !std::isfinite(per_beam.range[i]);
        }
        dispatchVariant(v, [&](auto m, auto x) {
          constexpr TriangleMethod M = decltype(m)::value;
          using T = decltype(x);
          const auto vertices = castVertices<T>(c.mesh.vertices);
          for (int i = 0; i < n; ++i) {
            core::RayT<T> ray;
            ray.origin = sensor.translation().cast<T>();
            ray.dir = (sensor.linear() * pattern.directions()[i]).cast<T>();
            const int hits = countHits<M>(ray, vertices, c.mesh.triangles);
            ++tally.beams;
            tally.missing += hits == 0;
            tally.doubled += hits > 1;
          }
        });
      }
    }
  }
  return out;
}

void recordFans(const std::string& key, const std::string& title, const std::string& text,
                const std::vector<FanTally>& tallies) {
  Table t{key,
          title,
          text,
          {"method", "beams", "Caster misses", "brute-force misses", "brute-force double hits"},
          {}};
  const FanTally& f = tallies[0];
  t.addRow({"Caster fast path (production; sliceMesh crossings)", count(f.beams),
            count(f.caster_misses), count(f.missing), count(f.doubled)});
  for (std::size_t k = 0; k < variants().size(); ++k) {
    const Variant& v = variants()[k];
    const FanTally& b = tallies[k + 1];
    t.addRow({variantName(v), count(b.beams), v.is_float ? "-" : count(b.caster_misses),
              count(b.missing), count(b.doubled)});
  }
  record(t);
  EXPECT_EQ(f.caster_misses, 0) << "the planar fast path leaked";
  EXPECT_EQ(f.missing, 0) << "a beam crossed no outline segment";
  EXPECT_EQ(f.doubled, 0) << "a beam crossed two outline segments at a shared endpoint";
  EXPECT_EQ(tallies[1].caster_misses, 0) << "the per-beam Caster (watertight) leaked";
  EXPECT_EQ(tallies[1].missing, 0) << "watertight (double) missed a beam";
  EXPECT_EQ(tallies[1].doubled, 0) << "watertight (double) hit two triangles with one beam";
}

Eigen::Isometry3d yawPose(const Vector3d& at, double yaw) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = Eigen::AngleAxisd(yaw, Vector3d::UnitZ()).toRotationMatrix();
  p.translation() = at;
  return p;
}

// 1c. The scan plane z = 0 runs through the icosphere's equator (a ring of vertices and edges with
// z exactly 0) and through a row of the box room's grid; the star prism's corners lie exactly on
// the beams (corner = 2^k times the beam's own direction, so the beam passes through it without
// rounding), with a vertex row at z = 0.
TEST(StressFans, PlanarFansThroughVertexRings) {
  Rng rng(1201);
  const std::vector<int> samples = {360, 720, 1000, 1441};
  std::vector<FanCase> cases;
  FanCase sphere{transformed(makeIcosphere(3), 2.0, Eigen::Isometry3d::Identity()), {}, {}};
  FanCase room{makeBoxRoom(Vector3d(4, 3, 2.5), 4), {}, {}};
  for (int s = 0; s < 8; ++s) {
    const double a0 = s % 2 ? -M_PI : uniform(rng, -7, 7);
    sphere.sensors.push_back(yawPose(Vector3d(uniform(rng, -0.7, 0.7), uniform(rng, -0.7, 0.7), 0),
                                     uniform(rng, -4, 4)));
    sphere.patterns.push_back(fan(a0, 2 * M_PI, samples[s % samples.size()]));
    room.sensors.push_back(yawPose(Vector3d(uniform(rng, -1.8, 1.8), uniform(rng, -1.3, 1.3), 0),
                                   uniform(rng, -4, 4)));
    room.patterns.push_back(fan(a0, 2 * M_PI, samples[(s + 1) % samples.size()]));
  }
  cases.push_back(std::move(sphere));
  cases.push_back(std::move(room));
  for (const int n : {360, 720}) {
    for (const int every : {1, 2}) {
      core::FanSpec spec;
      spec.angle_min = -M_PI + 0.01;
      spec.angle_max = spec.angle_min + 2 * M_PI * (n - 1) / n;
      spec.angle_increment = 2 * M_PI / n;
      const core::ScanPattern pattern(spec);
      std::vector<Eigen::Vector2d> star;
      for (int i = 0; i < n; i += every) {
        const double r = (i / every) % 2 ? 2.0 : 4.0;
        star.emplace_back(r * pattern.directions()[i].x(), r * pattern.directions()[i].y());
      }
      cases.push_back(
          {makePrism(star, {-1.0, 0.0, 1.0}), {Eigen::Isometry3d::Identity()}, {pattern}});
    }
  }
  const auto tallies = runFans(cases);
  recordFans("1c", "1c. Leaks: planar fans through rings of vertices",
             "Scan plane exactly through the icosphere's equator (8 sensors) and a grid row of a "
             "box room (8 sensors), and through the corners of star prisms whose corners lie on "
             "the beams. Fast path: `sliceMesh` must count exactly one crossing per beam; per-beam "
             "path: the Caster with each method in double; brute force: every triangle, each "
             "variant. Asserted on production (fast path, per-beam watertight, brute-force "
             "watertight double): all 0.",
             tallies);
  EXPECT_GT(tallies[0].beams, 10000);
}

// 1d. The real hexagon, cut by a tilted scan plane through three of its vertices (two on the top
// rim, one on the bottom rim, 120 degrees apart), so that the outline runs through them (to the
// rounding of the sensor pose).
TEST(StressFans, PlanarFansThroughRealMeshVertices) {
  REQUIRE_SHARED_DATA();
  Rng rng(1301);
  const TriMesh mesh = loadSharedMesh("hexagon.dae", 0.8);
  std::vector<Vector3d> top, bottom;
  core::Aabb box;
  for (const Vector3d& v : mesh.vertices) box.grow(v);
  for (const Vector3d& v : mesh.vertices) (v.z() == box.hi.z() ? top : bottom).push_back(v);
  ASSERT_EQ(top.size(), 6u);
  ASSERT_EQ(bottom.size(), 6u);
  auto by_angle = [](const Vector3d& a, const Vector3d& b) {
    return std::atan2(a.y(), a.x()) < std::atan2(b.y(), b.x());
  };
  std::sort(top.begin(), top.end(), by_angle);
  std::sort(bottom.begin(), bottom.end(), by_angle);
  FanCase c{mesh, {}, {}};
  for (int k = 0; k < 6; ++k) {
    const Vector3d& p0 = top[k];
    const Vector3d& p1 = bottom[(k + 2) % 6];
    const Vector3d& p2 = top[(k + 4) % 6];
    const Vector3d centroid = (p0 + p1 + p2) / 3.0;
    const Vector3d z = (p1 - p0).cross(p2 - p0).normalized();
    const Vector3d x = (p0 - centroid).normalized();
    Eigen::Matrix3d r;
    r.col(0) = x;
    r.col(1) = z.cross(x);
    r.col(2) = z;
    for (int s = 0; s < 3; ++s) {
      Eigen::Isometry3d sensor = Eigen::Isometry3d::Identity();
      sensor.linear() = r * Eigen::AngleAxisd(uniform(rng, -4, 4), Vector3d::UnitZ());
      sensor.translation() =
          centroid + r.col(0) * uniform(rng, -0.2, 0.2) + r.col(1) * uniform(rng, -0.2, 0.2);
      c.sensors.push_back(sensor);
      c.patterns.push_back(fan(uniform(rng, -4, 4), 2 * M_PI, 720 + 361 * s));
    }
  }
  const auto tallies = runFans({c});
  recordFans("1d", "1d. Leaks: planar fans through vertices of a real mesh",
             "`hexagon.dae` (scale 0.8) cut by 6 tilted scan planes, each through two top and one "
             "bottom vertex, 3 sensors per plane. Same figures and assertions as 1c.",
             tallies);
}

}  // namespace
}  // namespace laser_raycast_test
