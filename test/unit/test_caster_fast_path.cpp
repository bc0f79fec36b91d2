// Caster: the planar fast path against the per-beam path and brute force; culling changes nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "cast_reference.h"
#include "fan_specs.h"
#include "laser_raycast/core/caster.h"
#include "mesh_builder.h"
#include "random.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

// -------------------------------------------------------------------------------------------------
// Planar fast path against the per-beam path

// Bearings (sensor frame, rad) where the scan plane crosses a mesh edge: the silhouettes of the
// slices, near which hit/miss is decided by rounding and the two paths may legitimately differ.
std::vector<double> sliceBearings(const Scene& scene, const FramePoses& poses,
                                  const Eigen::Isometry3d& world_from_sensor) {
  std::vector<double> out;
  for (const Body& body : scene.bodies()) {
    const auto* mesh = std::get_if<std::shared_ptr<const Mesh>>(&body.shape);
    if (!mesh || !poses.valid[body.frame]) continue;
    const Eigen::Isometry3d sensor_from_body =
        world_from_sensor.inverse(Eigen::Isometry) * poses.pose[body.frame] * body.frame_from_body;
    for (const auto& t : (*mesh)->triangles()) {
      Eigen::Vector3d p[3];
      for (int k = 0; k < 3; ++k) p[k] = sensor_from_body * (*mesh)->vertices()[t[k]];
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d& a = p[k];
        const Eigen::Vector3d& b = p[(k + 1) % 3];
        if ((a.z() <= 0) == (b.z() <= 0) && a.z() != 0 && b.z() != 0) continue;
        const Eigen::Vector3d x = a.z() == b.z() ? a : a + (b - a) * (a.z() / (a.z() - b.z()));
        out.push_back(std::atan2(x.y(), x.x()));
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

double angularDistance(double a, const std::vector<double>& sorted) {
  double best = kInf;
  for (const double shift : {-2 * M_PI, 0.0, 2 * M_PI}) {
    const auto it = std::lower_bound(sorted.begin(), sorted.end(), a + shift);
    if (it != sorted.end()) best = std::min(best, std::abs(*it - a - shift));
    if (it != sorted.begin()) best = std::min(best, std::abs(*(it - 1) - a - shift));
  }
  return best;
}

// Random scenes (closed spheres, boxes, triangle soups, a room, primitives) at random poses, random
// sensor poses (tilted, so the scan plane cuts the meshes obliquely) and random fans, with and
// without back-face culling and tmin: the fast path must give what the per-beam path gives, except
// within 1e-7 rad of a slice's silhouette, and both must match the brute force.
TEST(Caster, FastPathMatchesGeneralPath) {
  Rng rng(99);
  int compared = 0, hits = 0;
  for (int trial = 0; trial < 40; ++trial) {
    Scene scene;
    scene.addLabel("l");
    const int frames = 3;
    for (int f = 0; f < frames; ++f) scene.addFrame("f" + std::to_string(f));
    const auto room = gridBox(steps(-8, 9, 5), steps(-7, 8, 4), steps(-3, 4, 2), true);
    addBody(&scene, room, 0);
    for (int k = 0; k < 6; ++k) {
      const int frame = k % frames;
      const auto body_pose =
          pose(Eigen::Vector3d(uniform(rng, -5, 5), uniform(rng, -5, 5), uniform(rng, -1, 1)),
               randomRotation(rng).toRotationMatrix());
      switch (k % 6) {
        case 0:
          addBody(&scene, uvSphere(uniform(rng, 0.3, 1.5), 8 + k, 12 + k), frame, body_pose);
          break;
        case 1:
          addBody(&scene, gridBox(steps(-0.5, 0.7, 2), steps(-0.3, 0.4, 3), steps(-1, 1, 2), false),
                  frame, body_pose);
          break;
        case 2:
          addBody(&scene, randomSoup(rng, 300, 1.5, 0.4), frame, body_pose);
          break;
        case 3:
          addBody(&scene, Sphere{uniform(rng, 0.2, 1)}, frame, body_pose);
          break;
        case 4:
          addBody(&scene, Box{Eigen::Vector3d(0.5, 1, 1.5)}, frame, body_pose);
          break;
        default:
          addBody(&scene, prism(circle(17, 0.6), {-0.5, 0.0, 0.5}, false), frame, body_pose);
      }
    }
    FramePoses poses = FramePoses::identity(scene);
    for (int f = 1; f < frames; ++f) {
      poses.pose[f] =
          pose(Eigen::Vector3d(uniform(rng, -1, 1), uniform(rng, -1, 1), 0),
               rpy(uniform(rng, -0.2, 0.2), uniform(rng, -0.2, 0.2), uniform(rng, -3, 3)));
    }
    const auto sensor =
        pose(Eigen::Vector3d(uniform(rng, -2, 2), uniform(rng, -2, 2), uniform(rng, -0.5, 0.5)),
             rpy(uniform(rng, -0.5, 0.5), uniform(rng, -0.5, 0.5), uniform(rng, -3, 3)));
    // Fans: full turn, a partial window, more than a turn, coarse and fine.
    const double a0 = uniform(rng, -4, 1);
    const FanSpec fans[] = {
        fanBySamples(-M_PI, M_PI, 1000), fanBySamples(a0, a0 + uniform(rng, 0.3, 3), 333),
        fanByIncrement(a0, a0 + 7.5, uniform(rng, 0.005, 0.05)), fanBySamples(a0, a0 + 6, 17)};
    const ScanPattern pattern(fans[trial % 4]);
    CastConfig general = config(false, uniform(rng, 4, 30));
    general.cull_backfaces = trial % 3 == 1;
    general.tmin = trial % 5 == 2 ? uniform(rng, 0.1, 2) : 0.0;
    CastConfig fast = general;
    fast.planar_fast_path = true;

    const ScanResult rf = cast(scene, poses, sensor, pattern, fast);
    const ScanResult rg = cast(scene, poses, sensor, pattern, general);
    const auto truth = bruteForce(scene, poses, sensor, pattern, general);
    const auto bearings = sliceBearings(scene, poses, sensor);
    EXPECT_EQ(rf.stats.bodies_culled, rg.stats.bodies_culled);
    for (int i = 0; i < pattern.size(); ++i) {
      const double azimuth = pattern.azimuth(i);
      if (angularDistance(azimuth, bearings) < 1e-7) continue;
      // Hits within rounding of tmin or tmax may fall either side of it.
      if (near(truth[i].t, general.tmax, 1e-9) || near(truth[i].t, general.tmin, 1e-9)) continue;
      ++compared;
      ASSERT_TRUE(near(rf.range[i], rg.range[i], 1e-9))
          << "trial " << trial << " beam " << i << ": fast " << rf.range[i] << " general "
          << rg.range[i] << " truth " << truth[i].t;
      ASSERT_TRUE(near(rg.range[i], truth[i].t, 1e-9)) << "trial " << trial << " beam " << i;
      if (!near(truth[i].t, truth[i].second_body_t, 1e-9)) {
        ASSERT_EQ(rf.body[i], rg.body[i]) << "trial " << trial << " beam " << i;
        ASSERT_EQ(rg.body[i], truth[i].body) << "trial " << trial << " beam " << i;
      }
      if (std::isfinite(rf.range[i])) ++hits;
    }
  }
  EXPECT_GT(compared, 10000);
  EXPECT_GT(hits, 5000);
}

// -------------------------------------------------------------------------------------------------
// Culling

// Bodies beyond tmax, wholly nearer than tmin, off the scan plane, or outside the fan's window are
// counted in stats.bodies_culled (by hand below) and change nothing: both paths equal the brute
// force over every body.
TEST(Caster, CullingCountsAndChangesNothing) {
  Scene scene = sceneWithFrame();
  auto cube = gridBox(steps(-0.5, 0.5, 1), steps(-0.5, 0.5, 1), steps(-0.5, 0.5, 1), false);
  addBody(&scene, Sphere{0.5}, 0, pose(Eigen::Vector3d(3, 0, 0)));   // 0 visible
  addBody(&scene, Sphere{0.5}, 0, pose(Eigen::Vector3d(20, 0, 0)));  // 1 beyond tmax
  addBody(&scene, Sphere{0.5}, 0, pose(Eigen::Vector3d(3, 0, 2)));   // 2 above the plane
  addBody(&scene, Sphere{0.5}, 0, pose(Eigen::Vector3d(-3, 0, 0)));  // 3 behind the fan
  addBody(&scene, cube, 0, pose(Eigen::Vector3d(0, 15, 0)));         // 4 beyond tmax
  addBody(&scene, cube, 0, pose(Eigen::Vector3d(2, 2, 3)));  // 5 above the plane and every ring
  addBody(&scene, cube, 0, pose(Eigen::Vector3d(0.3, -4, 0), yaw(0.3)));  // 6 at the fan's edge
  addBody(&scene, Sphere{0.1}, 0, pose(Eigen::Vector3d(0.2, 0, 0)));      // 7 nearer than tmin
  addBody(&scene, Cylinder{0.4, 1}, 0, pose(Eigen::Vector3d(1, 3, 0)));   // 8 visible
  addBody(&scene, cube, 0, pose(Eigen::Vector3d(-2, -2, 0)));             // 9 behind the fan
  const FramePoses poses = FramePoses::identity(scene);
  CastConfig base = config(true, 10.0);
  base.tmin = 0.5;
  const ScanPattern planar(fanBySamples(-M_PI / 2, M_PI / 2, 361));
  const ScanPattern rings(fanBySamples(-M_PI / 2, M_PI / 2, 181), {-0.7, -0.3, 0.0, 0.3, 0.6});
  struct Case {
    const ScanPattern* pattern;
    int culled;
  };
  // Planar: 1, 2, 3, 4, 5, 7, 9. Rings: the plane test does not apply, so 2 stays; 5 lies above
  // the highest ring (its lowest point is at 0.615 rad, the ring at 0.6), so no beam reaches it.
  for (const Case& c : {Case{&planar, 7}, Case{&rings, 6}}) {
    const auto truth = bruteForce(scene, poses, Eigen::Isometry3d::Identity(), *c.pattern, base);
    for (const bool fast : {true, false}) {
      CastConfig cfg = base;
      cfg.planar_fast_path = fast;
      const ScanResult r = cast(scene, poses, Eigen::Isometry3d::Identity(), *c.pattern, cfg);
      EXPECT_EQ(r.stats.bodies, 10);
      EXPECT_EQ(r.stats.bodies_culled, c.culled) << (fast ? "fast" : "general");
      EXPECT_EQ(r.stats.bodies_skipped, 0);
      expectMatchesTruth(r, truth, 1e-9, fast ? "fast" : "general");
    }
    // The planar fan's first beam (azimuth -pi/2) sees body 6, at the fan's edge.
    if (c.pattern == &planar) {
      EXPECT_EQ(truth[0].body, 6);
    }
  }
  int sees_2 = 0;
  for (const auto& t : bruteForce(scene, poses, Eigen::Isometry3d::Identity(), rings, base)) {
    sees_2 += t.body == 2;
  }
  EXPECT_GT(sees_2, 0);
}

// Random scenes with everything culled or not: the result never depends on culling, checked
// against the brute force for both paths and both pattern kinds.
TEST(Caster, RandomScenesMatchBruteForce) {
  Rng rng(1234);
  for (int trial = 0; trial < 12; ++trial) {
    Scene scene = sceneWithFrame();
    for (int k = 0; k < 12; ++k) {
      const auto p =
          pose(Eigen::Vector3d(uniform(rng, -15, 15), uniform(rng, -15, 15), uniform(rng, -3, 3)),
               randomRotation(rng).toRotationMatrix());
      if (k % 3 == 0) addBody(&scene, uvSphere(uniform(rng, 0.3, 2), 6, 10), 0, p);
      if (k % 3 == 1) addBody(&scene, Cylinder{uniform(rng, 0.2, 1), uniform(rng, 0.5, 3)}, 0, p);
      if (k % 3 == 2) addBody(&scene, Box{Eigen::Vector3d(1, 2, 0.5)}, 0, p);
    }
    const FramePoses poses = FramePoses::identity(scene);
    const auto sensor =
        pose(Eigen::Vector3d(uniform(rng, -2, 2), uniform(rng, -2, 2), 0),
             rpy(uniform(rng, -0.2, 0.2), uniform(rng, -0.2, 0.2), uniform(rng, -3, 3)));
    const double a0 = uniform(rng, -3, 0);
    const ScanPattern planar(fanBySamples(a0, a0 + uniform(rng, 0.5, 3), 500));
    const ScanPattern rings(fanBySamples(a0, a0 + 2, 120), {-0.5, -0.1, 0.0, 0.3});
    CastConfig base = config(true, uniform(rng, 5, 20));
    base.tmin = uniform(rng, 0, 1);
    for (const ScanPattern* pattern : {&planar, &rings}) {
      const auto truth = bruteForce(scene, poses, sensor, *pattern, base);
      for (const bool fast : {true, false}) {
        CastConfig cfg = base;
        cfg.planar_fast_path = fast;
        expectMatchesTruth(cast(scene, poses, sensor, *pattern, cfg), truth, 1e-9,
                           "trial " + std::to_string(trial));
        if (HasFatalFailure()) return;
      }
    }
  }
}

// Beams grazing an upright cylinder's side, where the tube's pre-test (a beam line's distance from
// the axis, in float) decides what the exact test sees: fans of 2001 beams within 1e-6 rad of
// each silhouette bearing, from near and far, for thin and thick cylinders, planar and in rings
// just off the plane, against the brute force.
TEST(Caster, BeamsGrazingACylinderMatchBruteForce) {
  Rng rng(77);
  int hits = 0, misses = 0;
  for (const double distance : {0.7, 4.0, 45.0}) {
    for (const double radius : {0.03, 0.4, 2.0}) {
      if (radius >= distance) continue;
      Scene scene = sceneWithFrame();
      const double bearing = uniform(rng, -3, 3);
      addBody(&scene, Cylinder{radius, 1.0}, 0,
              pose(Eigen::Vector3d(distance * std::cos(bearing), distance * std::sin(bearing),
                                   uniform(rng, -0.3, 0.3)),
                   yaw(uniform(rng, -3, 3))));
      const FramePoses poses = FramePoses::identity(scene);
      const CastConfig base = config(true, 100);
      for (const double side : {-1.0, 1.0}) {
        const double tangent = bearing + side * std::asin(radius / distance);
        const ScanPattern planar(fanBySamples(tangent - 1e-6, tangent + 1e-6, 2001));
        const ScanPattern rings(fanBySamples(tangent - 1e-6, tangent + 1e-6, 2001),
                                {-0.01, 0.0, 0.02});
        for (const ScanPattern* pattern : {&planar, &rings}) {
          const auto truth =
              bruteForce(scene, poses, Eigen::Isometry3d::Identity(), *pattern, base);
          for (const auto& t : truth) (std::isfinite(t.t) ? hits : misses) += 1;
          expectMatchesTruth(
              cast(scene, poses, Eigen::Isometry3d::Identity(), *pattern, base), truth, 1e-9,
              "distance " + std::to_string(distance) + " radius " + std::to_string(radius));
          if (HasFatalFailure()) return;
        }
      }
    }
  }
  // The fans straddle the silhouettes: both kinds of beam are there.
  EXPECT_GT(hits, 1000);
  EXPECT_GT(misses, 1000);
}

// A room of primitives as a warehouse builds one: floor, roof and walls (large for their distance,
// so the walk casts them after everything else, over beams mostly closed by then), and clutter
// that stands in the floor and against the walls, so that many beams first hit something just
// beyond the floor's or a wall's nearest distance and the large primitive must still win them.
// Rings from random poses, against the brute force, with occlusion culling on and off.
TEST(Caster, RoomsOfPrimitivesWithClutterMatchBruteForce) {
  Rng rng(4321);
  long long hits = 0;
  for (int trial = 0; trial < 8; ++trial) {
    Scene scene = sceneWithFrame();
    const double half = uniform(rng, 3, 8), height = uniform(rng, 2, 4);
    addBody(&scene, Box{Eigen::Vector3d(2 * half, 2 * half, 0.2)}, 0,
            pose(Eigen::Vector3d(0, 0, -0.1)));  // floor
    addBody(&scene, Box{Eigen::Vector3d(2 * half, 2 * half, 0.2)}, 0,
            pose(Eigen::Vector3d(0, 0, height + 0.1)));  // roof
    for (const double side : {-1.0, 1.0}) {
      addBody(&scene, Box{Eigen::Vector3d(2 * half, 0.2, height)}, 0,
              pose(Eigen::Vector3d(0, side * (half + 0.1), height / 2)));
      addBody(&scene, Box{Eigen::Vector3d(0.2, 2 * half, height)}, 0,
              pose(Eigen::Vector3d(side * (half + 0.1), 0, height / 2)));
    }
    for (int k = 0; k < 30; ++k) {
      // Sunk into the floor (centre near z = 0) or pushed into a wall.
      Eigen::Vector3d at(uniform(rng, -half, half), uniform(rng, -half, half),
                         uniform(rng, -0.2, 0.3));
      if (k % 3 == 2) at.x() = (k % 2 ? 1 : -1) * (half + uniform(rng, -0.3, 0.1));
      const auto p = pose(at, randomRotation(rng).toRotationMatrix());
      if (k % 3 == 0)
        addBody(&scene, Box{Eigen::Vector3d(uniform(rng, 0.2, 1.2), uniform(rng, 0.2, 1.2), 0.4)},
                0, p);
      if (k % 3 == 1) addBody(&scene, Cylinder{uniform(rng, 0.1, 0.5), uniform(rng, 0.3, 1)}, 0, p);
      if (k % 3 == 2) addBody(&scene, Sphere{uniform(rng, 0.2, 0.6)}, 0, p);
    }
    const FramePoses poses = FramePoses::identity(scene);
    const auto sensor =
        pose(Eigen::Vector3d(uniform(rng, -half, half) * 0.8, uniform(rng, -half, half) * 0.8,
                             uniform(rng, 0.2, 1.0)),
             rpy(uniform(rng, -0.1, 0.1), uniform(rng, -0.1, 0.1), uniform(rng, -3, 3)));
    std::vector<double> elevations;
    for (int r = 0; r < 24; ++r) elevations.push_back(-0.9 + 1.3 * r / 23);
    const ScanPattern rings(fanBySamples(-M_PI, M_PI, 360), elevations);
    CastConfig base = config(true, 30);
    const auto truth = bruteForce(scene, poses, sensor, rings, base);
    for (const bool culling : {true, false}) {
      CastConfig cfg = base;
      cfg.occlusion_culling = culling;
      expectMatchesTruth(cast(scene, poses, sensor, rings, cfg), truth, 1e-9,
                         "trial " + std::to_string(trial));
      if (HasFatalFailure()) return;
    }
    for (const auto& t : truth) hits += std::isfinite(t.t);
  }
  EXPECT_GT(hits, 8 * 360 * 24 * 9 / 10);
}

}  // namespace
}  // namespace laser_raycast_test
