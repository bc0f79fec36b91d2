// Caster::castSweep, against distances worked out by hand: a rotating scan whose beams are taken at
// their own times, from a sensor (or a body) that moves during the sweep.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "cast_reference.h"
#include "expect_invalid.h"
#include "fan_specs.h"
#include "laser_raycast/core/ouster_beams.h"
#include "laser_raycast/core/pose_samples.h"
#include "laser_raycast/core/velodyne_beams.h"
#include "random_scene.h"
#include "sweep_by_columns.h"

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

// A sensor moving and turning through a random scene (a moving frame among them), sampled at
// `steps` + 1 times across `duration` s: position p0 + v t, orientation turning at w (world axes)
// from rpy; the cart moves at its own speed. With tilt 0 the sensor stays level and at one height
// (a robot driving on a floor): every column's scan plane is the same, bit for bit.
core::PoseSamples randomMotion(Rng& rng, const RandomScene& rs, double duration, double speed,
                               double turn_rate, double tilt) {
  core::PoseSamples s;
  const Eigen::Vector3d p0 =
      uniformInBox(rng, Eigen::Vector3d(-6, -6, -0.3), Eigen::Vector3d(6, 6, 0.3));
  const Eigen::Vector3d v =
      speed * randomUnitVector(rng).cwiseProduct(Eigen::Vector3d(1, 1, tilt > 0 ? 0.2 : 0.0));
  const Eigen::Vector3d w(tilt * uniform(rng, -1, 1), tilt * uniform(rng, -1, 1),
                          turn_rate * uniform(rng, -1, 1));
  const Eigen::Matrix3d r0 =
      rpy(tilt * uniform(rng, -1, 1), tilt * uniform(rng, -1, 1), uniform(rng, -3, 3));
  const Eigen::Vector3d cart_v(uniform(rng, -1, 1), uniform(rng, -1, 1), 0);
  const int steps = 7;
  for (int k = 0; k <= steps; ++k) {
    const double t = duration * k / steps;
    s.times.push_back(t);
    const Eigen::Matrix3d turn =
        w.norm() > 0 ? Eigen::AngleAxisd(w.norm() * t, w.normalized()).toRotationMatrix()
                     : Eigen::Matrix3d::Identity();
    s.world_from_sensor.push_back(pose(p0 + v * t, turn * r0));
    core::FramePoses frames = rs.poses;
    frames.pose[1].translation() += cart_v * t;
    s.frames.push_back(frames);
  }
  return s;
}

struct Agreement {
  long long beams = 0, hits = 0, range_off = 0, body_off = 0, triangle_off = 0;
  double worst = 0;
  void add(const Agreement& a) {
    beams += a.beams;
    hits += a.hits;
    range_off += a.range_off;
    body_off += a.body_off;
    triangle_off += a.triangle_off;
    worst = std::max(worst, a.worst);
  }
};

Agreement compare(const core::ScanResult& sweep, const core::ScanResult& columns, bool incidence) {
  Agreement a;
  for (std::size_t i = 0; i < sweep.range.size(); ++i) {
    ++a.beams;
    const double x = sweep.range[i], y = columns.range[i];
    if (std::isnan(x) || std::isnan(y) || std::isinf(x) || std::isinf(y)) {
      const bool same = (std::isnan(x) && std::isnan(y)) || x == y;
      a.range_off += !same;
      continue;
    }
    ++a.hits;
    const double off = std::abs(x - y);
    a.worst = std::max(a.worst, off);
    a.range_off += off > 1e-9;
    a.body_off += sweep.body[i] != columns.body[i];
    a.triangle_off += sweep.triangle[i] != columns.triangle[i];
    if (incidence && sweep.body[i] == columns.body[i] && sweep.triangle[i] == columns.triangle[i]) {
      EXPECT_NEAR(sweep.cos_incidence[i], columns.cos_incidence[i], 1e-9) << "beam " << i;
    }
  }
  return a;
}

