// Caster and frames: frames that are unknown or not rigid, frame poses from a lookup, bad sensor
// poses, a scene far from the origin, and when a result is reused. Expected values come from the
// brute force of cast_reference.h or from the same cast near the origin.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "cast_reference.h"
#include "fan_specs.h"
#include "laser_raycast/core/caster.h"
#include "mesh_builder.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

// -------------------------------------------------------------------------------------------------
// Frames

// A frame with valid = 0 skips its bodies (counted), and the result is that of the other bodies.
TEST(Caster, InvalidFrameSkipsItsBodies) {
  Scene scene;
  scene.addLabel("l");
  const int base = scene.addFrame("base");
  const int arm = scene.addFrame("arm");
  addBody(&scene, Sphere{0.5}, base, pose(Eigen::Vector3d(4, 0, 0)));
  addBody(&scene, Sphere{0.5}, arm, pose(Eigen::Vector3d(2, 0, 0)));
  addBody(&scene, Box{Eigen::Vector3d(1, 1, 1)}, arm, pose(Eigen::Vector3d(0, 3, 0)));
  FramePoses poses = FramePoses::identity(scene);
  poses.valid[arm] = 0;
  const ScanPattern pattern(fanBySamples(-M_PI, M_PI, 361));
  for (const bool fast : {true, false}) {
    const ScanResult r = cast(scene, poses, Eigen::Isometry3d::Identity(), pattern, config(fast));
    EXPECT_EQ(r.stats.bodies_skipped, 2);
    EXPECT_EQ(r.stats.bodies, 3);
    expectMatchesTruth(
        r, bruteForce(scene, poses, Eigen::Isometry3d::Identity(), pattern, config(fast)), 1e-12,
        "skipped arm");
    for (const int b : r.body) EXPECT_NE(b, 1);
    EXPECT_NEAR(r.range[180], 3.5, 1e-12);  // azimuth 0 sees the base sphere, not the arm's
  }
}

// resolveFramePoses asks the lookup for every frame; unknown, non-rigid and non-finite poses make
// the frame invalid, and the count of invalid frames is returned.
TEST(Caster, ResolveFramePosesWithLambda) {
  Scene scene;
  scene.addLabel("l");
  for (const char* name : {"base", "missing", "scaled", "nan", "sheared", "mirrored", "arm"}) {
    scene.addFrame(name);
  }
  const auto base_pose = pose(Eigen::Vector3d(1, 2, 3), rpy(0.1, 0.2, 0.3));
  const auto arm_pose = pose(Eigen::Vector3d(-1, 0, 0.5), yaw(1.0));
  std::vector<std::string> asked;
  const PoseLookup lookup = [&](const std::string& frame, Eigen::Isometry3d& p) {
    asked.push_back(frame);
    if (frame == "missing") return false;
    p = Eigen::Isometry3d::Identity();
    if (frame == "base") p = base_pose;
    if (frame == "arm") p = arm_pose;
    if (frame == "scaled") p.linear() *= 1.01;
    if (frame == "nan") p.translation().x() = kNan;
    if (frame == "sheared") p.linear()(0, 1) = 0.05;
    if (frame == "mirrored") p.linear()(2, 2) = -1;
    return true;
  };
  FramePoses poses;
  EXPECT_EQ(resolveFramePoses(scene, lookup, &poses), 5);
  EXPECT_EQ(asked, scene.frames());
  ASSERT_EQ(poses.valid.size(), 7u);
  ASSERT_EQ(poses.pose.size(), 7u);
  EXPECT_EQ(poses.valid, (std::vector<char>{1, 0, 0, 0, 0, 0, 1}));
  EXPECT_TRUE(poses.pose[0].isApprox(base_pose, 0));
  EXPECT_TRUE(poses.pose[6].isApprox(arm_pose, 0));

  // The resolved poses cast: a body on the arm at (2, 0, 0) in the arm frame.
  addBody(&scene, Sphere{0.25}, 6, pose(Eigen::Vector3d(2, 0, 0)));
  addBody(&scene, Sphere{0.25}, 2, pose(Eigen::Vector3d(1, 0, 0)));  // on "scaled": skipped
  resolveFramePoses(scene, lookup, &poses);
  const ScanPattern pattern(fanBySamples(-M_PI, M_PI, 90));
  const auto sensor = pose(Eigen::Vector3d(0, 0, 0.5));
  const ScanResult r = cast(scene, poses, sensor, pattern, config(true));
  EXPECT_EQ(r.stats.bodies_skipped, 1);
  expectMatchesTruth(r, bruteForce(scene, poses, sensor, pattern, config(true)), 1e-9, "arm");
  // The sphere sits at arm_pose * (2, 0, 0), in the scan plane z = 0.5: some beams see it.
  int seen = 0;
  for (int i = 0; i < pattern.size(); ++i) seen += r.body[i] == 0;
  EXPECT_GT(seen, 0);
}

