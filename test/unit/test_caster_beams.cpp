// Caster::castBeams and castBeamsSweep (beams off any grid) and core::PatternFile: the beams of a
// grid pattern give the grid cast's results bit for bit; random beams from random origins agree
// with the brute force; a sweep's beam is the cast of that beam alone from the poses at its time;
// a pattern file's beams have the directions, lines and times worked out by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "cast_reference.h"
#include "expect_invalid.h"
#include "fan_specs.h"
#include "laser_raycast/core/pattern_file.h"
#include "laser_raycast/core/pose_samples.h"
#include "random_scene.h"

namespace laser_raycast_test {
namespace {

template <class F>
void expectInvalid(F&& f, const std::string& needle) {
  expectMentions(invalidMessage(f), {needle});
}

core::BeamList beamsOf(const core::ScanPattern& pattern) {
  core::BeamList beams;
  beams.directions = pattern.directions();
  return beams;
}

void expectSameResult(const core::ScanResult& a, const core::ScanResult& b, bool normals) {
  ASSERT_EQ(a.range.size(), b.range.size());
  int differing = 0;
  for (std::size_t i = 0; i < a.range.size(); ++i) {
    const bool same_range =
        a.range[i] == b.range[i] || (std::isnan(a.range[i]) && std::isnan(b.range[i]));
    const bool same = same_range && a.body[i] == b.body[i] && a.triangle[i] == b.triangle[i] &&
                      (!normals || a.normal[i] == b.normal[i]);
    if (!same && differing++ < 5) {
      ADD_FAILURE() << "beam " << i << ": range " << a.range[i] << " vs " << b.range[i] << ", body "
                    << a.body[i] << " vs " << b.body[i] << ", triangle " << a.triangle[i] << " vs "
                    << b.triangle[i];
    }
  }
  EXPECT_EQ(differing, 0);
}

// The same rays, the same tests: a grid pattern's beams cast as a list give the grid cast's ranges,
// bodies, triangles and normals exactly, for every triangle method and any thread count.
TEST(CastBeams, GridBeamsGiveTheGridCastExactly) {
  for (unsigned seed = 1; seed <= 4; ++seed) {
    Rng rng(seed);
    const RandomScene s = randomScene(rng);
    const core::ScanPattern pattern(fanBySamples(-M_PI, M_PI, 361),
                                    {-0.4, -0.25, -0.1, -0.02, 0.05, 0.15, 0.3});
    const Eigen::Isometry3d sensor =
        pose(Eigen::Vector3d(uniform(rng, -1, 1), 0, 0.3), randomRotation(rng).toRotationMatrix());
    for (const core::TriangleMethod method :
         {core::TriangleMethod::kWatertight, core::TriangleMethod::kSeedPlane}) {
      core::CastConfig c = config(true, 25.0);
      c.method = method;
      c.compute_incidence = true;
      core::Caster grid, list;
      const core::ScanResult& expected = grid.cast(s.scene, s.poses, sensor, pattern, c);
      expectSameResult(list.castBeams(s.scene, s.poses, sensor, beamsOf(pattern), c), expected,
                       true);
      EXPECT_EQ(list.castBeams(s.scene, s.poses, sensor, beamsOf(pattern), c).cos_incidence,
                expected.cos_incidence);
      c.threads = 3;
      core::Caster threaded;
      expectSameResult(threaded.castBeams(s.scene, s.poses, sensor, beamsOf(pattern), c), expected,
                       true);
    }
  }
}

// Random directions from random origins near the sensor, against every body by brute force (the
// sensor moved to each beam's origin, Eigen's own inverse).
TEST(CastBeams, BeamsFromTheirOwnOriginsMatchTheBruteForce) {
  Rng rng(7);
  const RandomScene s = randomScene(rng);
  const Eigen::Isometry3d sensor = pose(Eigen::Vector3d(0.5, -0.5, 0.2), yaw(0.3));
  core::BeamList beams;
  for (int i = 0; i < 3000; ++i) {
    beams.directions.push_back(randomUnitVector(rng));
    beams.origins.push_back(uniformInCube(rng, 0.1));
  }
  const core::CastConfig c = config(true, 25.0);
  core::Caster caster;
  const core::ScanResult& r = caster.castBeams(s.scene, s.poses, sensor, beams, c);
  int hits = 0;
  for (int i = 0; i < beams.size(); ++i) {
    Eigen::Isometry3d from = sensor;
    from.translation() += sensor.linear() * beams.origins[i];
    // The brute force over the one beam, from the ray directly.
    double t = kInf;
    for (std::size_t b = 0; b < s.scene.bodies().size(); ++b) {
      const core::Body& body = s.scene.bodies()[b];
      const Eigen::Isometry3d body_from_sensor =
          (s.poses.pose[body.frame] * body.frame_from_body).inverse(Eigen::Isometry) * from;
      core::Ray ray;
      ray.origin = body_from_sensor.translation();
      ray.dir = body_from_sensor.linear() * beams.directions[i];
      ray.tmax = c.tmax;
      if (const auto* mesh = std::get_if<std::shared_ptr<const core::Mesh>>(&body.shape)) {
        const auto& v = (*mesh)->vertices();
        for (const auto& tri : (*mesh)->triangles()) {
          const auto hit = core::intersectTriangle(c.method, ray, v[tri[0]], v[tri[1]], v[tri[2]],
                                                   c.cull_backfaces);
          if (hit) t = std::min(t, hit->t);
        }
      } else {
        std::optional<core::PrimitiveHit> hit;
        if (const auto* box = std::get_if<core::Box>(&body.shape)) hit = core::intersect(ray, *box);
        if (const auto* cyl = std::get_if<core::Cylinder>(&body.shape)) {
          hit = core::intersect(ray, *cyl);
        }
        if (const auto* sph = std::get_if<core::Sphere>(&body.shape)) {
          hit = core::intersect(ray, *sph);
        }
        if (hit) t = std::min(t, hit->t);
      }
    }
    hits += std::isfinite(t);
    EXPECT_TRUE(near(r.range[i], t, 1e-9)) << "beam " << i << ": " << r.range[i] << " vs " << t;
  }
  EXPECT_GT(hits, 300);  // about a fifth of random directions hit something
}

// A sweep's beam is cast from the sensor and frame poses at its own time: the same result as that
// beam cast alone from those poses.
TEST(CastBeams, SweepBeamIsItsOwnCastAtItsTime) {
  Rng rng(11);
  const RandomScene s = randomScene(rng);
  core::PoseSamples samples;
  for (int k = 0; k < 5; ++k) {
    const double t = 0.025 * k;
    samples.times.push_back(t);
    samples.world_from_sensor.push_back(pose(Eigen::Vector3d(2 * t, -t, 0.2), yaw(3 * t)));
    core::FramePoses frames = s.poses;
    frames.pose[1] = pose(Eigen::Vector3d(-4 * t, 0, 0)) * frames.pose[1];  // the cart moves
    samples.frames.push_back(frames);
  }
  core::BeamList beams;
  for (int i = 0; i < 2000; ++i) {
    beams.directions.push_back(randomUnitVector(rng));
    beams.times.push_back(i * 0.1 / 2000);
  }
  const core::CastConfig c = config(true, 25.0);
  core::Caster caster, alone;
  const core::ScanResult r = caster.castBeamsSweep(s.scene, samples, beams, c);
  int differing = 0;
  for (int i = 0; i < beams.size(); i += 7) {
    core::FramePoses frames = s.poses;
    samples.framesAt(beams.times[i], &frames);
    core::BeamList single;
    single.directions = {beams.directions[i]};
    const core::ScanResult& one =
        alone.castBeams(s.scene, frames, samples.sensorAt(beams.times[i]), single, c);
    differing += !(one.range[0] == r.range[i]);
    differing += one.body[0] != r.body[i];
  }
  EXPECT_EQ(differing, 0);
}

// A beam from an origin off the sensor's: its range is measured from that origin. A wall x = 5.
TEST(CastBeams, RangeFromTheBeamsOrigin) {
  core::Scene scene = sceneWithFrame();
  addBody(&scene, core::Box{Eigen::Vector3d(0.2, 100, 100)}, 0, pose({5.1, 0, 0}));
  core::BeamList beams;
  beams.directions = {Eigen::Vector3d::UnitX(), Eigen::Vector3d(1, 1, 0).normalized()};
  beams.origins = {Eigen::Vector3d(0.03, 0.01, -0.02), Eigen::Vector3d(-0.015, 0, 0)};
  core::Caster caster;
  const core::ScanResult& r = caster.castBeams(scene, core::FramePoses::identity(scene),
                                               Eigen::Isometry3d::Identity(), beams, config(true));
  EXPECT_NEAR(r.range[0], 4.97, 1e-12);
  EXPECT_NEAR(r.range[1], 5.015 * std::sqrt(2.0), 1e-12);
}

TEST(CastBeams, BadSensorPoseGivesNanAndBadBeamsAreRefused) {
  core::Scene scene = sceneWithFrame();
  addBody(&scene, core::Sphere{1.0}, 0, pose({5, 0, 0}));
  core::BeamList beams;
  beams.directions = {Eigen::Vector3d::UnitX()};
  core::Caster caster;
  Eigen::Isometry3d bad = Eigen::Isometry3d::Identity();
  bad.translation().x() = std::nan("");
  EXPECT_TRUE(std::isnan(
      caster.castBeams(scene, core::FramePoses::identity(scene), bad, beams, config(true))
          .range[0]));
  beams.directions[0] = Eigen::Vector3d(2, 0, 0);
  expectInvalid(
      [&] {
        caster.castBeams(scene, core::FramePoses::identity(scene), Eigen::Isometry3d::Identity(),
                         beams, config(true));
      },
      "direction of beam 0");
  beams.directions[0] = Eigen::Vector3d::UnitX();
  beams.times = {-1.0};
  expectInvalid(
      [&] {
        caster.castBeams(scene, core::FramePoses::identity(scene), Eigen::Isometry3d::Identity(),
                         beams, config(true));
      },
      "time of beam 0");
}

core::PatternFile parsePattern(const std::string& text) {
  std::istringstream in(text);
  return core::PatternFile::parse(in, "test.csv");
}

// Directions from azimuth (counter-clockwise from x) and zenith (from +z), worked out by hand; the
// file read as a loop, point k of a scan at k / point_rate s.
TEST(PatternFile, DirectionsLinesAndTimesByHand) {
  const core::PatternFile file = parsePattern(
      "Time/s,Azimuth/deg,Zenith/deg,Line\n"
      "0,0,90,0\n"
      "0.1,90,90,1\n"
      "0.2,180,45,2\n"
      "0.3,-90,0,3\n");
  ASSERT_EQ(file.size(), 4);
  EXPECT_TRUE(file.hasLines());
  const core::BeamList beams = file.scan(3, 6, 1000.0);
  ASSERT_EQ(beams.size(), 6);
  const double h = std::sqrt(0.5);
  const Eigen::Vector3d expected[6] = {{0, 0, 1},  {1, 0, 0}, {0, 1, 0},
                                       {-h, 0, h}, {0, 0, 1}, {1, 0, 0}};
  const int lines[6] = {3, 0, 1, 2, 3, 0};
  for (int k = 0; k < 6; ++k) {
    EXPECT_LT((beams.directions[k] - expected[k]).norm(), 1e-15) << k;
    EXPECT_EQ(beams.lines[k], lines[k]) << k;
    EXPECT_DOUBLE_EQ(beams.times[k], k / 1000.0);
  }
  EXPECT_NO_THROW(beams.validate());
  const core::PatternFile no_lines = parsePattern("Time/s,Azimuth/deg,Zenith/deg\n0,10,80\n");
  EXPECT_FALSE(no_lines.hasLines());
  EXPECT_EQ(no_lines.scan(0, 1, 1.0).lines[0], 0);
}

TEST(PatternFile, BadFilesAreRefusedNamingTheLine) {
  expectInvalid([] { parsePattern(""); }, "test.csv line 0: empty");
  expectInvalid([] { parsePattern("Time,Azimuth,Zenith\n0,0,0\n"); }, "line 1: header");
  expectInvalid([] { parsePattern("Time/s,Azimuth/deg,Zenith/deg\n"); }, "no rows");
  expectInvalid([] { parsePattern("Time/s,Azimuth/deg,Zenith/deg\n0,0,90\n0,0\n"); },
                "line 3: 2 fields, expected 3");
  expectInvalid([] { parsePattern("Time/s,Azimuth/deg,Zenith/deg\n0,x,90\n"); },
                "line 2: field 2 'x' is not a finite number");
  expectInvalid([] { parsePattern("Time/s,Azimuth/deg,Zenith/deg\n0,0,190\n"); },
                "zenith 190 deg is outside [0, 180]");
  expectInvalid([] { parsePattern("Time/s,Azimuth/deg,Zenith/deg,Line\n0,0,90,1.5\n"); },
                "line 1.5 is not an integer");
  expectInvalid([] { core::PatternFile::load("/nonexistent/pattern.csv"); }, "cannot be opened");
}

// The repository's example rosette (scripts/make_rosette_pattern) reads, with its four lines.
TEST(PatternFile, ExampleRosetteReads) {
  const core::PatternFile file =
      core::PatternFile::load(LASER_RAYCAST_SOURCE_DIR "/config/patterns/rosette_4line.csv");
  EXPECT_EQ(file.size(), 10000);
  int max_line = 0;
  for (const auto& row : file.rows()) max_line = std::max(max_line, row.line);
  EXPECT_EQ(max_line, 3);
}

}  // namespace
}  // namespace laser_raycast_test