// The blocks of a sweep against each column cast on its own (sweepByColumns): random scenes,
// sensors driving up to 3 m/s and turning up to 4 rad/s, level and tilting, planar fans and rings,
// one thread and two, with the fast paths and without (every beam traced from the root).
TEST(CastSweep, BlocksAgreeWithEachColumnCastOnItsOwn) {
  Rng rng(2211);
  Agreement all;
  int kept_slices = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const RandomScene rs = randomScene(rng);
    const double tilt = trial % 2 ? 0.3 : 0.0;
    const core::PoseSamples samples =
        randomMotion(rng, rs, 0.1, uniform(rng, 0, 3), uniform(rng, 0, 4), tilt);
    const bool planar = trial % 4 < 2;
    const core::ScanPattern pattern =
        planar ? core::ScanPattern(fanBySamples(-3.0, 3.0, 1441))
               : core::ScanPattern(fanBySamples(-M_PI, M_PI - 2 * M_PI / 720, 720),
                                   {-0.26, -0.2, -0.13, -0.09, -0.05, -0.02, 0.0, 0.02, 0.04, 0.07,
                                    0.11, 0.15, 0.2, 0.23, 0.26, 0.3});
    core::CastConfig cfg = config(trial % 3 != 2);
    cfg.threads = trial % 2 ? 2 : 1;
    cfg.compute_incidence = trial % 2 == 0;
    const double dt = 0.1 / pattern.azimuthCount();
    core::Caster caster;
    const core::ScanResult sweep = caster.castSweep(rs.scene, samples, pattern, cfg, dt);
    kept_slices += sweep.stats.kept_slices;
    const core::ScanResult columns = sweepByColumns(rs.scene, samples, pattern, cfg, dt);
    all.add(compare(sweep, columns, cfg.compute_incidence));
  }
  // The two methods round differently (the blocks test a column's ray from its origin in the
  // block's reference frame, the column cast from the origin of its own), so a beam through a
  // shared edge may be kept on the other triangle, and one grazing a silhouette may hit in one and
  // miss in the other: a handful in 10^5 beams, never a range off by more than 1e-9 m otherwise.
  EXPECT_GT(all.hits, 30000);
  EXPECT_GT(kept_slices, 0);  // the level planar sweeps went through kept slices
  EXPECT_LE(all.range_off, all.beams / 50000) << "of " << all.beams;
  EXPECT_LE(all.body_off, all.beams / 50000);
  EXPECT_LE(all.triangle_off, all.beams / 10000);
  std::printf(
      "sweep blocks vs columns: %lld beams, %lld hits, %lld ranges off, %lld bodies off, "
      "%lld triangles off, worst %.3g m\n",
      all.beams, all.hits, all.range_off, all.body_off, all.triangle_off, all.worst);
}

// A caster keeps state between casts (its beams' arrays and occlusion tiles, kept slices, the
// last cast's inputs): a caster that cast other sweeps before (other scenes, motions and patterns,
// one thread and two) gives each sweep the bits a new caster gives it.
TEST(CastSweep, ACasterThatCastOtherSweepsGivesTheBitsOfANewOne) {
  Rng rng(3301);
  long long hits = 0;
  core::Caster reused;
  for (int trial = 0; trial < 10; ++trial) {
    const RandomScene rs = randomScene(rng);
    const double tilt = trial % 2 ? 0.3 : 0.0;
    const core::PoseSamples samples =
        randomMotion(rng, rs, 0.1, uniform(rng, 0.5, 3), uniform(rng, 0, 4), tilt);
    const int columns = trial % 3 ? 720 : 360;
    const core::ScanPattern pattern(fanBySamples(-M_PI, M_PI - 2 * M_PI / columns, columns),
                                    {-0.2, -0.1, -0.03, 0.0, 0.05, 0.1, 0.2});
    core::CastConfig cfg = config(true);
    cfg.threads = trial % 4 < 2 ? 1 : 2;
    const double dt = 0.1 / columns;
    const core::ScanResult again = reused.castSweep(rs.scene, samples, pattern, cfg, dt);
    core::Caster fresh;
    const core::ScanResult& first = fresh.castSweep(rs.scene, samples, pattern, cfg, dt);
    ASSERT_EQ(again.range.size(), first.range.size());
    for (std::size_t i = 0; i < first.range.size(); ++i) {
      hits += std::isfinite(first.range[i]);
      ASSERT_EQ(std::memcmp(&again.range[i], &first.range[i], sizeof(double)), 0)
          << "trial " << trial << " beam " << i << ": " << again.range[i] << " vs "
          << first.range[i];
      ASSERT_EQ(again.body[i], first.body[i]) << "trial " << trial << " beam " << i;
      ASSERT_EQ(again.triangle[i], first.triangle[i]) << "trial " << trial << " beam " << i;
    }
  }
  EXPECT_GT(hits, 10000);
}

