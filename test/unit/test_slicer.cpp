// The fan slicer (the Caster's planar fast path) is watertight: from inside a closed mesh every
// beam hits, and sliceMesh counts exactly one outline crossing per beam, through rows of vertices,
// through vertices exactly on a beam, and with a tilted sensor.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <variant>
#include <vector>

#include "cast_reference.h"
#include "fan_specs.h"
#include "laser_raycast/core/caster.h"
#include "slice_mesh.h"
#include "laser_raycast/core/pose.h"
#include "mesh_builder.h"
#include "random.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

// How many of the mesh's outline segments each beam crosses, nearest or not. From a point of a
// star-shaped outline's kernel it is exactly one per beam: more would be a shared segment endpoint
// counted twice (a double hit), fewer a leak.
std::vector<int> crossingsPerBeam(const Mesh& mesh, const Eigen::Isometry3d& world_from_sensor,
                                  const ScanPattern& pattern) {
  const int n = pattern.size();
  std::vector<double> range(n, std::numeric_limits<double>::infinity());
  std::vector<int> body(n, -1), triangle(n, -1), crossings(n, 0);
  sliceMesh(mesh, relativePose(world_from_sensor, Eigen::Isometry3d::Identity()), pattern, 0.0,
            std::numeric_limits<double>::infinity(), false, 0,
            DepthBuffer{&range, &body, &triangle, &crossings});
  return crossings;
}

// Closed meshes with a vertex row exactly at the sensor's height: the scan plane runs through rows
// of vertices and along horizontal edges. From inside, every beam must hit, for many fans and
// sensor positions; and the fast path must agree with the general path.
TEST(FanSlicer, FastPathIsWatertightThroughVertexRows) {
  Rng rng(7);
  const double h = 0.375;  // the sensor's height, and a vertex row
  std::vector<std::shared_ptr<const Mesh>> meshes;
  for (const int n : {3, 4, 5, 8, 31, 97, 256}) {
    meshes.push_back(prism(circle(n, 2.0, 0.1 * n), {h - 1, h, h + 0.25, h + 1}, true));
  }
  meshes.push_back(gridBox(steps(-3, 4, 7), steps(-2, 2.5, 9), {h - 1, h, h + 1.5}, true));
  // The same closed surfaces wound outward: culling is off, so they must be as tight.
  meshes.push_back(prism(circle(12, 2.0), {h - 2, h - 1, h, h + 1}, false));
  const std::vector<int> sample_counts = {2, 3, 7, 64, 360, 361, 720, 1000, 1441};
  int casts = 0;
  for (const auto& mesh : meshes) {
    Scene scene = sceneWithFrame();
    addBody(&scene, mesh, 0);
    const FramePoses poses = FramePoses::identity(scene);
    for (int s = 0; s < 12; ++s) {
      // Inside: within 0.9 m of the axis (every prism's inradius is at least 2 cos(60 deg) = 1).
      const double rho = 0.9 * std::sqrt(uniform(rng, 0, 1)), phi = uniform(rng, -M_PI, M_PI);
      const auto sensor = pose(Eigen::Vector3d(rho * std::cos(phi), rho * std::sin(phi), h),
                               yaw(uniform(rng, -4, 4)));
      const int samples = sample_counts[(s + casts) % sample_counts.size()];
      const double a0 = s % 3 == 0 ? -M_PI : uniform(rng, -7, 7);
      const ScanPattern pattern(fanBySamples(a0, a0 + (s % 2 ? 2 * M_PI : 5.0), samples));
      const ScanResult fast = cast(scene, poses, sensor, pattern, config(true));
      const ScanResult general = cast(scene, poses, sensor, pattern, config(false));
      ASSERT_EQ(misses(fast), 0) << "mesh " << casts << " sensor " << s;
      ASSERT_EQ(misses(general), 0) << "mesh " << casts << " sensor " << s;
      const std::vector<int> crossings = crossingsPerBeam(*mesh, sensor, pattern);
      for (int i = 0; i < pattern.size(); ++i) {
        ASSERT_EQ(crossings[i], 1) << "mesh " << casts << " sensor " << s << " beam " << i;
      }
      for (int i = 0; i < pattern.size(); ++i)
        ASSERT_TRUE(near(fast.range[i], general.range[i], 1e-9));
    }
    ++casts;
  }
}

// Beams aimed exactly at vertices: a star polygon whose corners are placed at the beams' own
// directions times a power of two (so r * cos a and r * sin a are exact and the beam's line passes
// through the corner without rounding), with a vertex row at the sensor's height.
TEST(FanSlicer, FastPathIsWatertightThroughVertices) {
  for (const int n : {6, 24, 180, 720}) {
    for (const int every : {1, 2, 3}) {
      const ScanPattern pattern(
          fanByIncrement(-M_PI + 0.01, -M_PI + 0.01 + 2 * M_PI * (n - 1) / n, 2 * M_PI / n));
      ASSERT_EQ(pattern.size(), n);
      std::vector<Eigen::Vector2d> star;
      for (int i = 0; i < n; i += every) {
        const double r = (i / every) % 2 ? 2.0 : 4.0;
        star.emplace_back(r * pattern.directions()[i].x(), r * pattern.directions()[i].y());
      }
      if (star.size() < 3) continue;
      Scene scene = sceneWithFrame();
      addBody(&scene, prism(star, {-1.0, 0.0, 1.0}, true), 0);
      const FramePoses poses = FramePoses::identity(scene);
      for (const bool fast : {true, false}) {
        const ScanResult r =
            cast(scene, poses, Eigen::Isometry3d::Identity(), pattern, config(fast));
        ASSERT_EQ(misses(r), 0) << "n " << n << " every " << every << (fast ? " fast" : " general");
        if (fast) {
          // Every corner is a shared endpoint that a beam runs through exactly.
          const std::vector<int> crossings =
              crossingsPerBeam(*std::get<std::shared_ptr<const Mesh>>(scene.bodies()[0].shape),
                               Eigen::Isometry3d::Identity(), pattern);
          for (int i = 0; i < n; ++i) ASSERT_EQ(crossings[i], 1) << "n " << n << " beam " << i;
        }
        // The beams through a corner measure exactly its radius.
        for (int i = 0; i < n; i += every) {
          ASSERT_NEAR(r.range[i], (i / every) % 2 ? 2.0 : 4.0, 1e-12) << i;
        }
      }
    }
  }
}

// A tilted sensor in a closed room: generic crossings, every beam must still hit.
TEST(FanSlicer, FastPathIsWatertightWhenTilted) {
  Rng rng(21);
  const auto room = gridBox(steps(-3, 4, 9), steps(-2, 5, 11), steps(-1, 2, 5), true);
  const auto drum = prism(circle(40, 2.5), steps(-1, 1, 6), true);
  for (const auto& mesh : {room, drum}) {
    Scene scene = sceneWithFrame();
    addBody(&scene, mesh, 0);
    const FramePoses poses = FramePoses::identity(scene);
    for (int s = 0; s < 30; ++s) {
      const auto sensor =
          pose(Eigen::Vector3d(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -0.5, 0.5)),
               rpy(uniform(rng, -0.3, 0.3), uniform(rng, -0.3, 0.3), uniform(rng, -4, 4)));
      const ScanPattern pattern(fanBySamples(-M_PI, M_PI, 500 + 37 * s));
      const ScanResult r = cast(scene, poses, sensor, pattern, config(true));
      ASSERT_EQ(misses(r), 0) << "sensor " << s;
    }
  }
}

}  // namespace
}  // namespace laser_raycast_test
