// What a Caster keeps between casts (CasterState, behind the facade's one pointer), shared by the
// stages of a cast (caster.cpp) and of a rotating sweep (caster_sweep.cpp).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "beams/beam_cells.h"
#include "beams/beam_list_grid.h"
#include "beams/beam_set.h"
#include "beams/column_motion.h"
#include "caster/column_poses.h"
#include "laser_raycast/core/cast_config.h"
#include "laser_raycast/core/pose_samples.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/scan_result.h"
#include "laser_raycast/core/scene.h"
#include "scene/scene_index.h"
#include "slice/kept_slice.h"
#include "slice/slicer.h"
#include "util/thread_pool.h"

namespace laser_raycast {
namespace core {

// What a result was computed from: if all of it is equal, the result is too.
struct ReuseKey {
  std::uint64_t scene_version = 0;
  CastConfig config;
  double angle_min = 0, angle_increment = 0;
  int azimuths = 0;
  std::vector<double> elevations;
  std::vector<Eigen::Isometry3d> sensor_from_frame;  // meaningful where valid
  std::vector<char> valid;

  bool operator==(const ReuseKey& o) const {
    if (scene_version != o.scene_version || !(config == o.config) || angle_min != o.angle_min ||
        angle_increment != o.angle_increment || azimuths != o.azimuths ||
        elevations != o.elevations || valid != o.valid) {
      return false;
    }
    for (std::size_t f = 0; f < sensor_from_frame.size(); ++f) {
      if (valid[f] && sensor_from_frame[f].matrix() != o.sensor_from_frame[f].matrix()) {
        return false;
      }
    }
    return true;
  }
};

// A scene frame with bodies this scan, with its pose in the sensor frame.
struct PlacedGroup {
  const SceneIndex::Group* group;
  const Eigen::Isometry3d* sensor_from_frame;
  double near;
};

// The inputs of a cast from one pose: every frame relative to the sensor, in double (so that a
// scene far from the origin loses nothing), with everything else the result depends on.
ReuseKey relativeInputs(const Scene& scene, const FramePoses& poses,
                        const Eigen::Isometry3d& world_from_sensor, const ScanPattern& pattern,
                        const CastConfig& config);

// Throws std::invalid_argument if poses does not hold one pose per frame of scene.
void checkFramePoses(const Scene& scene, const FramePoses& poses);
// The threads a cast of `beams` beams uses: config.threads (0: every core), but no more than give
// each thread min_per_thread beams (waking threads costs more than a small scan does), at least 1.
int castThreads(const CastConfig& config, int beams, int min_per_thread);

// A result of `beams` beams before a cast: every range inf (NaN if !sensor_ok), nothing hit; or,
// overwritten, sized only: the caller writes every beam's range, body and triangle (a list cast
// through its grids).
void resetResult(int beams, int bodies, bool sensor_ok, bool with_normals, ScanResult* result,
                 bool overwritten = false);
// Each hit beam's |cos| of the angle between its direction and the hit's normal.
void computeIncidence(const std::vector<Eigen::Vector3d>& directions, ScanResult* result);

// A block of a rotating sweep's columns, cast as one scan from the poses at its reference time with
// each column's beams from the column's own poses (column_motion.h): the frames relative to the
// reference sensor pose, the groups placed there, and each frame's column motions (null for
// frames without bodies or without a pose).
//
// Planar fans: where every column scans the reference's plane in a frame (ColumnMotion::inPlane, as
// a level sensor driving on a floor does), the block is walked through that frame's kept slice.
struct SweepBlock {
  int col_lo = 0, col_hi = -1;
  ReuseKey key;
  std::vector<PlacedGroup> placed;
  std::vector<std::shared_ptr<const ColumnMotion>> motion;  // by frame
  std::vector<const KeptSlice*> slices;                     // by placed group; null: none
};

// How the beams of a sweep's columns leave (CasterState::sweepColumns): from the sensor's origin
// along the pattern's directions at their column's time, unless said otherwise here.
struct SweepBeams {
  // By column, in its sensor frame: where its beams leave from (a calibrated lidar's); null: the
  // sensor's origin.
  const std::vector<Eigen::Vector3d>* origins = nullptr;
  // A bundle's sub-rays are cast instead of the pattern's beams, turned by at most `turn` (rad).
  const BeamSet::Bundle* bundle = nullptr;
  double turn = 0;
  // Rows that fire at times of their own (a Velodyne's lasers): `classes` times a column, grid
  // row r at class class_of_row[r] (empty: every row at class 0).
  int classes = 1;
  std::vector<int> class_of_row;
};

// What a caster keeps between casts: the scene's body trees (rebuilt when the scene changes), the
// walk's per-scan state (kept to reuse its memory), the threads, the kept slices and the inputs of
// the last result.
struct CasterState {
  std::unique_ptr<SceneIndex> index;
  std::vector<PlacedGroup> placed;
  std::vector<std::atomic<char>> cast;  // per body: cast against this scan (for the stats)
  BeamSet beams;
  std::unique_ptr<ThreadPool> pool;     // for CastConfig::threads > 1
  std::unique_ptr<KeptSlices> planes;   // CastConfig::keep_slices
  std::optional<ReuseKey> previous;     // the inputs of the result, if it is complete
  std::vector<ScanResult> bundle;       // Caster::castBundle's results, one per sub-ray pattern
  ScanResult bundle_result;             // its results beam by beam (a SubRayBundle's order)
  // A grid part's lines grouped by when they fire: lines of one class fire at one time in every
  // column (an Ouster's part is one class, each Velodyne laser its own, at its place in the firing
  // sequence). class_of_row by the rows of the part's grid (ascending elevation).
  struct TimeClasses {
    int count = 0;
    std::vector<int> class_of_row;
  };
  // The time classes of a list's grid parts, and each class's times at its part's columns (part
  // by part, class by class: ColumnPoses' columns).
  struct SweepTimes {
    std::vector<TimeClasses> classes;  // by part
    std::vector<double> times;
  };
  // The beam list Caster::castBeams last fitted to grids (its directions, origins, lines and
  // times), and what fitBeamGrid found, or fitBeamCells where it found none: a node casts the same
  // list scan after scan. source: the list, where the caller shares it (Caster::castBeams'
  // shared_ptr overloads): while the same one is passed, it is not compared again.
  struct FittedList {
    std::vector<Eigen::Vector3d> directions, origins;
    std::vector<int> lines;
    std::vector<double> times;
    std::optional<BeamListGrid> grid;
    std::optional<BeamCells> cells;
    std::shared_ptr<const BeamList> source;
    // The owners (BeamSet::Bundle::owner) of the grid's parts' directions and of the cells',
    // made with them: while the list is the same, the BeamSet keeps what it made of them.
    std::vector<std::shared_ptr<const int>> part_owner;
    std::shared_ptr<const int> cells_owner;
    // The grid's sweep times, made when first swept: [0] each beam at its time, [1] all at once.
    std::optional<SweepTimes> sweep_times[2];
  };
  std::optional<FittedList> fitted;
  // A sweep's sensor poses at its columns (ColumnPoses' columns; of a calibrated lidar's, row
  // class 0's), each relative to its block's reference, kept from sweep to sweep: the blocks'
  // ColumnMotion of the frames that stay put are views of them.
  std::vector<ColumnMotion::Pose> sweep_poses;
  ColumnPoses::Storage sweep_columns;  // the ColumnPoses' of a sweep
  std::vector<double> sweep_column_times;  // Caster::castSweep's columns' times
  ScanResult grid_culling, grid_own;  // castBeamGrids' results for one part, by its grid beams

