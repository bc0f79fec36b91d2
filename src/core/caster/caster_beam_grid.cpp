// Caster::castBeams for a beam list that lies on grids (beams/beam_list_grid.h): a calibrated
// spinning lidar's beams, each cast exactly as its own ray, with the grid's walks finding what
// each may hit; and for a list off any grid from one origin, in the cells of an angular grid
// (beams/beam_cells.h).
//
// Each part of the grid is cast as a bundle (BeamSet::Bundle) whose one sub-ray at a grid beam is
// the list's beam there, with the windows widened by the part's turn. Columns that all leave from
// one origin (a Velodyne's) are cast from a reference pose there; columns from origins of their
// own (an Ouster's) and rotating sweeps go through the blocks of a rotating sweep
// (CasterState::sweepColumns), each column from its own origin and its beams' poses. The walks
// test the sub-ray wherever they would test its grid beam, so a beam's range is what its own ray
// gives; only the work of finding its triangles is shared.
#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

#include "beams/beam_grid.h"
#include "caster/caster_state.h"
#include "caster/column_poses.h"
#include "walk/frame_walk.h"

namespace laser_raycast {
namespace core {

namespace {

// Whether two lists of vectors hold the same bits (so the same values; a list the node casts every
// scan is compared with the fitted one as memory, not value by value).
bool sameBits(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Eigen::Vector3d)) == 0);
}

// The bodies cast against in any of a list's walks, for its CastStats::bodies_culled.
class CastBodies {
 public:
  explicit CastBodies(int bodies) : any_(bodies, 0) {}
  void add(const std::vector<std::atomic<char>>& cast) {
    for (std::size_t b = 0; b < any_.size(); ++b) {
      any_[b] |= cast[b].load(std::memory_order_relaxed);
    }
  }
  int count() const { return static_cast<int>(std::count(any_.begin(), any_.end(), 1)); }

 private:
  std::vector<char> any_;
};

// Sub-ray k's result (own's k-th) as the list's beam i: its range, body, triangle and, with
// compute_incidence, normal and incidence.
LASER_RAYCAST_HOT_INLINE void scatterBeam(const ScanResult& own, std::size_t k, int i,
                                          const BeamList& list, const CastConfig& config,
                                          ScanResult* result) {
  result->range[i] = own.range[k];
  result->body[i] = own.body[k];
  result->triangle[i] = own.triangle[k];
  if (config.compute_incidence && own.body[k] >= 0) {
    result->normal[i] = own.normal[k];
    result->cos_incidence[i] = std::min(1.0, std::abs(list.directions[i].dot(own.normal[k])));
  }
}

// A part's result (own, by its grid's beams) into the list's; NaN where column_valid (if given)
// is 0.
void scatter(const BeamListGrid::Part& part, const ScanResult& own, const BeamList& list,
             const CastConfig& config, const std::vector<char>* column_valid,
             ScanResult* result) {
  const std::size_t cols = part.culling.azimuthCount();
  // Beam k is at column k % cols, counted along (a division a beam costs a 28,928-beam sweep a
  // tenth of a millisecond).
  for (std::size_t k = 0, col = 0; k < part.beam.size(); ++k, col = col + 1 == cols ? 0 : col + 1) {
    if (column_valid && !(*column_valid)[col]) {
      result->range[part.beam[k]] = std::numeric_limits<double>::quiet_NaN();
      continue;
    }
    scatterBeam(own, k, part.beam[k], list, config, result);
  }
}

// A part's lines grouped by when they fire: lines of one class fire at one time in every column
// (an Ouster's part is one class, each Velodyne laser its own, at its place in the firing
// sequence). class_of_row by the rows of the part's grid (ascending elevation).
struct TimeClasses {
  int count = 0;
  std::vector<int> class_of_row;
};

// Appends each class's times at the part's columns to *times (class by class); at_once: every
// beam at time 0 (a cast from one pose).
TimeClasses timeClasses(const BeamListGrid::Part& part, const BeamList& list, bool at_once,
                        std::vector<double>* times) {
  const int rings = part.culling.ringCount(), cols = part.culling.azimuthCount();
  auto time = [&](int ring, int col) {
    return at_once ? 0.0 : list.time(part.beam[ring * cols + col]);
  };
  TimeClasses out;
  std::vector<int> first_ring, class_of_ring(rings);
  for (int ring = 0; ring < rings; ++ring) {
    int k = 0;
    for (; k < out.count; ++k) {
      bool same = true;
      for (int col = 0; col < cols && same; ++col) {
        same = time(ring, col) == time(first_ring[k], col);
      }
      if (same) break;
    }
    if (k == out.count) {
      ++out.count;
      first_ring.push_back(ring);
      for (int col = 0; col < cols; ++col) times->push_back(time(ring, col));
    }
    class_of_ring[ring] = k;
  }
  std::vector<int> order;
  ringsByElevation(part.culling, &order);
  for (int ring : order) out.class_of_row.push_back(class_of_ring[ring]);
  return out;
}

}  // namespace