// Many small primitives close around a fast sensor: a beam of a block that meets one near its
// silhouette, from its own column's pose, may miss it from the reference pose. The primitives'
// pre-test (in the reference frame) must let every such beam through: checked against each column
// cast on its own, in the world frame and on the moving cart.
TEST(CastSweep, PrimitivesPreTestLetsThroughEveryBeamOfABlock) {
  Rng rng(4517);
  Agreement all;
  for (int trial = 0; trial < 12; ++trial) {
    RandomScene rs;
    core::Scene& scene = rs.scene;
    const int world = scene.addFrame("world");
    const int cart = scene.addFrame("cart");
    for (const char* label : {"box", "can", "bead"}) scene.addLabel(label);
    for (int i = 0; i < 300; ++i) {
      const Eigen::Vector3d at =
          randomUnitVector(rng).cwiseProduct(Eigen::Vector3d(1, 1, 0.15)) * uniform(rng, 0.4, 4);
      const Eigen::Isometry3d where = pose(at, randomRotation(rng).toRotationMatrix());
      const int frame = i % 4 ? world : cart;
      if (i % 3 == 0) {
        addBody(&scene,
                core::Box{uniformInBox(rng, Eigen::Vector3d::Constant(0.03),
                                       Eigen::Vector3d::Constant(0.4))},
                frame, where, 0);
      } else if (i % 3 == 1) {
        addBody(&scene, core::Cylinder{uniform(rng, 0.02, 0.2), uniform(rng, 0.05, 0.6)}, frame,
                where, 1);
      } else {
        addBody(&scene, core::Sphere{uniform(rng, 0.02, 0.2)}, frame, where, 2);
      }
    }
    rs.poses = core::FramePoses::identity(scene);
    const double tilt = trial % 2 ? 0.3 : 0.0;
    // Slow turns and a long sweep: blocks as long as their shift allows.
    const double duration = 0.4;
    const core::PoseSamples samples = randomMotion(rng, rs, duration, 3, 0.3, tilt);
    const bool planar = trial % 4 < 2;
    const core::ScanPattern pattern =
        planar ? core::ScanPattern(fanBySamples(-3.0, 3.0, 1441))
               : core::ScanPattern(fanBySamples(-M_PI, M_PI - 2 * M_PI / 720, 720),
                                   {-0.2, -0.1, -0.05, 0.0, 0.05, 0.1, 0.2});
    const core::CastConfig cfg = config(true);
    const double dt = duration / pattern.azimuthCount();
    core::Caster caster;
    const core::ScanResult sweep = caster.castSweep(rs.scene, samples, pattern, cfg, dt);
    const core::ScanResult columns = sweepByColumns(rs.scene, samples, pattern, cfg, dt);
    all.add(compare(sweep, columns, false));
  }
  EXPECT_GT(all.hits, 5000);
  EXPECT_EQ(all.range_off, 0) << "of " << all.beams;
  EXPECT_EQ(all.body_off, 0);
  std::printf(
      "primitives, sweep blocks vs columns: %lld beams, %lld hits, %lld ranges off, "
      "worst %.3g m\n",
      all.beams, all.hits, all.range_off, all.worst);
}

// A scene carried by the sensor's robot: every frame's pose is the sensor's at each sample times
// its pose relative to the sensor (rs.poses), plus `drift` (m) along x a sample further on. With
// no drift nothing moves relative to the sensor, so a sweep's every beam meets the scene where the
// cast from one pose does: rings, a planar fan, a calibrated Velodyne's turn and an Ouster's from
// its beam origins, the sensor driving and turning. With a drift of 0.1 um a sample the frames
// move relative to it (past the 1 nm within which a frame rides with the sensor): each beam from
// its own column's poses, as each column cast on its own gives, and some beams see it.
core::PoseSamples carriedBy(const core::PoseSamples& sensor, const core::FramePoses& relative,
                            double drift) {
  core::PoseSamples s = sensor;
  for (std::size_t k = 0; k < s.times.size(); ++k) {
    for (std::size_t f = 0; f < relative.pose.size(); ++f) {
      s.frames[k].pose[f] = s.world_from_sensor[k] * relative.pose[f] *
                            Eigen::Translation3d(drift * static_cast<double>(k), 0, 0);
    }
  }
  return s;
}

