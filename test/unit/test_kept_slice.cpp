// Kept slices of a frame's bodies by the scan plane (kept_slice.h): a planar cast through them
// gives the same result, bit for bit, as one that cuts the meshes again; they are built only for a
// plane met again, never used for another plane, another scene or a changed one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "cast_reference.h"
#include "fan_specs.h"
#include "random.h"
#include "random_scene.h"

namespace laser_raycast_test {
namespace {

void expectSameBits(const core::ScanResult& a, const core::ScanResult& b, const char* what) {
  ASSERT_EQ(a.range.size(), b.range.size());
  ASSERT_EQ(a.normal.size(), b.normal.size());
  for (std::size_t i = 0; i < a.range.size(); ++i) {
    const bool same =
        a.range[i] == b.range[i] || (std::isnan(a.range[i]) && std::isnan(b.range[i]));
    ASSERT_TRUE(same && a.body[i] == b.body[i] && a.triangle[i] == b.triangle[i])
        << what << ": beam " << i << " range " << a.range[i] << " vs " << b.range[i] << ", body "
        << a.body[i] << " vs " << b.body[i] << ", triangle " << a.triangle[i] << " vs "
        << b.triangle[i];
    if (!a.normal.empty()) {
      ASSERT_EQ(a.normal[i], b.normal[i]) << what << ": beam " << i;
    }
  }
}

// A sensor driving on a floor: level, at one height, anywhere and turned any way (a rotation about
// z with exact zeros, so that the plane's pose in every frame is the same bit for bit).
Eigen::Isometry3d onTheFloor(Rng& rng, double height) {
  return pose(Eigen::Vector3d(uniform(rng, -8, 8), uniform(rng, -8, 8), height),
              yaw(uniform(rng, -M_PI, M_PI)));
}

core::ScanResult castFresh(const RandomScene& rs, const Eigen::Isometry3d& sensor,
                           const core::ScanPattern& pattern, core::CastConfig config) {
  config.keep_slices = false;
  core::Caster caster;
  return caster.cast(rs.scene, rs.poses, sensor, pattern, config);
}

TEST(KeptSlice, KeptSlicesNeverChangeAResult) {
  Rng rng(53);
  int kept = 0, hits = 0;
  for (int s = 0; s < 4; ++s) {
    const RandomScene rs = randomScene(rng);
    const double height = uniform(rng, -0.5, 0.5);
    for (const core::ScanPattern& pattern : {core::ScanPattern(fanBySamples(-M_PI, M_PI, 720)),
                                             core::ScanPattern(fanBySamples(-2.35, 2.35, 1081))}) {
      core::CastConfig cfg = config(true, 25.0);
      cfg.compute_incidence = s % 2 == 1;
      cfg.cull_backfaces = s == 2;
      cfg.tmin = s == 3 ? 0.4 : 0.0;
      core::Caster caster;  // the same caster throughout, so that it keeps slices
      for (int cast = 0; cast < 8; ++cast) {
        const Eigen::Isometry3d sensor = onTheFloor(rng, height);
        cfg.threads = cast % 3 == 2 ? 2 : 1;
        caster.forget();
        const core::ScanResult& r = caster.cast(rs.scene, rs.poses, sensor, pattern, cfg);
        // The first cast meets the plane, the second keeps it for both frames.
        if (cast >= 1) {
          EXPECT_EQ(r.stats.kept_slices, 2) << "cast " << cast;
        }
        kept += r.stats.kept_slices;
        expectSameBits(castFresh(rs, sensor, pattern, cfg), r, "kept slices");
        for (const double range : r.range) hits += std::isfinite(range);
        if (HasFailure()) return;
      }
    }
  }
  EXPECT_GT(kept, 100);
  EXPECT_GT(hits, 10000);
}

// A laser on a turning base, its pose composed as TF composes it: its height h comes out as h (c^2
// + s^2) of the base's heading quaternion (c, s), off by a few ulp from one heading to the next.
// Its plane is still met again (ScanPlane keeps 44 bits), and the casts keep their bits.
TEST(KeptSlice, APlaneOffByUlpsFromTfsCompositionIsMetAgain) {
  Rng rng(61);
  const RandomScene rs = randomScene(rng);
  const core::ScanPattern pattern(fanBySamples(-2.35, 2.35, 1081));
  const core::CastConfig cfg = config(true, 25.0);
  core::Caster caster;
  std::vector<double> heights;
  for (int cast = 0; cast < 12; ++cast) {
    const double heading = uniform(rng, -M_PI, M_PI);
    const double c = std::cos(heading / 2), s = std::sin(heading / 2);
    const double height = 0.3 * (c * c + s * s);
    heights.push_back(height);
    const Eigen::Isometry3d sensor =
        pose(Eigen::Vector3d(uniform(rng, -8, 8), uniform(rng, -8, 8), height), yaw(heading));
    const core::ScanResult& r = caster.cast(rs.scene, rs.poses, sensor, pattern, cfg);
    if (cast >= 1) {
      EXPECT_EQ(r.stats.kept_slices, 2) << "cast " << cast << ", height " << height;
    }
    expectSameBits(castFresh(rs, sensor, pattern, cfg), r, "composed height");
    if (HasFailure()) return;
  }
  // The heights did differ in their last bits.
  std::sort(heights.begin(), heights.end());
  EXPECT_GT(std::unique(heights.begin(), heights.end()) - heights.begin(), 1);
}

// A field of small primitives as a warehouse's barrels and crates (upright and tilted cylinders,
// boxes, spheres, near and far): a kept slice's walk meets many of them with one traced beam at a
// time, and must find what a fresh cut finds, bit for bit, and what the brute force finds.
TEST(KeptSlice, SmallPrimitivesThroughKeptSlices) {
  Rng rng(67);
  RandomScene rs;
  core::Scene& scene = rs.scene;
  scene.addFrame("world");
  scene.addLabel("clutter");
  for (int i = 0; i < 1200; ++i) {
    const Eigen::Vector3d at(uniform(rng, -25, 25), uniform(rng, -25, 25), uniform(rng, -0.3, 0.3));
    const Eigen::Matrix3d turn =
        i % 2 ? yaw(uniform(rng, -M_PI, M_PI)) : randomRotation(rng).toRotationMatrix();
    const Eigen::Isometry3d p = pose(at, turn);
    if (i % 3 == 0) addBody(&scene, core::Cylinder{uniform(rng, 0.02, 0.25), 1.0}, 0, p);
    if (i % 3 == 1) {
      addBody(&scene,
              core::Box{Eigen::Vector3d(uniform(rng, 0.04, 0.4), uniform(rng, 0.04, 0.4), 1.0)}, 0,
              p);
    }
    if (i % 3 == 2) addBody(&scene, core::Sphere{uniform(rng, 0.04, 0.25)}, 0, p);
  }
  rs.poses = core::FramePoses::identity(scene);
  const core::ScanPattern pattern(fanBySamples(-2.35, 2.35, 1081));
  const core::CastConfig cfg = config(true, 40.0);
  core::Caster caster;
  int kept = 0, hits = 0;
  for (int cast = 0; cast < 8; ++cast) {
    const Eigen::Isometry3d sensor = onTheFloor(rng, 0.0);
    const core::ScanResult& r = caster.cast(scene, rs.poses, sensor, pattern, cfg);
    kept += r.stats.kept_slices;
    expectSameBits(castFresh(rs, sensor, pattern, cfg), r, "small primitives");
    expectMatchesTruth(r, bruteForce(scene, rs.poses, sensor, pattern, cfg), 1e-9,
                       "cast " + std::to_string(cast));
    for (const double range : r.range) hits += std::isfinite(range);
    if (HasFailure()) return;
  }
  EXPECT_GE(kept, 7);
  EXPECT_GT(hits, 8 * 1081 / 2);
}

// A tilting sensor meets a new plane every scan: nothing is kept, and nothing changes.
TEST(KeptSlice, ANewPlaneEveryScanKeepsNothing) {
  Rng rng(59);
  const RandomScene rs = randomScene(rng);
  const core::ScanPattern pattern(fanBySamples(-M_PI, M_PI, 720));
  const core::CastConfig cfg = config(true, 25.0);
  core::Caster caster;
  for (int cast = 0; cast < 6; ++cast) {
    const Eigen::Isometry3d sensor =
        pose(Eigen::Vector3d(uniform(rng, -8, 8), uniform(rng, -8, 8), 0.1),
             rpy(uniform(rng, -0.1, 0.1), uniform(rng, -0.1, 0.1), uniform(rng, -M_PI, M_PI)));
    const core::ScanResult& r = caster.cast(rs.scene, rs.poses, sensor, pattern, cfg);
    EXPECT_EQ(r.stats.kept_slices, 0);
    expectSameBits(castFresh(rs, sensor, pattern, cfg), r, "tilting");
  }
}

// A scene changed after its slices were kept: the next cast sees the change.
TEST(KeptSlice, AChangedSceneIsNotCastThroughOldSlices) {
  Rng rng(61);
  RandomScene rs = randomScene(rng);
  const core::ScanPattern pattern(fanBySamples(-M_PI, M_PI, 720));
  const core::CastConfig cfg = config(true, 25.0);
  const Eigen::Isometry3d sensor = pose(Eigen::Vector3d(0, 0, 0.05), yaw(0.3));
  core::Caster caster;
  for (int cast = 0; cast < 3; ++cast) {
    caster.forget();
    caster.cast(rs.scene, rs.poses, sensor, pattern, cfg);
  }
  // A wall right in front of the sensor, on the world frame.
  addBody(&rs.scene, core::Box{Eigen::Vector3d(0.2, 4, 2)}, 0,
          pose(Eigen::Vector3d(1.0, 0, 0), yaw(0.3)), 3);
  rs.poses = core::FramePoses::identity(rs.scene);
  const core::ScanResult& r = caster.cast(rs.scene, rs.poses, sensor, pattern, cfg);
  const core::ScanResult fresh = castFresh(rs, sensor, pattern, cfg);
  expectSameBits(fresh, r, "changed scene");
  const int wall = static_cast<int>(rs.scene.bodies().size()) - 1;
  EXPECT_GT(std::count(r.body.begin(), r.body.end(), wall), 20);
}

}  // namespace
}  // namespace laser_raycast_test
