// Beam lists that lie on grids (beams/beam_list_grid.h): what fitBeamGrid finds in a calibrated
// Velodyne's and an Ouster's lists and what it turns down, and Caster::castBeams through the grid's
// walks against the same beams cast one ray at a time (the list shuffled, which lies on no grid,
// cast in lists too short for cells: beam_list_cast.h). Lists in cells: test_caster_beam_cells.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <vector>

#include "beam_list_cast.h"
#include "beams/beam_list_grid.h"
#include "cast_reference.h"
#include "laser_raycast/core/ouster_beams.h"
#include "laser_raycast/core/pattern_file.h"
#include "laser_raycast/core/velodyne_beams.h"
#include "random_scene.h"

namespace laser_raycast_test {
namespace {

// An Ouster of 32 rows in four columns of lasers (azimuth offsets 4.2, 1.4, -1.4 and -4.2 deg,
// far more than a column apart), 512 columns, its beams 15.806 mm off the axis and the lidar
// frame turned half a turn and raised 36.18 mm in the sensor frame, as Ouster's files have it.
core::OusterHead ouster() {
  core::OusterHead head;
  const double offsets[] = {4.2, 1.4, -1.4, -4.2};
  for (int r = 0; r < 32; ++r) {
    head.altitudes_deg.push_back(15.5 - r);
    head.azimuths_deg.push_back(offsets[r % 4]);
  }
  head.beam_origin_x_mm = 15.806;
  head.lidar_to_sensor(0, 0) = head.lidar_to_sensor(1, 1) = -1;
  head.lidar_to_sensor(2, 3) = 36.18;
  head.columns = 512;
  head.last_column = 511;
  return head;
}

// Every beam of the list stands at exactly one grid beam, with its own direction.
void expectEachBeamOnce(const core::BeamListGrid& grid, const core::BeamList& beams) {
  std::vector<int> seen(beams.size(), 0);
  for (const core::BeamListGrid::Part& part : grid.parts) {
    ASSERT_EQ(part.beam.size(), part.culling.directions().size());
    for (std::size_t k = 0; k < part.beam.size(); ++k) {
      ++seen[part.beam[k]];
      EXPECT_EQ(part.directions[k], beams.directions[part.beam[k]]);
    }
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), beams.size());
}

// A VLP-16's sixteen lasers fire 2.304 us apart while the head turns a sequence's step in 55.296
// us: their azimuths drift by 15 x 2.304 / 55.296 = 0.625 of a step, one part whose grid lies in
// the middle of the drift. The farthest beams from their grid beams are the first and last lasers
// (ids 0 and 15, at -15 and 15 deg): half the drift in azimuth, cos 15 deg of that as an angle.
TEST(FitBeamGrid, Vlp16IsOneGridWithinHalfItsFiringDrift) {
  const core::BeamList beams = core::nominalVlp16().scan(0.1);
  const auto grid = core::fitBeamGrid(beams);
  ASSERT_TRUE(grid);
  ASSERT_EQ(grid->parts.size(), 1u);
  const core::BeamListGrid::Part& part = grid->parts[0];
  EXPECT_EQ(part.culling.ringCount(), 16);
  EXPECT_EQ(part.culling.azimuthCount(), static_cast<int>(0.1 / 55.296e-6));
  const double step = 2 * M_PI * 55.296e-6 / 0.1;
  EXPECT_NEAR(part.culling.angleIncrement(), step, 1e-12);
  const double farthest = 15 * 2 * M_PI * 2.304e-6 / 0.1 / 2 * std::cos(15 * M_PI / 180);
  EXPECT_GT(part.turn, farthest * (1 - 1e-6));
  EXPECT_LT(part.turn, farthest * (1 + 1e-6));
  EXPECT_EQ(grid->center, Eigen::Vector3d::Zero());
  for (const Eigen::Vector3d& o : part.column_origin) EXPECT_EQ(o, Eigen::Vector3d::Zero());
  expectEachBeamOnce(*grid, beams);
}

// The Ouster's four azimuth offsets make four parts, each exactly on its grid; the columns leave
// from the circle of 15.806 mm about the lidar's axis, 36.18 mm above the sensor's origin.
TEST(FitBeamGrid, OusterIsAGridForEachAzimuthOffset) {
  const core::BeamList beams = ouster().scan(0.1);
  const auto grid = core::fitBeamGrid(beams);
  ASSERT_TRUE(grid);
  ASSERT_EQ(grid->parts.size(), 4u);
  EXPECT_NEAR((grid->center - Eigen::Vector3d(0, 0, 0.03618)).norm(), 0, 1e-12);
  for (const core::BeamListGrid::Part& part : grid->parts) {
    EXPECT_EQ(part.culling.ringCount(), 8);
    EXPECT_EQ(part.culling.azimuthCount(), 512);
    EXPECT_LT(part.turn, 1e-12);
    for (const Eigen::Vector3d& o : part.column_origin) EXPECT_NEAR(o.norm(), 0.015806, 1e-12);
  }
  expectEachBeamOnce(*grid, beams);
}

// Lists on no grid: shuffled, without lines, lasers of one column from different origins (a
// Velodyne's offset corrections), a rosette, and lines whose offsets spread over more than
// kMaxParts parts.
TEST(FitBeamGrid, ListsOnNoGridAreTurnedDown) {
  Rng rng(3);
  std::vector<int> order;
  const core::BeamList vlp16 = core::nominalVlp16().scan(0.1);
  EXPECT_FALSE(core::fitBeamGrid(shuffled(vlp16, rng, &order)));
  core::BeamList no_lines = vlp16;
  no_lines.lines.clear();
  EXPECT_FALSE(core::fitBeamGrid(no_lines));
  core::VelodyneHead offset = core::nominalVlp16();
  offset.lasers[3].horiz_offset = 0.02;
  EXPECT_FALSE(core::fitBeamGrid(offset.scan(0.1)));
  const core::PatternFile rosette =
      core::PatternFile::load(LASER_RAYCAST_SOURCE_DIR "/config/patterns/rosette_4line.csv");
  EXPECT_FALSE(core::fitBeamGrid(rosette.scan(0, rosette.size(), 1.0)));
  core::OusterHead spread = ouster();
  for (int r = 0; r < spread.rows(); ++r) spread.azimuths_deg[r] = 2.0 * r;
  EXPECT_FALSE(core::fitBeamGrid(spread.scan(0.1)));
}

// Through the grid's walks each beam is its own ray: a Velodyne's (from the sensor's origin) gives
// the ray-by-ray cast's ranges, bodies, triangles and normals bit for bit, an Ouster's (from its
// column's origin, relative to the middle of them) its ranges to the rounding of the origins, for
// any thread count.
TEST(CastBeamGrid, CalibratedListsGiveTheRayByRayCast) {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    Rng rng(seed);
    const RandomScene s = randomScene(rng);
    const Eigen::Isometry3d sensor =
        pose(Eigen::Vector3d(uniform(rng, -1, 1), 0, 0.3), randomRotation(rng).toRotationMatrix());
    core::CastConfig c = config(true, 25.0);
    c.compute_incidence = true;
    struct Case {
      core::BeamList beams;
      double tolerance;
    };
    const Case cases[] = {{core::nominalVlp16().scan(0.1), 0.0},
                          {core::nominalHdl32e().scan(0.1), 0.0},
                          {ouster().scan(0.1), 1e-12}};
    for (const Case& k : cases) {
      ASSERT_TRUE(core::fitBeamGrid(k.beams));
      std::vector<int> order;
      const core::BeamList one_by_one = shuffled(k.beams, rng, &order);
      core::Caster grid, rays, threaded;
      const core::ScanResult expected = rayByRay(rays, s, sensor, one_by_one, c);
      int hits = 0;
      for (int b : expected.body) hits += b >= 0;
      EXPECT_GT(hits, k.beams.size() / 10);
      expectSameResult(grid.castBeams(s.scene, s.poses, sensor, k.beams, c), expected, order,
                       k.tolerance);
      c.threads = 3;
      expectSameResult(threaded.castBeams(s.scene, s.poses, sensor, k.beams, c), expected, order,
                       k.tolerance);
      c.threads = 1;
    }
  }
}

