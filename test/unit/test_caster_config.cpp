// Caster: what CastConfig changes (back-face culling, tmin) and its validation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "cast_reference.h"
#include "expect_invalid.h"
#include "fan_specs.h"
#include "laser_raycast/core/caster.h"
#include "mesh_builder.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

// A room wound inward is all front faces from inside; wound outward, all back faces. With
// cull_backfaces the outward room vanishes from inside but is seen from outside; both paths.
TEST(Caster, CullBackfaces) {
  const auto xs = steps(-3, 3, 4), ys = steps(-2, 4, 3), zs = steps(-1, 1, 2);
  const auto inward = gridBox(xs, ys, zs, true), outward = gridBox(xs, ys, zs, false);
  const ScanPattern planar(fanBySamples(-M_PI, M_PI, 720));
  const ScanPattern rings(fanBySamples(-M_PI, M_PI, 180), {-0.5, 0.0, 0.5});
  const auto inside = pose(Eigen::Vector3d(0.5, 0.25, 0.1), yaw(0.3));
  const auto outside = pose(Eigen::Vector3d(-6, 0.5, 0), yaw(0.05));
  for (const ScanPattern* pattern : {&planar, &rings}) {
    for (const bool fast : {true, false}) {
      for (const bool cull : {false, true}) {
        CastConfig c = config(fast);
        c.cull_backfaces = cull;
        for (const bool in : {true, false}) {
          Scene scene = sceneWithFrame();
          addBody(&scene, in ? inward : outward, 0);
          const FramePoses poses = FramePoses::identity(scene);
          const ScanResult r = cast(scene, poses, inside, *pattern, c);
          const int expected_misses = cull && !in ? pattern->size() : 0;
          EXPECT_EQ(misses(r), expected_misses)
              << (fast ? "fast" : "general") << (cull ? " cull" : "")
              << (in ? " inward" : " outward");
          // From outside, some walls face the sensor and some face away: against the brute force.
          const ScanResult o = cast(scene, poses, outside, *pattern, c);
          expectMatchesTruth(o, bruteForce(scene, poses, outside, *pattern, c), 1e-9, "outside");
          EXPECT_GT(pattern->size() - misses(o), 0);
        }
      }
    }
  }
}

