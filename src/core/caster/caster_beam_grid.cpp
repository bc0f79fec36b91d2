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
template <class T>
bool sameBits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
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

// A part's result (own, by its grid's beams) into the list's: every beam of the part's range,
// body and triangle (NaN, -1 and -1 where column_valid, if given, is 0), normal and incidence
// where it hits.
void scatter(const BeamListGrid::Part& part, const ScanResult& own, const BeamList& list,
             const CastConfig& config, const std::vector<char>* column_valid,
             ScanResult* result) {
  const std::size_t cols = part.culling.azimuthCount(), rows = part.beam.size() / cols;
  // Beam k is row k / cols's column k % cols. A list holds a column's beams together (a
  // Velodyne's firing sequence, an Ouster's column): taken row by row over the whole scan, each
  // beam would be written a column's beams away from the last, a cache line each; a few columns
  // at a time, every row's, they stay in the nearest cache.
  constexpr std::size_t kTileColumns = 64;
  for (std::size_t lo = 0; lo < cols; lo += kTileColumns) {
    const std::size_t hi = std::min(cols, lo + kTileColumns);
    for (std::size_t row = 0; row < rows; ++row) {
      for (std::size_t col = lo, k = row * cols + lo; col < hi; ++col, ++k) {
        if (column_valid && !(*column_valid)[col]) {
          const int i = part.beam[k];
          result->range[i] = std::numeric_limits<double>::quiet_NaN();
          result->body[i] = -1;
          result->triangle[i] = -1;
          continue;
        }
        scatterBeam(own, k, part.beam[k], list, config, result);
      }
    }
  }
}

// Appends each class's times at the part's columns to *times (class by class); at_once: every
// beam at time 0 (a cast from one pose).
CasterState::TimeClasses timeClasses(const BeamListGrid::Part& part, const BeamList& list,
                                     bool at_once, std::vector<double>* times) {
  const int rings = part.culling.ringCount(), cols = part.culling.azimuthCount();
  auto time = [&](int ring, int col) {
    return at_once ? 0.0 : list.time(part.beam[ring * cols + col]);
  };
  CasterState::TimeClasses out;
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

const BeamListGrid* CasterState::gridOf(const BeamList& beams,
                                        const std::shared_ptr<const BeamList>* shared) {
  if (fitted && shared && fitted->source == *shared) {
    return fitted->grid ? &*fitted->grid : nullptr;
  }
  const std::vector<Eigen::Vector3d>& origins = beams.origins;
  if (!fitted || !sameBits(fitted->directions, beams.directions) ||
      !sameBits(fitted->origins, origins) || fitted->lines != beams.lines ||
      !sameBits(fitted->times, beams.times)) {
    fitted.reset();
    beams.validate();
    fitted = FittedList{beams.directions, origins, beams.lines, beams.times, fitBeamGrid(beams),
                        {}, {}, {}, {}, {}};
    if (!fitted->grid) fitted->cells = fitBeamCells(beams);
    if (fitted->grid) {
      for (std::size_t p = 0; p < fitted->grid->parts.size(); ++p) {
        fitted->part_owner.push_back(std::make_shared<const int>(0));
      }
    }
    if (fitted->cells) fitted->cells_owner = std::make_shared<const int>(0);
  }
  fitted->source = shared ? *shared : nullptr;
  return fitted->grid ? &*fitted->grid : nullptr;
}

const CasterState::SweepTimes& CasterState::sweepTimesOf(const BeamList& list, bool at_once) {
  std::optional<SweepTimes>& kept = fitted->sweep_times[at_once ? 1 : 0];
  if (!kept) {
    kept.emplace();
    for (const BeamListGrid::Part& part : fitted->grid->parts) {
      kept->classes.push_back(timeClasses(part, list, at_once, &kept->times));
    }
  }
  return *kept;
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
  for (std::size_t p = 0; p < grid.parts.size(); ++p) {
    const BeamListGrid::Part& part = grid.parts[p];
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
    sub_rays.directions = &part.directions;
    sub_rays.result = &own;
    sub_rays.from_origin = motion.spread().shift == 0;  // a Velodyne's columns, not an Ouster's
    if (fitted && fitted->grid && &grid == &*fitted->grid) {
      sub_rays.owner = fitted->part_owner[p];  // the same parts scan after scan
    }
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
  sub_rays.directions = &cells.directions;
  sub_rays.result = &own;
  sub_rays.first = &cells.first;
  sub_rays.from_origin = true;
  if (&cells == cellsOf()) sub_rays.owner = fitted->cells_owner;
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
  const SweepTimes& sweep_times = sweepTimesOf(list, at_once);
  const std::vector<TimeClasses>& classes = sweep_times.classes;
  const ColumnPoses poses(scene, indexOf(scene), samples, sweep_times.times, &sweep_columns);
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
    sub_rays.directions = &part.directions;
    sub_rays.result = &grid_own;
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