// The caster remembers the last list's grids: a list changed in place (one direction, one origin)
// is fitted anew, and gives the ray-by-ray cast of its new beams.
TEST(CastBeamGrid, AChangedListIsFittedAnew) {
  Rng rng(5);
  const RandomScene s = randomScene(rng);
  const Eigen::Isometry3d sensor = pose(Eigen::Vector3d(0.2, 0.1, 0.3), yaw(0.4));
  core::CastConfig c = config(true, 25.0);
  c.compute_incidence = true;
  core::BeamList beams = core::nominalVlp16().scan(0.1);
  core::Caster caster, rays;
  caster.castBeams(s.scene, s.poses, sensor, beams, c);
  beams.directions[100] = Eigen::Vector3d(0, 0, -1);
  beams.origins[5000] = Eigen::Vector3d(0.01, 0, 0);
  std::vector<int> order;
  const core::BeamList one_by_one = shuffled(beams, rng, &order);
  const core::ScanResult expected = rayByRay(rays, s, sensor, one_by_one, c);
  expectSameResult(caster.castBeams(s.scene, s.poses, sensor, beams, c), expected, order, 0.0);
}

// A VLP-16 whose azimuth corrections cancel its lasers' drift over the firing sequence: every
// laser of a sequence points at the sequence's azimuth, so its grid holds the beams exactly (no
// turn to widen the raster), while each laser still fires at its own time.
core::VelodyneHead driftless() {
  core::VelodyneHead head = core::nominalVlp16();
  for (core::VelodyneLaser& l : head.lasers) {
    l.rot_correction = 2 * M_PI * l.id * head.timing.laser_period / 0.1;
  }
  return head;
}