// A sensor pose that is not a finite rigid transform gives every beam NaN (REP 117: erroneous).
TEST(Caster, InvalidSensorPoseGivesNan) {
  Scene scene = sceneWithFrame();
  addBody(&scene, Sphere{1}, 0, pose(Eigen::Vector3d(3, 0, 0)));
  const FramePoses poses = FramePoses::identity(scene);
  const ScanPattern pattern(fanBySamples(-1, 1, 50));
  Eigen::Isometry3d nan_pose = Eigen::Isometry3d::Identity();
  nan_pose.translation().y() = kNan;
  Eigen::Isometry3d inf_pose = Eigen::Isometry3d::Identity();
  inf_pose.linear()(1, 1) = kInf;
  Eigen::Isometry3d scaled = Eigen::Isometry3d::Identity();
  scaled.linear() *= 2;
  Eigen::Isometry3d mirrored = Eigen::Isometry3d::Identity();
  mirrored.linear()(0, 0) = -1;
  Eigen::Isometry3d sheared = Eigen::Isometry3d::Identity();
  sheared.linear()(0, 2) = 1e-3;
  for (const auto& bad : {nan_pose, inf_pose, scaled, mirrored, sheared}) {
    for (const bool fast : {true, false}) {
      Caster caster;
      // A good cast first, so that a stale result cannot pass for the NaN one.
      caster.cast(scene, poses, Eigen::Isometry3d::Identity(), pattern, config(fast));
      const ScanResult& r = caster.cast(scene, poses, bad, pattern, config(fast));
      ASSERT_EQ(r.range.size(), 50u);
      for (int i = 0; i < 50; ++i) {
        EXPECT_TRUE(std::isnan(r.range[i]));
        EXPECT_EQ(r.body[i], -1);
        EXPECT_EQ(r.triangle[i], -1);
      }
      EXPECT_FALSE(r.stats.reused);
    }
  }
  // Slightly off (a float quaternion's rounding) is still rigid.
  Eigen::Isometry3d almost = Eigen::Isometry3d::Identity();
  almost.linear() =
      Eigen::Quaterniond(
          Eigen::Quaternionf(Eigen::AngleAxisf(0.3f, Eigen::Vector3f::UnitZ())).cast<double>())
          .toRotationMatrix();
  const ScanResult r = cast(scene, poses, almost, pattern, config(true));
  EXPECT_FALSE(std::isnan(r.range[25]));
}

// A frame pose marked valid but not rigid (scaled, sheared, mirrored, NaN) cannot be used: the
// caster treats it as unknown and skips the frame's bodies, as resolveFramePoses would have.
// Regression: the caster used such poses, inverting them by transposing the rotation; the scaled
// one put the sensor on the near sphere's surface and reported 0 m.
TEST(Caster, NonRigidFramePoseIsSkipped) {
  Scene scene;
  scene.addLabel("l");
  const int good = scene.addFrame("good");
  const int bad = scene.addFrame("bad");
  addBody(&scene, Sphere{0.5}, good, pose(Eigen::Vector3d(5, 0, 0)));
  addBody(&scene, Sphere{0.5}, bad, pose(Eigen::Vector3d(2, 0, 0)));
  const ScanPattern pattern(fanBySamples(-0.5, 0.5, 101));
  std::vector<Eigen::Matrix4d> broken;
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(0, 0) = 0.5;  // scaled
  broken.push_back(m);
  m = Eigen::Matrix4d::Identity();
  m(1, 0) = 0.2;  // sheared
  broken.push_back(m);
  m = Eigen::Matrix4d::Identity();
  m(2, 2) = -1;  // mirrored
  broken.push_back(m);
  m = Eigen::Matrix4d::Identity();
  m(0, 3) = kNan;
  broken.push_back(m);
  for (const auto& matrix : broken) {
    FramePoses poses = FramePoses::identity(scene);
    poses.pose[bad].matrix() = matrix;
    for (const bool fast : {true, false}) {
      const ScanResult r = cast(scene, poses, Eigen::Isometry3d::Identity(), pattern, config(fast));
      EXPECT_EQ(r.stats.bodies_skipped, 1) << matrix;
      EXPECT_EQ(r.range[50], 4.5) << matrix;  // the good sphere, as if "bad" were unknown
      EXPECT_EQ(r.body[50], 0);
    }
  }
}

