// Caster::castSweep, against distances worked out by hand: a rotating scan whose beams are taken at
// their own times, from a sensor (or a body) that moves during the sweep.
#include <gtest/gtest.h>

#include <cmath>

#include "cast_reference.h"
#include "expect_invalid.h"
#include "fan_specs.h"
#include "laser_raycast/core/pose_samples.h"

namespace laser_raycast_test {
namespace {

// A wall: the box x in [5, 5.2], |y| <= 50, |z| <= 5, in the world frame.
core::Scene wallScene() {
  core::Scene scene = sceneWithFrame();
  addBody(&scene, core::Box{Eigen::Vector3d(0.2, 100, 10)}, 0, pose({5.1, 0, 0}));
  return scene;
}

core::PoseSamples movingSensor(const core::Scene& scene, double speed, double duration) {
  core::PoseSamples s;
  s.times = {0.0, duration};
  s.world_from_sensor = {pose({0, 0, 0}), pose({-speed * duration, 0, 0})};
  s.frames = {core::FramePoses::identity(scene), core::FramePoses::identity(scene)};
  return s;
}

// Beams from -0.4 to 0.4 rad, all on the wall; the sensor moves away from it at 1 m/s for 0.1 s.
// Beam i at time i * dt sees the wall at (5 + v i dt) / cos(angle_i).
TEST(CastSweep, EachBeamSeesTheWallFromWhereTheSensorWasAtItsTime) {
  const core::Scene scene = wallScene();
  const core::ScanPattern pattern(fanBySamples(-0.4, 0.4, 81));
  const double dt = 0.1 / 80;
  for (const bool fast : {true, false}) {
    core::Caster caster;
    const core::ScanResult& r =
        caster.castSweep(scene, movingSensor(scene, 1.0, 0.1), pattern, config(fast), dt);
    for (int i = 0; i < pattern.size(); ++i) {
      const double expected = (5 + 1.0 * i * dt) / std::cos(pattern.azimuth(i));
      EXPECT_NEAR(r.range[i], expected, 1e-12) << "beam " << i << (fast ? " fast" : "");
    }
    // The check: the first and last beams on the wall differ by the distance travelled.
    const double first = r.range[0] * std::cos(pattern.azimuth(0));
    const double last = r.range[80] * std::cos(pattern.azimuth(80));
    EXPECT_NEAR(last - first, 0.1, 1e-12);
    EXPECT_FALSE(r.stats.reused);
  }
}

TEST(CastSweep, ZeroTimeIncrementIsTheInstantCast) {
  const core::Scene scene = wallScene();
  const core::ScanPattern pattern(fanBySamples(-1, 1, 33), {-0.1, 0.0, 0.2});
  const core::PoseSamples samples = movingSensor(scene, 2.0, 0.05);
  core::Caster sweep_caster;
  const core::ScanResult sweep =
      sweep_caster.castSweep(scene, samples, pattern, config(false), 0.0);
  const core::ScanResult instant =
      cast(scene, samples.frames[0], samples.world_from_sensor[0], pattern, config(false));
  EXPECT_EQ(sweep.range, instant.range);
  EXPECT_EQ(sweep.body, instant.body);
}

// The wall moves instead (a body on a moving frame), towards the sensor at 2 m/s; rings too.
TEST(CastSweep, MovingBodiesArePlacedAtEachBeamsTime) {
  core::Scene scene = sceneWithFrame("map");
  const int cart = scene.addFrame("cart");
  addBody(&scene, core::Box{Eigen::Vector3d(0.2, 100, 10)}, cart, pose({5.1, 0, 0}));
  core::PoseSamples s;
  s.times = {0.0, 0.04, 0.1};
  s.world_from_sensor = {pose({0, 0, 0}), pose({0, 0, 0}), pose({0, 0, 0})};
  s.frames.assign(3, core::FramePoses::identity(scene));
  s.frames[1].pose[cart] = pose({-0.08, 0, 0});
  s.frames[2].pose[cart] = pose({-0.2, 0, 0});
  const core::ScanPattern pattern(fanBySamples(-0.3, 0.3, 61), {-0.2, 0.0, 0.1});
  const double dt = 0.1 / 60;
  core::Caster caster;
  const core::ScanResult& r = caster.castSweep(scene, s, pattern, config(true), dt);
  for (int ring = 0; ring < 3; ++ring) {
    const double el = pattern.elevations()[ring];
    for (int c = 0; c < 61; ++c) {
      const double x = 5 - 2.0 * c * dt;
      const double expected = x / (std::cos(el) * std::cos(pattern.azimuth(c)));
      EXPECT_NEAR(r.range[ring * 61 + c], expected, 1e-12) << ring << " " << c;
    }
  }
}

TEST(CastSweep, RefusesBadInput) {
  const core::Scene scene = wallScene();
  const core::ScanPattern pattern(fanBySamples(-1, 1, 5));
  core::Caster caster;
  const core::PoseSamples samples = movingSensor(scene, 1, 0.1);
  expectMentions(
      invalidMessage([&] { caster.castSweep(scene, samples, pattern, config(true), -1); }),
      {"time_increment", "-1"});
  expectMentions(invalidMessage([&] {
                   caster.castSweep(scene, core::PoseSamples{}, pattern, config(true), 0.01);
                 }),
                 {"no samples"});
}

}  // namespace
}  // namespace laser_raycast_test