// A rotating sweep through the grids: each beam from the sensor and frame poses at its own time
// (a VLP-16's lasers each at its place in the firing sequence, an Ouster's columns at theirs),
// against the shuffled list's ray-by-ray sweep; the sensor drives (at 6 m/s: a laser's origin
// moves 0.2 mm between the first and last of a sequence) and turns (2 rad/s, or 0.1 rad/s as a
// robot sways: its samples' slerp takes the shortest sine series), or only drives, the cart moves
// the other way, and the sensor has no pose for the first 20 ms (those beams NaN either way).
TEST(CastBeamGrid, RotatingSweepsGiveTheRayByRaySweep) {
  const auto drift_free = core::fitBeamGrid(driftless().scan(0.1));
  ASSERT_TRUE(drift_free);
  EXPECT_LT(drift_free->parts[0].turn, 1e-9);
  for (unsigned seed = 1; seed <= 4; ++seed) {
    Rng rng(seed + 20);
    const RandomScene s = randomScene(rng);
    core::PoseSamples samples;
    const Eigen::Isometry3d start =
        pose(Eigen::Vector3d(uniform(rng, -1, 1), 0, 0.3), randomRotation(rng).toRotationMatrix());
    for (int k = 0; k <= 5; ++k) {
      const double t = 0.02 * k;
      samples.times.push_back(t);
      // Seed 1 only drives: no turn widens the raster, so the lasers' origins off their
      // column's must (ColumnMotion::deviation).
      const double turn_rate = seed == 1 ? 0.0 : seed == 4 ? 0.1 : 2.0;
      Eigen::Isometry3d sensor =
          start * pose(Eigen::Vector3d(6 * t, 0.4 * t, 0), yaw(turn_rate * t));
      if (k == 0) sensor.translation().x() = std::nan("");
      samples.world_from_sensor.push_back(sensor);
      core::FramePoses frames = s.poses;
      frames.pose[1] = pose(Eigen::Vector3d(-3 * t, 0, 0)) * frames.pose[1];
      samples.frames.push_back(frames);
    }
    core::CastConfig c = config(true, 25.0);
    c.compute_incidence = true;
    for (const core::BeamList& beams :
         {core::nominalVlp16().scan(0.1), driftless().scan(0.1), ouster().scan(0.1)}) {
      std::vector<int> order;
      const core::BeamList one_by_one = shuffled(beams, rng, &order);
      core::Caster grid, rays;
      const core::ScanResult expected = rays.castBeamsSweep(s.scene, samples, one_by_one, c);
      const core::ScanResult& r = grid.castBeamsSweep(s.scene, samples, beams, c);
      int hits = 0, nan = 0, differing = 0;
      for (std::size_t k = 0; k < order.size(); ++k) {
        const int i = order[k];
        hits += expected.body[k] >= 0;
        nan += std::isnan(expected.range[k]);
        const bool same =
            (std::isnan(r.range[i]) && std::isnan(expected.range[k])) ||
            (near(r.range[i], expected.range[k], 1e-9) && r.body[i] == expected.body[k] &&
             (r.body[i] < 0 || (r.normal[i] - expected.normal[k]).norm() < 1e-9));
        if (!same && differing++ < 5) {
          ADD_FAILURE() << "beam " << i << ": range " << r.range[i] << " vs "
                        << expected.range[k] << ", body " << r.body[i] << " vs "
                        << expected.body[k];
        }
      }
      EXPECT_EQ(differing, 0);
      EXPECT_GT(hits, beams.size() / 10);
      EXPECT_GT(nan, beams.size() / 20);
    }
  }
}