const BeamListGrid* CasterState::gridOf(const BeamList& beams) {
  const std::vector<Eigen::Vector3d>& origins = beams.origins;
  if (!fitted || !sameBits(fitted->directions, beams.directions) ||
      !sameBits(fitted->origins, origins) || fitted->lines != beams.lines) {
    fitted.reset();
    beams.validate();
    fitted = FittedList{beams.directions, origins, beams.lines, fitBeamGrid(beams), {}};
    if (!fitted->grid) fitted->cells = fitBeamCells(beams);
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
  CastBodies cast_any(bodies);
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
    cast_any.add(cast);
    scatter(part, own, list, config, nullptr, result);
  }
  result->stats.bodies_culled = bodies - result->stats.bodies_skipped - cast_any.count();
}

void CasterState::castBeamCells(const Scene& scene, const FramePoses& poses,
                                const Eigen::Isometry3d& world_from_sensor, const BeamList& list,
                                const BeamCells& cells, const CastConfig& config,
                                ScanResult* result) {
  const int bodies = static_cast<int>(scene.bodies().size());
  const Eigen::Isometry3d world_from_ref = world_from_sensor * Eigen::Translation3d(cells.origin);
  const ReuseKey key = relativeInputs(scene, poses, world_from_ref, cells.culling, config);
  result->stats.bodies_skipped = 0;
  placeGroups(scene, key, cells.culling, &placed, &result->stats.bodies_skipped);
  const ColumnMotion motion(
      0, std::vector<Eigen::Isometry3d>(cells.culling.azimuthCount(), Eigen::Isometry3d::Identity()),
      steepestElevation(cells.culling), cells.turn);
  ScanResult& culling = grid_culling;
  ScanResult& own = grid_own;
  resetResult(cells.culling.size(), bodies, true, false, &culling);
  resetResult(list.size(), bodies, true, config.compute_incidence, &own);
  BeamSet::Bundle sub_rays;
  sub_rays.directions.push_back(&cells.directions);
  sub_rays.results.push_back(&own);
  sub_rays.first = &cells.first;
  castOnThreads(
      scene, cells.culling, config, &culling,
      [&](const BeamRect& within) {
        for (const PlacedGroup& p : placed) {
          walkFrame(beams, scene, *p.group, *p.sensor_from_frame, config, within, &cast, &motion);
        }
      },
      &sub_rays);
  for (std::size_t s = 0; s < cells.beam.size(); ++s) {
    scatterBeam(own, s, cells.beam[s], list, config, result);
  }
  CastBodies cast_any(bodies);
  cast_any.add(cast);
  result->stats.bodies_culled = bodies - result->stats.bodies_skipped - cast_any.count();
}

void CasterState::castBeamGridsSweep(const Scene& scene, const PoseSamples& samples,
                                     const BeamList& list, const BeamListGrid& grid,
                                     const CastConfig& config, ScanResult* result, bool at_once) {
  const int bodies = static_cast<int>(scene.bodies().size());
  CastBodies cast_any(bodies);
  std::vector<char> column_valid;
  // Every part's columns' poses at once (the samples are prepared once for all of them).
  std::vector<TimeClasses> classes;
  std::vector<double>& times = sweep_columns.times;
  times.clear();
  for (const BeamListGrid::Part& part : grid.parts) {
    classes.push_back(timeClasses(part, list, at_once, &times));
  }
  const ColumnPoses poses(scene, indexOf(scene), samples, &sweep_columns);
  int base = 0;
  for (std::size_t p = 0; p < grid.parts.size(); ++p) {
    const BeamListGrid::Part& part = grid.parts[p];
    std::vector<Eigen::Vector3d> origins;
    bool offset = false;
    for (const Eigen::Vector3d& o : part.column_origin) {
      origins.push_back(o + grid.center);
      offset = offset || !origins.back().isZero(0);
    }
    resetResult(part.culling.size(), bodies, true, false, &grid_culling);
    resetResult(part.culling.size(), bodies, true, config.compute_incidence, &grid_own);
    BeamSet::Bundle sub_rays;
    sub_rays.directions.push_back(&part.directions);
    sub_rays.results.push_back(&grid_own);
    SweepBeams beams_of_part;
    beams_of_part.origins = offset ? &origins : nullptr;
    beams_of_part.bundle = &sub_rays;
    beams_of_part.turn = part.turn;
    beams_of_part.classes = classes[p].count;
    beams_of_part.class_of_row = classes[p].class_of_row;
    sweepColumns(scene, poses, base, part.culling, beams_of_part, config, &grid_culling,
                 &column_valid);
    base += classes[p].count * part.culling.azimuthCount();
    result->stats.bodies_skipped =
        std::max(result->stats.bodies_skipped, grid_culling.stats.bodies_skipped);
    cast_any.add(cast);
    scatter(part, grid_own, list, config, &column_valid, result);
  }
  result->stats.bodies_culled = bodies - result->stats.bodies_skipped - cast_any.count();
}

}  // namespace core
}  // namespace laser_raycast