// FramePoses sized for another scene is an error, not a silent misread.
TEST(Caster, FramePosesSizeMismatchThrows) {
  Scene scene = sceneWithFrame();
  scene.addFrame("second");
  FramePoses poses = FramePoses::identity(scene);
  poses.pose.pop_back();
  const ScanPattern pattern(fanBySamples(-1, 1, 5));
  Caster caster;
  EXPECT_THROW(caster.cast(scene, poses, Eigen::Isometry3d::Identity(), pattern, config(true)),
               std::invalid_argument);
  poses = FramePoses::identity(scene);
  poses.valid.push_back(1);
  EXPECT_THROW(caster.cast(scene, poses, Eigen::Isometry3d::Identity(), pattern, config(true)),
               std::invalid_argument);
}

// -------------------------------------------------------------------------------------------------
// Far from the origin

struct FarScene {
  Scene scene;
  FramePoses poses;
  Eigen::Isometry3d sensor;
};

// A room, boxes (mesh and primitive) and, when curved is set, a sphere and a tilted cylinder,
// spread over three frames.
FarScene farScene(bool curved, const Eigen::Vector3d& sensor_at,
                  const Eigen::Matrix3d& sensor_rot) {
  FarScene s;
  s.scene.addLabel("l");
  const int room_frame = s.scene.addFrame("room");
  const int a = s.scene.addFrame("a");
  const int b = s.scene.addFrame("b");
  addBody(&s.scene, gridBox(steps(-4, 5, 3), steps(-3, 4, 3), steps(-1, 1.5, 2), true), room_frame);
  addBody(&s.scene, Box{Eigen::Vector3d(0.6, 0.6, 1)}, a, pose(Eigen::Vector3d(0.5, 0.5, 0)));
  addBody(&s.scene, gridBox(steps(-0.4, 0.4, 2), steps(-0.4, 0.4, 2), steps(-0.5, 0.5, 1), false),
          b, pose(Eigen::Vector3d(-0.5, 0.5, 0)));
  if (curved) {
    addBody(&s.scene, Sphere{0.4}, a, pose(Eigen::Vector3d(0.25, -2, 0.125)));
    addBody(&s.scene, Cylinder{0.3, 1.2}, b, pose(Eigen::Vector3d(-1, -2, 0), rpy(0.7, 0.4, 0)));
    addBody(&s.scene, uvSphere(0.5, 9, 14), b,
            pose(Eigen::Vector3d(3, -1, 0.25), rpy(0.3, 0.2, 0.1)));
  }
  s.poses = FramePoses::identity(s.scene);
  s.poses.pose[a] = pose(Eigen::Vector3d(2, 1.5, 0), yaw(0.25));
  s.poses.pose[b] = pose(Eigen::Vector3d(-2, -1.5, 0), yaw(-0.6));
  s.sensor = pose(sensor_at, sensor_rot);
  return s;
}

void translateAll(FarScene* s, const Eigen::Vector3d& offset) {
  for (auto& p : s->poses.pose) p.pretranslate(offset);
  s->sensor.pretranslate(offset);
}

// The same scene and sensor moved 10^6 m away (frame poses and sensor pose alike) give the same
// ranges. With dyadic coordinates the translated poses are exact, so any difference would be the
// caster's own loss; with arbitrary coordinates the poses themselves round by ~1e-10 m, which the
// flat-faced scene turns into < 1e-9 relative.
TEST(Caster, FarFromOriginGivesSameRanges) {
  const Eigen::Vector3d offset(1e6, -1e6, 1e6);
  const ScanPattern planar(fanBySamples(-M_PI, M_PI, 1440));
  const ScanPattern rings(fanBySamples(-M_PI, M_PI, 360), {-0.3, -0.1, 0.0, 0.15, 0.3});
  struct Case {
    bool curved;
    Eigen::Vector3d at;
  };
  // 0.125 / 0.0625 are exact at 1e6; 0.1234567 / 0.0987654 are not.
  for (const Case& c : {Case{true, Eigen::Vector3d(0.125, -0.0625, 0.03125)},
                        Case{false, Eigen::Vector3d(0.1234567, -0.0987654, 0.0456789)}}) {
    const FarScene near_origin = farScene(c.curved, c.at, rpy(0.05, -0.08, 0.7));
    FarScene far = farScene(c.curved, c.at, rpy(0.05, -0.08, 0.7));
    translateAll(&far, offset);
    ASSERT_GT(far.sensor.translation().norm(), 1e6);
    for (const ScanPattern* pattern : {&planar, &rings}) {
      for (const bool fast : {true, false}) {
        const ScanResult a =
            cast(near_origin.scene, near_origin.poses, near_origin.sensor, *pattern, config(fast));
        const ScanResult b = cast(far.scene, far.poses, far.sensor, *pattern, config(fast));
        int hits = 0;
        for (int i = 0; i < pattern->size(); ++i) {
          ASSERT_TRUE(std::isfinite(a.range[i]));  // closed room
          ASSERT_TRUE(near(a.range[i], b.range[i], 1e-9))
              << (fast ? "fast" : "general") << " beam " << i << ": " << a.range[i] << " vs "
              << b.range[i] << ", difference " << a.range[i] - b.range[i];
          ASSERT_EQ(a.body[i], b.body[i]) << i;
          hits += a.body[i] != 0;
        }
        EXPECT_GT(hits, 10);  // the objects are seen, not just the room
      }
    }
  }
}