// Whether two results hold the same ranges (NaN where either is), bodies and triangles, bit for bit.
bool sameBits(const core::ScanResult& a, const core::ScanResult& b) {
  if (a.range.size() != b.range.size()) return false;
  for (std::size_t i = 0; i < a.range.size(); ++i) {
    const bool same_range =
        a.range[i] == b.range[i] || (std::isnan(a.range[i]) && std::isnan(b.range[i]));
    if (!same_range || a.body[i] != b.body[i] || a.triangle[i] != b.triangle[i]) return false;
  }
  return true;
}

// A list the caller shares is known again by its pointer; any other list is still compared with
// the one fitted last, its firing times too: a sweep of the same beams fired twice as fast (a
// 20 Hz turn's times), passed by value after the shared list, is swept at its own times, and the
// shared list after it at the shared times again. Each sweep as a fresh caster's, also where the
// sensor has no pose after a sweep that had one. A null list is refused.
TEST(CastBeamGrid, ASharedListIsKnownByItsPointerAndOthersAreCompared) {
  Rng rng(31);
  const RandomScene s = randomScene(rng);
  core::PoseSamples samples;
  for (int k = 0; k <= 5; ++k) {
    const double t = 0.02 * k;
    samples.times.push_back(t);
    samples.world_from_sensor.push_back(pose(Eigen::Vector3d(4 * t, 0.2, 0.3), yaw(3 * t)));
    samples.frames.push_back(s.poses);
  }
  core::CastConfig c = config(true, 25.0);
  const auto shared = std::make_shared<const core::BeamList>(core::nominalVlp16().scan(0.1));
  core::BeamList faster = *shared;
  for (double& t : faster.times) t *= 0.5;
  auto fresh = [&](const core::BeamList& beams) {
    core::Caster caster;
    return caster.castBeamsSweep(s.scene, samples, beams, c);
  };
  const core::ScanResult at_shared_times = fresh(*shared), at_faster_times = fresh(faster);
  int hits = 0;
  for (int b : at_shared_times.body) hits += b >= 0;
  EXPECT_GT(hits, shared->size() / 10);
  // The times matter: the sensor turns 3 rad/s, so some beam meets something else or elsewhere.
  EXPECT_FALSE(sameBits(at_shared_times, at_faster_times));

  core::Caster caster;
  EXPECT_TRUE(sameBits(caster.castBeamsSweep(s.scene, samples, shared, c), at_shared_times));
  EXPECT_TRUE(sameBits(caster.castBeamsSweep(s.scene, samples, shared, c), at_shared_times));
  EXPECT_TRUE(sameBits(caster.castBeamsSweep(s.scene, samples, faster, c), at_faster_times));
  EXPECT_TRUE(sameBits(caster.castBeamsSweep(s.scene, samples, shared, c), at_shared_times));
  const Eigen::Isometry3d sensor = samples.world_from_sensor.front();
  core::Caster one_pose;
  EXPECT_TRUE(sameBits(caster.castBeams(s.scene, s.poses, sensor, shared, c),
                       one_pose.castBeams(s.scene, s.poses, sensor, *shared, c)));

  // Without a sensor pose for the first 20 ms, those beams are NaN and meet nothing, whatever the
  // caster's last sweep met there.
  core::PoseSamples late = samples;
  late.world_from_sensor.front().translation().x() = std::nan("");
  core::Caster fresh_late;
  const core::ScanResult& without_start = caster.castBeamsSweep(s.scene, late, shared, c);
  int nan = 0, nan_meeting = 0;
  for (std::size_t i = 0; i < without_start.range.size(); ++i) {
    if (!std::isnan(without_start.range[i])) continue;
    ++nan;
    nan_meeting += without_start.body[i] != -1 || without_start.triangle[i] != -1;
  }
  EXPECT_GT(nan, shared->size() / 10);
  EXPECT_EQ(nan_meeting, 0);
  EXPECT_TRUE(sameBits(without_start, fresh_late.castBeamsSweep(s.scene, late, *shared, c)));

  const std::shared_ptr<const core::BeamList> none;
  EXPECT_THROW(caster.castBeams(s.scene, s.poses, sensor, none, c), std::invalid_argument);
  EXPECT_THROW(caster.castBeamsSweep(s.scene, samples, none, c), std::invalid_argument);
}

}  // namespace
}  // namespace laser_raycast_test
