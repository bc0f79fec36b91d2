// The caster's shortcuts never change what a beam reports, on random scenes (meshes of many
// components, a lone sphere mesh, a soup of separate triangles, boxes, cylinders and spheres, on a
// fixed and a moving frame) seen by fans and rings from random poses:
// - occlusion culling on or off: the same result, bit for bit;
// - one thread or several: the same result, bit for bit;
// - slicing and rasterising on or off (every beam traced instead): the same hits, the same ranges
//   to rounding, the same bodies.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "cast_reference.h"
#include "fan_specs.h"
#include "mesh_builder.h"
#include "random.h"
#include "random_scene.h"
#include "test_geometry.h"

namespace laser_raycast_test {
namespace {

std::vector<core::ScanPattern> patterns() {
  std::vector<core::ScanPattern> out;
  out.emplace_back(fanBySamples(-M_PI, M_PI, 720));
  out.emplace_back(fanBySamples(-2.35, 2.35, 1081));
  std::vector<double> rings;
  for (int r = 0; r < 16; ++r) rings.push_back(-0.26 + 0.52 * r / 15);
  out.emplace_back(fanBySamples(-M_PI, M_PI, 512), rings);
  return out;
}

// A pose in the scene, level (so the planar fan cuts the prisms) or tilted.
Eigen::Isometry3d sensorPose(Rng& rng, int i) {
  const Eigen::Vector3d at(uniform(rng, -8, 8), uniform(rng, -8, 8), uniform(rng, -0.5, 0.5));
  return pose(
      at, i % 3 ? yaw(uniform(rng, -M_PI, M_PI))
                : rpy(uniform(rng, -0.3, 0.3), uniform(rng, -0.3, 0.3), uniform(rng, -M_PI, M_PI)));
}

void expectSameBits(const core::ScanResult& a, const core::ScanResult& b, const char* what) {
  ASSERT_EQ(a.range.size(), b.range.size());
  for (std::size_t i = 0; i < a.range.size(); ++i) {
    const bool same =
        (a.range[i] == b.range[i] || (std::isnan(a.range[i]) && std::isnan(b.range[i])));
    ASSERT_TRUE(same && a.body[i] == b.body[i] && a.triangle[i] == b.triangle[i])
        << what << ": beam " << i << " range " << a.range[i] << " vs " << b.range[i] << ", body "
        << a.body[i] << " vs " << b.body[i] << ", triangle " << a.triangle[i] << " vs "
        << b.triangle[i];
  }
}

TEST(CasterWalk, CullingThreadsAndFastPathsNeverChangeAResult) {
  Rng rng(37);
  long long hits = 0, beams = 0;
  for (int s = 0; s < 6; ++s) {
    const RandomScene rs = randomScene(rng);
    for (const core::ScanPattern& pattern : patterns()) {
      for (int p = 0; p < 3; ++p) {
        const Eigen::Isometry3d sensor = sensorPose(rng, p);
        core::CastConfig base = config(true, 25.0);
        const core::ScanResult reference = cast(rs.scene, rs.poses, sensor, pattern, base);
        core::CastConfig no_culling = base;
        no_culling.occlusion_culling = false;
        expectSameBits(reference, cast(rs.scene, rs.poses, sensor, pattern, no_culling),
                       "occlusion culling off");
        for (const int threads : {2, 3, 0}) {
          core::CastConfig threaded = base;
          threaded.threads = threads;
          expectSameBits(reference, cast(rs.scene, rs.poses, sensor, pattern, threaded), "threads");
        }
        core::CastConfig traced = base;
        traced.planar_fast_path = false;
        traced.raster_fast_path = false;
        const core::ScanResult slow = cast(rs.scene, rs.poses, sensor, pattern, traced);
        for (int i = 0; i < pattern.size(); ++i) {
          ASSERT_EQ(std::isfinite(reference.range[i]), std::isfinite(slow.range[i]))
              << "scene " << s << " pose " << p << " beam " << i;
          if (!std::isfinite(slow.range[i])) continue;
          EXPECT_NEAR(reference.range[i], slow.range[i], 1e-9 * std::max(1.0, slow.range[i]));
          EXPECT_EQ(reference.body[i], slow.body[i]) << "beam " << i;
          ++hits;
        }
        beams += pattern.size();
        if (HasFailure()) return;
      }
    }
  }
  EXPECT_GT(hits, beams / 3);
}

// A closed room on a slope, with a row of vertices at the sensor's height: every beam of a fan in
// the room's level plane passes within an ulp of that row, on either side of it depending on the
// frame the arithmetic is done in (the boxes are the body's, the triangles are tested moved into
// the sensor's frame or cut by the plane). Every path must still hit the wall with every beam:
// traced, sliced, rasterised, through a kept slice, and a 3D pattern with a ring in that plane.
TEST(CasterWalk, TiltedRoomWithAVertexRowAtTheSensorHeightLeaksNowhere) {
  core::Scene scene = sceneWithFrame();
  const Eigen::Isometry3d room = pose(Eigen::Vector3d(40, 0, 3), rpy(0.25, -0.15, 0.6));
  addBody(&scene, prism(circle(48, 4.0, 0.1), steps(0, 2.5, 10), true), 0, room);
  const core::FramePoses poses = core::FramePoses::identity(scene);
  const core::ScanPattern fan(fanBySamples(-2.35, 2.35, 1081));
  const core::ScanPattern rings(fanBySamples(-M_PI, M_PI, 1024), {-0.02, 0.0, 0.02});
  core::Caster kept;  // one caster for every pose: the room's plane is sliced whole and kept
  Rng rng(53);
  long long beams = 0;
  for (int p = 0; p < 12; ++p) {
    // Level in the room, exactly at the height of its third row of vertices (z = 0.5).
    const Eigen::Isometry3d sensor =
        room * pose(Eigen::Vector3d(uniform(rng, -2.5, 2.5), uniform(rng, -2.5, 2.5), 0.5),
                    yaw(uniform(rng, -M_PI, M_PI)));
    for (int variant = 0; variant < 6; ++variant) {
      core::CastConfig c = config(true, 30.0);
      const core::ScanPattern* pattern = &fan;
      core::ScanResult result;
      switch (variant) {
        case 0:  // kept slices, cast three times (a plane is kept the second time it is met)
          for (int k = 0; k < 3; ++k) {
            kept.forget();
            result = kept.cast(scene, poses, sensor, fan, c);
          }
          break;
        case 1:
          c.keep_slices = false;
          break;
        case 2:
          c.planar_fast_path = false;  // every beam traced
          break;
        case 3:
          c.occlusion_culling = false;
          c.keep_slices = false;
          break;
        case 4:
          pattern = &rings;
          break;
        default:
          pattern = &rings;
          c.raster_fast_path = false;
      }
      if (variant > 0) result = cast(scene, poses, sensor, *pattern, c);
      for (int i = 0; i < pattern->size(); ++i) {
        ASSERT_TRUE(result.range[i] > 0 && result.range[i] < 9.0)
            << "pose " << p << ", variant " << variant << ", beam " << i << ": range "
            << result.range[i];
      }
      beams += pattern->size();
    }
  }
  EXPECT_GT(beams, 12 * 4 * 1081);
}

// The same with a scan that many threads share: every beam's answer is the one thread's.
TEST(CasterWalk, ManyThreadsOnALargeScan) {
  Rng rng(41);
  const RandomScene rs = randomScene(rng);
  std::vector<double> rings;
  for (int r = 0; r < 64; ++r) rings.push_back(-0.26 + 0.52 * r / 63);
  const core::ScanPattern pattern(fanBySamples(-M_PI, M_PI, 1024), rings);
  const Eigen::Isometry3d sensor = sensorPose(rng, 1);
  core::CastConfig one = config(true, 25.0);
  const core::ScanResult reference = cast(rs.scene, rs.poses, sensor, pattern, one);
  core::Caster caster;  // the same caster, so that its thread pool is reused
  for (const int threads : {2, 4, 7, 2}) {
    core::CastConfig many = one;
    many.threads = threads;
    caster.forget();
    expectSameBits(reference, caster.cast(rs.scene, rs.poses, sensor, pattern, many), "threads");
  }
}

TEST(CastConfig, ThreadsOutOfRangeAreRefused) {
  core::CastConfig c;
  c.threads = -1;
  EXPECT_THROW(c.validate(), std::invalid_argument);
  c.threads = 100000;
  EXPECT_THROW(c.validate(), std::invalid_argument);
  c.threads = 0;
  EXPECT_NO_THROW(c.validate());
}

}  // namespace
}  // namespace laser_raycast_test
