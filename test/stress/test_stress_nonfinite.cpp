// Stress case 6: non-finite input. NaN, +Inf or -Inf in a vertex, the ray origin or the direction,
// a zero direction, and a NaN interval: no hit and no crash at the triangle and through the BVH;
// Mesh rejects non-finite vertices; through the Caster and the MeasurementModel a non-finite sensor pose
// makes every beam NaN (REP 117: erroneous), and a non-finite frame pose drops only that frame.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/mesh.h"
#include "laser_raycast/core/measurement_model.h"
#include "random.h"
#include "stress_report.h"

namespace laser_raycast_test {
namespace {

using core::Vec3;
using Eigen::Vector3d;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
const double kBadValues[3] = {kNan, kInf, -kInf};

// A triangle and a ray that hits it, in double.
struct Case {
  std::array<Vector3d, 3> v;
  core::Ray ray;
};

// Every corruption of one value (each component of each vertex, of the origin and of the
// direction, by NaN, +Inf and -Inf), a zero direction, and NaN tmin or tmax.
std::vector<Case> corruptions(const Case& base) {
  std::vector<Case> out;
  for (int target = 0; target < 5; ++target) {
    for (int k = 0; k < 3; ++k) {
      for (const double bad : kBadValues) {
        Case c = base;
        Vector3d& p = target < 3 ? c.v[target] : target == 3 ? c.ray.origin : c.ray.dir;
        p[k] = bad;
        out.push_back(c);
      }
    }
  }
  Case c = base;
  c.ray.dir.setZero();
  out.push_back(c);
  c = base;
  c.ray.tmin = kNan;
  out.push_back(c);
  c = base;
  c.ray.tmax = kNan;
  out.push_back(c);
  return out;
}

template <typename T>
core::RayT<T> cast(const core::Ray& ray) {
  core::RayT<T> r;
  r.origin = ray.origin.cast<T>();
  r.dir = ray.dir.cast<T>();
  r.tmin = T(ray.tmin);
  r.tmax = T(ray.tmax);
  return r;
}

struct Tally {
  long cases = 0, hits = 0;
  std::string cell() const { return count(hits) + " / " + count(cases); }
};

TEST(StressNonFinite, TriangleAndBvhNeverHit) {
  Rng rng(6001);
  std::vector<Tally> triangle(variants().size()), closest(variants().size()),
      any(variants().size());
  // Triangle level: random triangles, each with a ray aimed at its centroid (which hits).
  for (int n = 0; n < 100; ++n) {
    Case base;
    for (auto& p : base.v) p = uniformInCube(rng, 1.0);
    base.ray.origin = 3.0 * randomUnitVector(rng);
    base.ray.dir = (base.v[0] + base.v[1] + base.v[2]) / 3.0 - base.ray.origin;
    for (const Case& c : corruptions(base)) {
      for (std::size_t vi = 0; vi < variants().size(); ++vi) {
        dispatchVariant(variants()[vi], [&](auto m, auto x) {
          using T = decltype(x);
          ++triangle[vi].cases;
          triangle[vi].hits += core::intersectTriangle<decltype(m)::value>(
                                   cast<T>(c.ray), Vec3<T>(c.v[0].cast<T>()),
                                   Vec3<T>(c.v[1].cast<T>()), Vec3<T>(c.v[2].cast<T>()))
                                   .has_value();
        });
      }
    }
  }
  // Through the BVH: rays from inside an icosphere (they all hit it), corrupted the same way
  // (origin, direction, zero direction, NaN interval).
  const TriMesh sphere = transformed(makeIcosphere(2), 2.0, randomPose(rng, 1.0));
  const core::Bvh bvh = core::Bvh::build(sphere.vertices, sphere.triangles);
  const core::BvhF bvh_f = core::BvhF::build(sphere.vertices, sphere.triangles);
  for (int n = 0; n < 100; ++n) {
    Case base;
    base.v = {Vector3d::Zero(), Vector3d::Zero(), Vector3d::Zero()};  // unused: the mesh's
    base.ray.origin = bvh.bounds().center() + uniformInCube(rng, 0.5);
    base.ray.dir = randomUnitVector(rng);
    const std::vector<Case> all = corruptions(base);
    for (std::size_t k = 27; k < all.size(); ++k) {  // after the 27 vertex corruptions
      const Case& c = all[k];
      for (std::size_t vi = 0; vi < variants().size(); ++vi) {
        dispatchVariant(variants()[vi], [&](auto m, auto x) {
          using T = decltype(x);
          constexpr TriangleMethod M = decltype(m)::value;
          const auto& b = pick(bvh, bvh_f, T{});
          ++closest[vi].cases;
          closest[vi].hits += b.template closestHit<M>(cast<T>(c.ray)).has_value();
          ++any[vi].cases;
          any[vi].hits += b.template anyHit<M>(cast<T>(c.ray));
        });
      }
    }
  }
  Table t{"6a",
          "6a. Non-finite input: hits / cases",
          "Triangle: 100 random triangles, each with a ray that hits it, then one value replaced "
          "by NaN, +Inf or -Inf (every vertex, origin and direction component), a zero direction, "
          "or a NaN tmin or tmax (48 cases each). BVH: 100 rays from inside an icosphere, the "
          "origin, direction or interval corrupted the same way (21 cases each). Asserted on "
          "production: no hit.",
          {"method", "triangle", "BVH closest hit", "BVH any hit"},
          {}};
  for (std::size_t vi = 0; vi < variants().size(); ++vi) {
    t.addRow(
        {variantName(variants()[vi]), triangle[vi].cell(), closest[vi].cell(), any[vi].cell()});
  }
  record(t);
  ASSERT_TRUE(isProduction(variants()[0]));
  EXPECT_EQ(triangle[0].cases, 4800);
  EXPECT_EQ(closest[0].cases, 2100);
  EXPECT_EQ(triangle[0].hits, 0);
  EXPECT_EQ(closest[0].hits, 0);
  EXPECT_EQ(any[0].hits, 0);
}

// The production pipeline: Mesh, ScanPattern, Caster and MeasurementModel.
TEST(StressNonFinite, PipelineReportsNanOrRejects) {
  // Mesh rejects a non-finite vertex (in the vertex list, used or not).
  const TriMesh cube = makeBoxRoom(Vector3d(1, 1, 1), 1);
  long mesh_cases = 0, mesh_rejected = 0;
  for (const std::size_t index : {std::size_t(0), cube.vertices.size() - 1}) {
    for (int k = 0; k < 3; ++k) {
      for (const double bad : kBadValues) {
        TriMesh m = cube;
        m.vertices[index][k] = bad;
        ++mesh_cases;
        try {
          core::Mesh mesh(m.vertices, m.triangles);
        } catch (const std::invalid_argument&) {
          ++mesh_rejected;
        }
      }
    }
  }
  // ScanPattern rejects non-finite angles, increments and elevations.
  long pattern_cases = 0, pattern_rejected = 0;
  auto expect_rejected = [&](const core::FanSpec& spec, std::vector<double> elevations) {
    ++pattern_cases;
    try {
      core::ScanPattern pattern(spec, std::move(elevations));
    } catch (const std::invalid_argument&) {
      ++pattern_rejected;
    }
  };
  for (const double bad : kBadValues) {
    expect_rejected(core::FanSpec{bad, 1, 0, 10}, {0.0});
    expect_rejected(core::FanSpec{-1, bad, 0, 10}, {0.0});
    expect_rejected(core::FanSpec{-1, 1, bad, 0}, {0.0});
    expect_rejected(core::FanSpec{-1, 1, 0, 10}, {0.1, bad});
  }

  // A closed room and a sphere on two frames.
  core::Scene scene;
  const int label = scene.addLabel("thing");
  core::Body room, ball;
  room.frame = scene.addFrame("room");
  ball.frame = scene.addFrame("ball");
  room.label = ball.label = label;
  const TriMesh room_mesh = makeBoxRoom(Vector3d(8, 6, 3), 2);
  room.shape = std::make_shared<const core::Mesh>(room_mesh.vertices, room_mesh.triangles);
  ball.shape = core::Sphere{0.5};
  ball.frame_from_body.translation() = Vector3d(2, 0, 0);
  scene.addBody(room);
  scene.addBody(ball);
  const core::FramePoses good = core::FramePoses::identity(scene);
  const core::ScanPattern planar(core::FanSpec{-M_PI, M_PI, 0, 720});
  const core::ScanPattern rings(core::FanSpec{-M_PI, M_PI, 0, 360}, {-0.2, 0.2});
  core::MeasurementConfig measurement_config;
  measurement_config.range_min = 0.1;
  measurement_config.range_max = 20;
  core::MeasurementModel model(measurement_config);

  // Non-finite sensor poses: a translation component or a rotation entry.
  std::vector<Eigen::Isometry3d> bad_sensors;
  for (const double bad : kBadValues) {
    for (int k = 0; k < 3; ++k) {
      Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
      p.translation()[k] = bad;
      bad_sensors.push_back(p);
      p = Eigen::Isometry3d::Identity();
      p.linear()(k, (k + 1) % 3) = bad;
      bad_sensors.push_back(p);
    }
  }
  long sensor_beams = 0, sensor_not_nan = 0, encoded_not_nan = 0, labelled = 0;
  for (const Eigen::Isometry3d& sensor : bad_sensors) {
    for (const core::ScanPattern* pattern : {&planar, &rings}) {
      for (const bool fast : {true, false}) {
        core::CastConfig config;
        config.planar_fast_path = fast;
        core::Caster caster;
        // A good cast first, so that a stale result cannot pass for the NaN one.
        caster.cast(scene, good, Eigen::Isometry3d::Identity(), *pattern, config);
        const core::ScanResult& r = caster.cast(scene, good, sensor, *pattern, config);
        core::MeasuredScan out;
        model.measure(scene, r, {}, &out);
        for (int i = 0; i < pattern->size(); ++i) {
          ++sensor_beams;
          sensor_not_nan += !std::isnan(r.range[i]);
          encoded_not_nan += !std::isnan(out.ranges[i]);
          labelled += out.labels[i] != -1;
        }
      }
    }
  }
  // A non-finite frame pose: that frame's bodies are skipped, the others cast normally.
  long frame_casts = 0, frames_skipped = 0, frame_nan = 0, ball_seen = 0;
  for (const double bad : kBadValues) {
    core::FramePoses poses = good;
    poses.pose[room.frame].translation().x() = bad;
    for (const bool fast : {true, false}) {
      core::CastConfig config;
      config.planar_fast_path = fast;
      core::Caster caster;
      const core::ScanResult& r =
          caster.cast(scene, poses, Eigen::Isometry3d::Identity(), planar, config);
      core::MeasuredScan out;
      model.measure(scene, r, {}, &out);
      ++frame_casts;
      frames_skipped += r.stats.bodies_skipped == 1;
      for (int i = 0; i < planar.size(); ++i) {
        frame_nan += std::isnan(r.range[i]) || std::isnan(out.ranges[i]);
        ball_seen += r.body[i] == 1;
      }
    }
  }
  Table t{"6b",
          "6b. Non-finite input through the production pipeline",
          "Sensor poses with a NaN, +Inf or -Inf translation component or rotation entry (18), "
          "cast with the fast path and per-beam, planar and on two cones, then encoded (REP "
          "117: NaN = erroneous).",
          {"check", "result"},
          {}};
  t.addRow({"Mesh: non-finite vertex rejected (std::invalid_argument)",
            count(mesh_rejected) + " / " + count(mesh_cases)});
  t.addRow({"ScanPattern: non-finite angle, increment or elevation rejected",
            count(pattern_rejected) + " / " + count(pattern_cases)});
  t.addRow({"Caster: beams NaN under a non-finite sensor pose",
            count(sensor_beams - sensor_not_nan) + " / " + count(sensor_beams)});
  t.addRow({"MeasurementModel: ranges NaN, labels -1",
            count(sensor_beams - encoded_not_nan) + " / " + count(sensor_beams) + ", " +
                count(sensor_beams - labelled) + " / " + count(sensor_beams)});
  t.addRow({"Non-finite frame pose: frame skipped, no NaN beam",
            count(frames_skipped) + " / " + count(frame_casts) + ", " + count(frame_nan) + " NaN"});
  record(t);
  EXPECT_EQ(mesh_rejected, mesh_cases);
  EXPECT_EQ(pattern_rejected, pattern_cases);
  EXPECT_EQ(sensor_beams, 18 * 2 * (720 + 720));
  EXPECT_EQ(sensor_not_nan, 0);
  EXPECT_EQ(encoded_not_nan, 0);
  EXPECT_EQ(labelled, 0);
  EXPECT_EQ(frames_skipped, frame_casts);
  EXPECT_EQ(frame_nan, 0);
  EXPECT_GT(ball_seen, 0);  // the other frame's body is still cast
}

}  // namespace
}  // namespace laser_raycast_test
