// Caster::castBeams for a beam list that lies on grids (beams/beam_list_grid.h): a calibrated
// spinning lidar's beams, each cast exactly as its own ray, with the grid's walks finding what
// each may hit.
//
// Each part of the grid is cast as a bundle (BeamSet::Bundle) whose one sub-ray at a grid beam is
// the list's beam there, from a reference pose at the middle of the beams' origins: each column of
// the part leaves from its own origin (a ColumnMotion of translations, as a rotating sweep's block
// leaves from its columns' poses), and the windows are widened by that shift and by the part's
// turn. The walks test the sub-ray wherever they would test its grid beam, so a beam's range is
// what its own ray gives; only the work of finding its triangles is shared.
#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "caster/caster_state.h"
#include "caster/column_poses.h"
#include "walk/frame_walk.h"

namespace laser_raycast {
namespace core {

const BeamListGrid* CasterState::gridOf(const BeamList& beams) {
  const std::vector<Eigen::Vector3d>& origins = beams.origins;
  if (!fitted || fitted->directions != beams.directions || fitted->origins != origins ||
      fitted->lines != beams.lines) {
    fitted.reset();
    beams.validate();
    fitted = FittedList{beams.directions, origins, beams.lines, fitBeamGrid(beams)};
  }
  return fitted->grid ? &*fitted->grid : nullptr;
}

void CasterState::castBeamGrids(const Scene& scene, const FramePoses& poses,
                                const Eigen::Isometry3d& world_from_sensor, const BeamList& list,
                                const BeamListGrid& grid, const CastConfig& config,
                                ScanResult* result) {
  bool offsets = false;
  for (const BeamListGrid::Part& part : grid.parts) {
    for (const Eigen::Vector3d& o : part.column_origin) offsets = offsets || !o.isZero(0);
  }
  if (offsets) {
    // Columns from origins of their own (an Ouster's): cast in blocks of columns, each from its
    // middle column's origin, as a sweep whose every column is at the one pose.
    PoseSamples at_once;
    at_once.times = {0.0};
    at_once.world_from_sensor = {world_from_sensor};
    at_once.frames = {poses};
    castBeamGridsSweep(scene, at_once, list, grid, config, result, true);
    return;
  }
  const int bodies = static_cast<int>(scene.bodies().size());
  const Eigen::Isometry3d world_from_ref = world_from_sensor * Eigen::Translation3d(grid.center);
  std::vector<char> cast_any(bodies, 0);
  ScanResult& culling = grid_culling;
  ScanResult& own = grid_own;
  for (const BeamListGrid::Part& part : grid.parts) {
    const ReuseKey key = relativeInputs(scene, poses, world_from_ref, part.culling, config);
    result->stats.bodies_skipped = 0;
    placeGroups(scene, key, part.culling, &placed, &result->stats.bodies_skipped);
    std::vector<Eigen::Isometry3d> ref_from_column;
    ref_from_column.reserve(part.column_origin.size());
    for (const Eigen::Vector3d& o : part.column_origin) {
      ref_from_column.emplace_back(Eigen::Translation3d(o));
    }
    const ColumnMotion motion(0, std::move(ref_from_column), steepestElevation(part.culling),
                              part.turn);
    resetResult(part.culling.size(), bodies, true, false, &culling);
    resetResult(part.culling.size(), bodies, true, config.compute_incidence, &own);
    BeamSet::Bundle sub_rays;
    sub_rays.directions.push_back(&part.directions);
    sub_rays.results.push_back(&own);
    castOnThreads(
        scene, part.culling, config, &culling,
        [&](const BeamRect& within) {
          for (const PlacedGroup& p : placed) {
            walkFrame(beams, scene, *p.group, *p.sensor_from_frame, config, within, &cast,
                      &motion);
          }
        },
        &sub_rays);
    for (int b = 0; b < bodies; ++b) cast_any[b] |= cast[b].load(std::memory_order_relaxed);
    for (std::size_t k = 0; k < part.beam.size(); ++k) {
      const int i = part.beam[k];
      result->range[i] = own.range[k];
      result->body[i] = own.body[k];
      result->triangle[i] = own.triangle[k];
      if (config.compute_incidence && own.body[k] >= 0) {
        result->normal[i] = own.normal[k];
        result->cos_incidence[i] = std::min(1.0, std::abs(list.directions[i].dot(own.normal[k])));
      }
    }
  }
  int cast_count = 0;
  for (char c : cast_any) cast_count += c;
  result->stats.bodies_culled = bodies - result->stats.bodies_skipped - cast_count;
}

namespace {

// The lines of a part that fire at one time in every column (an Ouster's column, a Velodyne
// laser's place in its firing sequence): a rotating sweep casts each such class as a sweep of its
// own, every column from the poses at its one time.
struct TimeClass {
  ScanPattern culling;
  std::vector<Eigen::Vector3d> directions;
  std::vector<int> beam;
  std::vector<double> column_time;
  double turn = 0;
};

// at_once: every beam at time 0 (a cast from one pose).
std::vector<TimeClass> timeClasses(const BeamListGrid::Part& part, const BeamList& list,
                                   bool at_once) {
  const int rows = part.culling.ringCount(), cols = part.culling.azimuthCount();
  auto time = [&](int ring, int col) {
    return at_once ? 0.0 : list.time(part.beam[ring * cols + col]);
  };
  std::vector<std::vector<int>> classes;
  for (int ring = 0; ring < rows; ++ring) {
    bool placed = false;
    for (std::vector<int>& rings : classes) {
      bool same = true;
      for (int col = 0; col < cols && same; ++col) same = time(ring, col) == time(rings[0], col);
      if (same) {
        rings.push_back(ring);
        placed = true;
        break;
      }
    }
    if (!placed) classes.push_back({ring});
  }
  FanSpec fan;
  fan.angle_min = part.culling.angleMin();
  fan.angle_max = part.culling.angleMax();
  fan.samples = cols;
  std::vector<TimeClass> out;
  for (const std::vector<int>& rings : classes) {
    std::vector<double> elevations;
    for (int ring : rings) elevations.push_back(part.culling.elevations()[ring]);
    TimeClass c{cullingGrid(fan, elevations), {}, {}, {}, 0};
    for (int ring : rings) {
      for (int col = 0; col < cols; ++col) {
        c.directions.push_back(part.directions[ring * cols + col]);
        c.beam.push_back(part.beam[ring * cols + col]);
      }
    }
    c.turn = farthestTurn(c.culling, c.directions);
    for (int col = 0; col < cols; ++col) c.column_time.push_back(time(rings[0], col));
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace

void CasterState::castBeamGridsSweep(const Scene& scene, const PoseSamples& samples,
                                     const BeamList& list, const BeamListGrid& grid,
                                     const CastConfig& config, ScanResult* result, bool at_once) {
  const int bodies = static_cast<int>(scene.bodies().size());
  std::vector<char> cast_any(bodies, 0), column_valid;
  // Every class's columns' poses at once (the samples are prepared once for all of them).
  std::vector<std::vector<TimeClass>> classes;
  std::vector<double> times;
  for (const BeamListGrid::Part& part : grid.parts) {
    classes.push_back(timeClasses(part, list, at_once));
    for (const TimeClass& c : classes.back()) {
      times.insert(times.end(), c.column_time.begin(), c.column_time.end());
    }
  }
  const ColumnPoses poses(scene, indexOf(scene), samples, std::move(times));
  int base = 0;
  for (std::size_t p = 0; p < grid.parts.size(); ++p) {
    std::vector<Eigen::Vector3d> origins;
    bool offset = false;
    for (const Eigen::Vector3d& o : grid.parts[p].column_origin) {
      origins.push_back(o + grid.center);
      offset = offset || !origins.back().isZero(0);
    }
    for (const TimeClass& c : classes[p]) {
      resetResult(c.culling.size(), bodies, true, false, &grid_culling);
      resetResult(c.culling.size(), bodies, true, config.compute_incidence, &grid_own);
      BeamSet::Bundle sub_rays;
      sub_rays.directions.push_back(&c.directions);
      sub_rays.results.push_back(&grid_own);
      sweepColumns(scene, poses, base, c.culling, offset ? &origins : nullptr, c.turn, config,
                   &sub_rays, &grid_culling, &column_valid);
      base += c.culling.azimuthCount();
      result->stats.bodies_skipped =
          std::max(result->stats.bodies_skipped, grid_culling.stats.bodies_skipped);
      for (int b = 0; b < bodies; ++b) cast_any[b] |= cast[b].load(std::memory_order_relaxed);
      const int cols = c.culling.azimuthCount();
      for (std::size_t k = 0; k < c.beam.size(); ++k) {
        const int i = c.beam[k];
        if (!column_valid[k % cols]) {
          result->range[i] = std::numeric_limits<double>::quiet_NaN();
          continue;
        }
        result->range[i] = grid_own.range[k];
        result->body[i] = grid_own.body[k];
        result->triangle[i] = grid_own.triangle[k];
        if (config.compute_incidence && grid_own.body[k] >= 0) {
          result->normal[i] = grid_own.normal[k];
          result->cos_incidence[i] =
              std::min(1.0, std::abs(list.directions[i].dot(grid_own.normal[k])));
        }
      }
    }
  }
  int cast_count = 0;
  for (char c : cast_any) cast_count += c;
  result->stats.bodies_culled = bodies - result->stats.bodies_skipped - cast_count;
}

}  // namespace core
}  // namespace laser_raycast