  // The scene's index for this scene version.
  const SceneIndex& indexOf(const Scene& scene);
  // The kept slices (CastConfig::keep_slices), made when first asked for.
  KeptSlices& keptSlices() {
    if (!planes) planes = std::make_unique<KeptSlices>();
    return *planes;
  }
  // The valid frames' groups placed by key, nearest first, into *out; the bodies of frames without
  // a pose are counted in *skipped.
  void placeGroups(const Scene& scene, const ReuseKey& key, const ScanPattern& pattern,
                   std::vector<PlacedGroup>* out, int* skipped);
  void castBodies(const Scene& scene, const ScanPattern& pattern, const CastConfig& config,
                  ScanResult* result);
  // A rotating sweep of pattern's columns into result (reset for pattern), column c's beams from
  // the sensor and frame poses of poses' column base + c (caster/column_poses.h; those of row
  // class k at base + k * columns + c), as sweep_beams says they leave. column_valid: 1 for each
  // column with a sensor pose (at every class's time); the others' beams are NaN in result
  // (caster_sweep.cpp).
  void sweepColumns(const Scene& scene, const ColumnPoses& poses, int base,
                    const ScanPattern& pattern, const SweepBeams& sweep_beams,
                    const CastConfig& config, ScanResult* result,
                    std::vector<char>* column_valid);
  // The blocks of a sweep cast against the beams of result (caster_sweep.cpp).
  void castBlocks(const Scene& scene, const std::vector<SweepBlock>& blocks,
                  const ScanPattern& pattern, const CastConfig& config, ScanResult* result,
                  const BeamSet::Bundle* bundle = nullptr);
  // beams' grids (beam_list_grid.h), fitted or remembered from the last call; null if it lies on
  // none. A list not remembered is checked first (BeamList::validate throws for a bad one).
  // shared: the same list as the caller shares it, or null.
  const BeamListGrid* gridOf(const BeamList& beams,
                             const std::shared_ptr<const BeamList>* shared = nullptr);
  // After gridOf(list) found a grid: its parts' time classes and times (at_once: every beam at
  // time 0, a cast from one pose), made once for the list.
  const SweepTimes& sweepTimesOf(const BeamList& list, bool at_once);
  // After gridOf(beams): beams' cells (beam_cells.h) if it lies on no grid and has some, else null.
  const BeamCells* cellsOf() const { return fitted && fitted->cells ? &*fitted->cells : nullptr; }
  // Casts a beam list in its cells from one pose into result (reset for it, the sensor pose
  // valid): one bundle whose grid beam stands for its cell's beams (caster_beam_grid.cpp).
  void castBeamCells(const Scene& scene, const FramePoses& poses,
                     const Eigen::Isometry3d& world_from_sensor, const BeamList& beams,
                     const BeamCells& cells, const CastConfig& config, ScanResult* result);
  // Casts a beam list that lies on `grid` from one pose into result (reset for it, the sensor
  // pose valid): each part as a bundle of one sub-ray a grid beam, from its column's origin
  // (caster_beam_grid.cpp).
  void castBeamGrids(const Scene& scene, const FramePoses& poses,
                     const Eigen::Isometry3d& world_from_sensor, const BeamList& beams,
                     const BeamListGrid& grid, const CastConfig& config, ScanResult* result);
  // The same for a rotating sweep, each beam from the sensor and frame poses at its own time
  // (caster_beam_grid.cpp): each part's lines that fire together in every column are swept as a
  // bundle of one sub-ray a grid beam, their columns from the poses at those times.
  // at_once: every beam at the samples' first time, whatever its own.
  void castBeamGridsSweep(const Scene& scene, const PoseSamples& samples, const BeamList& beams,
                          const BeamListGrid& grid, const CastConfig& config, ScanResult* result,
                          bool at_once = false);
  // Starts a cast (the beams open as result holds them, no body marked), runs
  // castWithin(rect) over the pattern's beams on config's threads, and counts the bodies culled.
  void castOnThreads(const Scene& scene, const ScanPattern& pattern, const CastConfig& config,
                     ScanResult* result, const std::function<void(const BeamRect&)>& castWithin,
                     const BeamSet::Bundle* bundle = nullptr);
};

}  // namespace core
}  // namespace laser_raycast