// tmin: surfaces nearer than tmin are invisible and what lies beyond is reported; at exactly tmin a
// surface is visible (inclusive). A thin mesh panel and a small sphere in front of a wall.
TEST(Caster, TminHidesNearerSurfaces) {
  MeshBuilder panel;
  const auto a = panel.vertex(Eigen::Vector3d(1, -0.5, -0.5)),
             b = panel.vertex(Eigen::Vector3d(1, 0.5, -0.5)),
             c = panel.vertex(Eigen::Vector3d(1, 0.5, 0.5)),
             d = panel.vertex(Eigen::Vector3d(1, -0.5, 0.5));
  panel.quad(a, b, c, d, Eigen::Vector3d(-1, 0, 0));
  MeshBuilder wall;
  const auto e = wall.vertex(Eigen::Vector3d(3, -5, -5)),
             f = wall.vertex(Eigen::Vector3d(3, 5, -5)), g = wall.vertex(Eigen::Vector3d(3, 5, 5)),
             h = wall.vertex(Eigen::Vector3d(3, -5, 5));
  wall.quad(e, f, g, h, Eigen::Vector3d(-1, 0, 0));
  const ScanPattern fan(fanBySamples(-0.1, 0.1, 5));
  const ScanPattern rings(fanBySamples(-0.1, 0.1, 5), {-0.05, 0.0, 0.05});
  for (const bool use_sphere : {false, true}) {
    Scene scene = sceneWithFrame();
    const int wall_body = addBody(&scene, wall.build(), 0);
    const int near_body = use_sphere
                              ? addBody(&scene, Sphere{0.2}, 0, pose(Eigen::Vector3d(1, 0, 0)))
                              : addBody(&scene, panel.build(), 0);
    const FramePoses poses = FramePoses::identity(scene);
    const double near_t = use_sphere ? 0.8 : 1.0;  // the near body's first surface at azimuth 0
    for (const ScanPattern* pattern : {&fan, &rings}) {
      const int mid = pattern->size() / 2;  // azimuth 0, elevation 0
      for (const bool fast : {true, false}) {
        CastConfig cfg = config(fast);
        cfg.tmin = 0;
        ScanResult r = cast(scene, poses, Eigen::Isometry3d::Identity(), *pattern, cfg);
        EXPECT_NEAR(r.range[mid], near_t, 1e-12);
        EXPECT_EQ(r.body[mid], near_body);
        const double first = r.range[mid];
        cfg.tmin = first;  // exactly the computed distance: inclusive
        r = cast(scene, poses, Eigen::Isometry3d::Identity(), *pattern, cfg);
        EXPECT_EQ(r.range[mid], first);
        EXPECT_EQ(r.body[mid], near_body);
        cfg.tmin = 1.5;  // past the panel and the whole sphere
        r = cast(scene, poses, Eigen::Isometry3d::Identity(), *pattern, cfg);
        for (int i = 0; i < pattern->size(); ++i) {
          EXPECT_EQ(r.body[i], wall_body) << i;
          const Eigen::Vector3d w = pattern->directions()[i];
          EXPECT_NEAR(r.range[i], 3 / w.x(), 1e-12) << i;
        }
        cfg.tmin = 3.5;  // past everything
        r = cast(scene, poses, Eigen::Isometry3d::Identity(), *pattern, cfg);
        EXPECT_EQ(misses(r), pattern->size());
      }
    }
  }
  // A sensor inside a sphere with tmin past its far side sees nothing of it.
  Scene scene = sceneWithFrame();
  addBody(&scene, Sphere{0.5}, 0);
  CastConfig cfg = config(true);
  cfg.tmin = 0.6;
  EXPECT_EQ(
      misses(cast(scene, FramePoses::identity(scene), Eigen::Isometry3d::Identity(), fan, cfg)),
      fan.size());
  cfg.tmin = 0.4;
  const ScanResult r =
      cast(scene, FramePoses::identity(scene), Eigen::Isometry3d::Identity(), fan, cfg);
  EXPECT_NEAR(r.range[2], 0.5, 1e-12);
}

// CastConfig::validate names the field and the value; cast() validates.
TEST(CastConfig, ValidateNamesFieldAndValue) {
  auto message = [](const CastConfig& c) { return invalidMessage([&] { c.validate(); }); };
  CastConfig c;
  EXPECT_NO_THROW(c.validate());
  c.tmin = -0.5;
  expectMentions(message(c), {"tmin", "-0.5"});
  c.tmin = kNan;
  expectMentions(message(c), {"tmin", "nan"});
  c.tmin = kInf;
  expectMentions(message(c), {"tmin", "inf"});
  c = CastConfig{};
  c.tmax = 0;
  expectMentions(message(c), {"tmax", "0"});
  c.tmin = 2;
  c.tmax = 2;
  expectMentions(message(c), {"tmax", "tmin", "2"});
  c.tmax = 1.5;
  expectMentions(message(c), {"tmax", "1.5", "tmin"});
  c.tmax = kNan;
  expectMentions(message(c), {"tmax", "nan"});
  c = CastConfig{};
  c.tmax = kInf;  // no far limit is allowed
  EXPECT_NO_THROW(c.validate());

  Scene scene = sceneWithFrame();
  addBody(&scene, Sphere{1}, 0, pose(Eigen::Vector3d(3, 0, 0)));
  c = CastConfig{};
  c.tmin = -1;
  Caster caster;
  EXPECT_THROW(caster.cast(scene, FramePoses::identity(scene), Eigen::Isometry3d::Identity(),
                           ScanPattern(fanBySamples(-1, 1, 3)), c),
               std::invalid_argument);
}

}  // namespace
}  // namespace laser_raycast_test
