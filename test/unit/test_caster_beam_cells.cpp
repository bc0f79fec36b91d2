// Beam lists off any grid in cells (beams/beam_cells.h): what fitBeamCells makes of a rosette,
// random beams and a shuffled VLP-16 and what it turns down, and Caster::castBeams through the
// cells against the same beams cast one ray at a time (beam_list_cast.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <vector>

#include "beam_list_cast.h"
#include "beams/beam_cells.h"
#include "beams/beam_list_grid.h"
#include "cast_reference.h"
#include "laser_raycast/core/pattern_file.h"
#include "laser_raycast/core/velodyne_beams.h"
#include "random_scene.h"

namespace laser_raycast_test {
namespace {

// n random unit directions: within `cone` rad of azimuth `toward`, or (cone 0) over the sphere up
// to 70 degrees from the horizontal.
core::BeamList randomBeams(Rng& rng, int n, double cone, double toward = 0) {
  core::BeamList beams;
  for (int i = 0; i < n; ++i) {
    const double azimuth =
        cone > 0 ? toward + uniform(rng, -cone, cone) : uniform(rng, -M_PI, M_PI);
    const double elevation = cone > 0 ? uniform(rng, -cone, cone) : uniform(rng, -1.2, 1.2);
    beams.directions.push_back(core::beamDirection(azimuth, elevation));
  }
  return beams;
}

// Every beam in exactly one cell, with its own direction, no farther from its cell's direction
// than the turn, and the turn no more than a cell's diagonal.
void expectCellsHoldEachBeam(const core::BeamCells& cells, const core::BeamList& beams) {
  ASSERT_EQ(cells.first.size(), cells.culling.directions().size() + 1);
  EXPECT_EQ(cells.first.front(), 0);
  EXPECT_EQ(cells.first.back(), beams.size());
  std::vector<int> seen(beams.size(), 0);
  for (std::size_t c = 0; c + 1 < cells.first.size(); ++c) {
    ASSERT_LE(cells.first[c], cells.first[c + 1]);
    for (int k = cells.first[c]; k < cells.first[c + 1]; ++k) {
      ++seen[cells.beam[k]];
      EXPECT_EQ(cells.directions[k], beams.directions[cells.beam[k]]);
      const double angle = std::acos(std::min(1.0, cells.directions[k].dot(
                                                       cells.culling.directions()[c])));
      EXPECT_LE(angle, cells.turn + 1e-9);
    }
  }
  EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), beams.size());
  const double step = std::abs(cells.culling.angleIncrement());
  const auto& e = cells.culling.elevations();
  const double row_step = e.size() > 1 ? e[1] - e[0] : step;
  EXPECT_LE(cells.turn, std::hypot(step, row_step));
}

// A rosette, random beams in a cone (ahead, and behind: across azimuth +-pi) and all round, and a
// VLP-16's beams shuffled go into cells of about three beams each; a list too short, from several
// origins or too steep for the column raster is turned down.
TEST(FitBeamCells, ListsOffAnyGridGoIntoCells) {
  Rng rng(11);
  const core::PatternFile rosette =
      core::PatternFile::load(LASER_RAYCAST_SOURCE_DIR "/config/patterns/rosette_4line.csv");
  std::vector<int> order;
  const core::BeamList lists[] = {rosette.scan(0, rosette.size(), 1.0),
                                  randomBeams(rng, 3000, 0.6), randomBeams(rng, 3000, 0.3, M_PI),
                                  randomBeams(rng, 3000, 0),
                                  shuffled(core::nominalVlp16().scan(0.1), rng, &order)};
  const double cones[] = {0.62, 0.6, 0.3, M_PI, M_PI};  // each list's half width in azimuth
  for (int l = 0; l < 5; ++l) {
    const core::BeamList& beams = lists[l];
    const std::optional<core::BeamCells> cells = core::fitBeamCells(beams);
    ASSERT_TRUE(cells);
    expectCellsHoldEachBeam(*cells, beams);
    // The grid's columns span the beams' arc only (behind too, across +-pi).
    const double step = std::abs(cells->culling.angleIncrement());
    EXPECT_LE((cells->culling.azimuthCount() - 1) * step, 2 * cones[l] + 2 * step) << l;
    EXPECT_GT(cells->culling.size(), beams.size() / 6);
    EXPECT_LT(cells->culling.size(), beams.size());
  }
  EXPECT_FALSE(core::fitBeamCells(randomBeams(rng, core::kMinCellBeams - 1, 0.5)));
  core::BeamList origins = randomBeams(rng, 1000, 0.5);
  origins.origins.assign(1000, Eigen::Vector3d::Zero());
  ASSERT_TRUE(core::fitBeamCells(origins));
  origins.origins[7].x() = 0.01;
  EXPECT_FALSE(core::fitBeamCells(origins));
  core::BeamList steep = randomBeams(rng, 1000, 0.5);
  steep.directions[3] = Eigen::Vector3d(0.1, 0, 1).normalized();
  EXPECT_FALSE(core::fitBeamCells(steep));
}