TEST(CastSweep, ASceneTheSensorCarriesIsSweptAsItsCastFromOnePose) {
  Rng rng(5802);
  Agreement carried, drifting;
  long long moved = 0;
  for (int trial = 0; trial < 8; ++trial) {
    const RandomScene rs = randomScene(rng);
    const double tilt = trial % 2 ? 0.3 : 0.0;
    const core::PoseSamples sensor =
        randomMotion(rng, rs, 0.1, uniform(rng, 0.5, 3), uniform(rng, 0.5, 4), tilt);
    const core::CastConfig cfg = config(true);
    const Eigen::Isometry3d at = Eigen::Isometry3d::Identity();
    // Grid sweeps.
    const core::ScanPattern pattern =
        trial % 4 < 2 ? core::ScanPattern(fanBySamples(-3.0, 3.0, 1441))
                      : core::ScanPattern(fanBySamples(-M_PI, M_PI - 2 * M_PI / 720, 720),
                                          {-0.2, -0.1, -0.03, 0.0, 0.05, 0.1, 0.2});
    const double dt = 0.1 / pattern.azimuthCount();
    core::Caster caster;
    const core::ScanResult still = cast(rs.scene, rs.poses, at, pattern, cfg);
    carried.add(
        compare(caster.castSweep(rs.scene, carriedBy(sensor, rs.poses, 0), pattern, cfg, dt), still,
                false));
    const core::PoseSamples drift = carriedBy(sensor, rs.poses, 1e-7);
    const core::ScanResult swept = caster.castSweep(rs.scene, drift, pattern, cfg, dt);
    drifting.add(compare(swept, sweepByColumns(rs.scene, drift, pattern, cfg, dt), false));
    for (std::size_t i = 0; i < swept.range.size(); ++i) {
      moved += std::isfinite(swept.range[i]) && std::abs(swept.range[i] - still.range[i]) > 1e-8;
    }
    // Beam lists swept through the grids: a Velodyne's lasers each at its own time, an Ouster's
    // columns from their beam origins.
    core::OusterHead ouster;
    for (int r = 0; r < 16; ++r) {
      ouster.altitudes_deg.push_back(15 - 2 * r);
      ouster.azimuths_deg.push_back(r % 2 ? -1.5 : 1.5);
    }
    ouster.beam_origin_x_mm = 15.8;
    ouster.columns = 512;
    ouster.last_column = 511;
    const core::BeamList list = trial % 2 ? core::nominalVlp16().scan(0.1) : ouster.scan(0.1);
    core::Caster list_caster;
    const core::ScanResult list_still = list_caster.castBeams(rs.scene, rs.poses, at, list, cfg);
    carried.add(
        compare(list_caster.castBeamsSweep(rs.scene, carriedBy(sensor, rs.poses, 0), list, cfg),
                list_still, false));
  }
  EXPECT_GT(carried.hits, 30000);
  EXPECT_EQ(carried.range_off, 0) << "of " << carried.beams << ", worst " << carried.worst;
  EXPECT_LT(carried.worst, 1e-12);  // the rounding of one relative pose, not a turn's chord
  EXPECT_EQ(carried.body_off, 0);
  EXPECT_LE(drifting.range_off, drifting.beams / 50000) << "of " << drifting.beams;
  EXPECT_GT(moved, 1000);
  std::printf(
      "carried scenes: %lld beams, %lld hits, worst %.3g m; drifting: %lld hits, %lld "
      "ranges off, %lld beams moved past 1e-8 m\n",
      carried.beams, carried.hits, carried.worst, drifting.hits, drifting.range_off, moved);
}

}  // namespace
}  // namespace laser_raycast_test