// -------------------------------------------------------------------------------------------------
// Reuse

void expectSameResult(const ScanResult& a, const ScanResult& b) {
  ASSERT_EQ(a.range.size(), b.range.size());
  for (std::size_t i = 0; i < a.range.size(); ++i) {
    ASSERT_TRUE(a.range[i] == b.range[i] || (std::isnan(a.range[i]) && std::isnan(b.range[i])));
  }
  EXPECT_EQ(a.body, b.body);
  EXPECT_EQ(a.triangle, b.triangle);
  EXPECT_EQ(a.cos_incidence, b.cos_incidence);
}

// Casting again with nothing moved returns the previous result (stats.reused); any change that can
// alter the result (a frame, the sensor, validity, config, pattern, the scene) recomputes.
TEST(Caster, ReuseOnlyWhenNothingChanged) {
  Scene scene;
  scene.addLabel("l");
  const int base = scene.addFrame("base");
  const int arm = scene.addFrame("arm");
  addBody(&scene, gridBox(steps(-4, 4, 2), steps(-4, 4, 2), steps(-1, 1, 1), true), base);
  addBody(&scene, Sphere{0.5}, arm, pose(Eigen::Vector3d(2, 0, 0)));
  FramePoses poses = FramePoses::identity(scene);
  const ScanPattern pattern(fanBySamples(-M_PI, M_PI, 360));
  const auto sensor = pose(Eigen::Vector3d(0.25, 0.5, 0), yaw(0.1));
  for (const bool fast : {true, false}) {
    CastConfig cfg = config(fast);
    cfg.compute_incidence = true;
    Caster caster;
    const ScanResult first = caster.cast(scene, poses, sensor, pattern, cfg);
    EXPECT_FALSE(first.stats.reused);
    const ScanResult& again = caster.cast(scene, poses, sensor, pattern, cfg);
    EXPECT_TRUE(again.stats.reused);
    EXPECT_EQ(again.stats.bodies, 2);
    expectSameResult(first, again);
    // An equal pattern built anew, an equal config copy: still reused.
    const ScanPattern same_pattern(fanBySamples(-M_PI, M_PI, 360));
    const CastConfig same_cfg = cfg;
    EXPECT_TRUE(caster.cast(scene, poses, sensor, same_pattern, same_cfg).stats.reused);

    auto expectRecomputed = [&](const ScanResult& r, const FramePoses& p,
                                const Eigen::Isometry3d& s, const ScanPattern& pat,
                                const CastConfig& c, const char* what) {
      EXPECT_FALSE(r.stats.reused) << what;
      expectMatchesTruth(r, bruteForce(scene, p, s, pat, c), 1e-9, what);
    };
    // Move one frame.
    FramePoses moved = poses;
    moved.pose[arm].translation().y() = 0.5;
    expectRecomputed(caster.cast(scene, moved, sensor, pattern, cfg), moved, sensor, pattern, cfg,
                     "frame moved");
    EXPECT_TRUE(caster.cast(scene, moved, sensor, pattern, cfg).stats.reused);
    // Move the sensor.
    const auto sensor2 = pose(Eigen::Vector3d(0.25, 0.5, 0), yaw(0.2));
    expectRecomputed(caster.cast(scene, moved, sensor2, pattern, cfg), moved, sensor2, pattern, cfg,
                     "sensor moved");
    // Invalidate a frame, then restore it.
    FramePoses invalid = moved;
    invalid.valid[arm] = 0;
    expectRecomputed(caster.cast(scene, invalid, sensor2, pattern, cfg), invalid, sensor2, pattern,
                     cfg, "frame invalid");
    expectRecomputed(caster.cast(scene, moved, sensor2, pattern, cfg), moved, sensor2, pattern, cfg,
                     "frame valid again");
    // Change the config.
    CastConfig shorter = cfg;
    shorter.tmax = 2.0;
    expectRecomputed(caster.cast(scene, moved, sensor2, pattern, shorter), moved, sensor2, pattern,
                     shorter, "config tmax");
    CastConfig culled = shorter;
    culled.cull_backfaces = true;
    expectRecomputed(caster.cast(scene, moved, sensor2, pattern, culled), moved, sensor2, pattern,
                     culled, "config cull");
    CastConfig no_incidence = culled;
    no_incidence.compute_incidence = false;
    EXPECT_FALSE(caster.cast(scene, moved, sensor2, pattern, no_incidence).stats.reused);
    EXPECT_TRUE(caster.cast(scene, moved, sensor2, pattern, no_incidence).cos_incidence.empty());
    // Change the pattern: increment, first angle, count, rings.
    for (const ScanPattern& other :
         {ScanPattern(fanBySamples(-M_PI, M_PI, 361)), ScanPattern(fanBySamples(-3, M_PI, 360)),
          ScanPattern(fanBySamples(-M_PI, 3, 360)),
          ScanPattern(fanBySamples(-M_PI, M_PI, 360), {0.0, 0.1})}) {
      expectRecomputed(caster.cast(scene, moved, sensor2, other, no_incidence), moved, sensor2,
                       other, no_incidence, "pattern");
    }
    // Modify the scene: a new body in front of the sensor appears.
    caster.cast(scene, moved, sensor2, pattern, cfg);
    EXPECT_TRUE(caster.cast(scene, moved, sensor2, pattern, cfg).stats.reused);
    const auto version = scene.version();
    addBody(&scene, Sphere{0.2}, base, pose(Eigen::Vector3d(-2, 0.5, 0)));
    EXPECT_NE(scene.version(), version);
    expectRecomputed(caster.cast(scene, moved, sensor2, pattern, cfg), moved, sensor2, pattern, cfg,
                     "scene modified");
    EXPECT_EQ(caster.cast(scene, moved, sensor2, pattern, cfg).stats.bodies, 3);
    // After a NaN sensor, the same good inputs recompute.
    Eigen::Isometry3d nan_sensor = sensor2;
    nan_sensor.translation().x() = kNan;
    caster.cast(scene, moved, nan_sensor, pattern, cfg);
    expectRecomputed(caster.cast(scene, moved, sensor2, pattern, cfg), moved, sensor2, pattern, cfg,
                     "after NaN");
    // Remove the body again for the other path's loop.
    scene = Scene();
    scene.addLabel("l");
    scene.addFrame("base");
    scene.addFrame("arm");
    addBody(&scene, gridBox(steps(-4, 4, 2), steps(-4, 4, 2), steps(-1, 1, 1), true), base);
    addBody(&scene, Sphere{0.5}, arm, pose(Eigen::Vector3d(2, 0, 0)));
  }
}

// Moving the sensor and every frame together leaves every relative pose unchanged (exactly, with
// dyadic offsets): nothing moved relative to the sensor, so the result is reused.
TEST(Caster, ReuseWhenEverythingMovesTogether) {
  Scene scene = sceneWithFrame();
  addBody(&scene, Sphere{0.5}, 0, pose(Eigen::Vector3d(2, 0, 0)));
  FramePoses poses = FramePoses::identity(scene);
  poses.pose[0] = pose(Eigen::Vector3d(0.5, 0.25, 0));
  auto sensor = pose(Eigen::Vector3d(0.125, 0, 0));
  const ScanPattern pattern(fanBySamples(-1, 1, 21));
  Caster caster;
  const ScanResult first = caster.cast(scene, poses, sensor, pattern, config(true));
  poses.pose[0].pretranslate(Eigen::Vector3d(8, -4, 2));
  sensor.pretranslate(Eigen::Vector3d(8, -4, 2));
  const ScanResult& second = caster.cast(scene, poses, sensor, pattern, config(true));
  EXPECT_TRUE(second.stats.reused);
  expectSameResult(first, second);
}

}  // namespace
}  // namespace laser_raycast_test