// Cast in cells, each beam is still its own ray: ranges, bodies, triangles, normals and incidence
// bit for bit those of the beams cast one ray at a time, for any thread count, from a sensor at an
// origin of its own too.
TEST(CastBeamCells, ListsInCellsGiveTheRayByRayCast) {
  const core::PatternFile rosette =
      core::PatternFile::load(LASER_RAYCAST_SOURCE_DIR "/config/patterns/rosette_4line.csv");
  for (unsigned seed = 1; seed <= 3; ++seed) {
    Rng rng(seed + 40);
    const RandomScene s = randomScene(rng);
    const Eigen::Isometry3d sensor =
        pose(Eigen::Vector3d(uniform(rng, -1, 1), 0, 0.3), randomRotation(rng).toRotationMatrix());
    core::CastConfig c = config(true, 25.0);
    c.compute_incidence = true;
    std::vector<int> order;
    core::BeamList away = randomBeams(rng, 2000, 0.4);
    away.origins.assign(away.size(), Eigen::Vector3d(0.05, -0.02, 0.1));
    // From an origin of its own, the cells are cast from a reference there: ranges to the
    // rounding of the origin.
    struct Case {
      core::BeamList beams;
      double tolerance;
    };
    const Case cases[] = {{rosette.scan(0, rosette.size(), 1.0), 0.0},
                          {randomBeams(rng, 4000, 0), 0.0},
                          {randomBeams(rng, 2000, 0.3, M_PI), 0.0},
                          {away, 1e-12},
                          {shuffled(core::nominalVlp16().scan(0.1), rng, &order), 0.0}};
    for (const Case& k : cases) {
      const core::BeamList& beams = k.beams;
      ASSERT_TRUE(core::fitBeamCells(beams));
      order.resize(beams.size());
      std::iota(order.begin(), order.end(), 0);
      core::Caster cells, rays, threaded;
      const core::ScanResult expected = rayByRay(rays, s, sensor, beams, c);
      int hits = 0;
      for (int b : expected.body) hits += b >= 0;
      EXPECT_GT(hits, 20);  // the random scene is sparse in some directions
      expectSameResult(cells.castBeams(s.scene, s.poses, sensor, beams, c), expected, order,
                       k.tolerance);
      c.threads = 3;
      expectSameResult(threaded.castBeams(s.scene, s.poses, sensor, beams, c), expected, order,
                       k.tolerance);
      c.threads = 1;
    }
  }
}

// A caster keeps what its BeamSet makes of a list's directions (their float copy, each beam's shear
// for the watertight test) while the list stays the same, and makes them anew for another: lists
// cast in turn by one caster, a grid's (a VLP-16) and a list in cells (the rosette), each a second
// list of the same kind between (its beams turned by 0.01 rad), give each list's ray-by-ray cast
// bit for bit every time.
TEST(CastBeamCells, ListsCastInTurnEachGiveTheirOwnCast) {
  const core::PatternFile rosette =
      core::PatternFile::load(LASER_RAYCAST_SOURCE_DIR "/config/patterns/rosette_4line.csv");
  Rng rng(61);
  const RandomScene s = randomScene(rng);
  const Eigen::Isometry3d sensor = pose(Eigen::Vector3d(0.3, -0.2, 0.3), yaw(0.7));
  core::CastConfig c = config(true, 25.0);
  c.compute_incidence = true;
  auto turned = [](core::BeamList beams) {
    for (Eigen::Vector3d& d : beams.directions) d = yaw(0.01) * d;
    return beams;
  };
  const core::BeamList vlp16 = core::nominalVlp16().scan(0.1);
  const core::BeamList in_cells = rosette.scan(0, rosette.size(), 1.0);
  ASSERT_TRUE(core::fitBeamGrid(vlp16));
  ASSERT_TRUE(core::fitBeamCells(in_cells));
  for (const core::BeamList& first : {vlp16, in_cells}) {
    const core::BeamList second = turned(first);
    std::vector<int> order;
    const core::BeamList first_shuffled = shuffled(first, rng, &order);
    core::Caster rays;
    const core::ScanResult first_rays = rayByRay(rays, s, sensor, first_shuffled, c);
    const core::ScanResult second_rays = rayByRay(rays, s, sensor, turned(first_shuffled), c);
    core::Caster caster;
    for (int pass = 0; pass < 2; ++pass) {
      expectSameResult(caster.castBeams(s.scene, s.poses, sensor, first, c), first_rays, order,
                       0.0);
      expectSameResult(caster.castBeams(s.scene, s.poses, sensor, second, c), second_rays, order,
                       0.0);
    }
    const auto shared = std::make_shared<const core::BeamList>(first);
    for (int pass = 0; pass < 2; ++pass) {
      expectSameResult(caster.castBeams(s.scene, s.poses, sensor, shared, c), first_rays, order,
                       0.0);
    }
  }
}

}  // namespace
}  // namespace laser_raycast_test
