#include "laser_raycast/core/caster.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <vector>

#include "beams/beam_window.h"
#include "caster/caster_state.h"
#include "laser_raycast/core/pose.h"
#include "walk/frame_walk.h"
#include "walk/slice_walk.h"

namespace laser_raycast {
namespace core {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A cast is split between threads only if each gets at least this many beams: a 2D fan of a few
// thousand beams is cast in tens of microseconds, about what handing work to another thread costs.
constexpr int kMinBeamsPerThread = 4096;

// Columns per piece of work when a cast is split between threads: whole coarse occlusion tiles, so
// that no tile is written by two threads, and several pieces per thread to even out the load.
constexpr int kPiecesPerThread = 8;
int chunkColumns(int columns, int threads) {
  const int unit = OcclusionTiles::kCoarseWidth;
  const int pieces = threads * kPiecesPerThread;
  const int width = (columns + pieces - 1) / pieces;
  return std::max(unit, (width + unit - 1) / unit * unit);
}

// Rows per piece: whole coarse tile rows, so that with the column pieces there are about
// kPiecesPerThread pieces per thread. Each piece walks the scene from its top, so pieces are no
// smaller than the load needs.
int bandRows(int rows, int column_pieces, int threads) {
  const int unit = OcclusionTiles::kCoarseRings;
  const int bands = std::max(1, kPiecesPerThread * threads / std::max(1, column_pieces));
  const int height = (rows + bands - 1) / bands;
  return std::max(unit, (height + unit - 1) / unit * unit);
}

// The pieces of a scan (rows x columns beams) for `threads` threads, in the order the threads take
// them: columns first, then bands of rings (chunkColumns, bandRows); the last piece per thread is
// cut into single coarse tiles, so that the threads run out of work at about the same time.
std::vector<BeamRect> cutPieces(int rows, int columns, int threads) {
  const int width = chunkColumns(columns, threads);
  const int column_pieces = (columns + width - 1) / width;
  const int height = bandRows(rows, column_pieces, threads);
  const int bands = (rows + height - 1) / height;
  const int whole = column_pieces * bands;
  std::vector<BeamRect> pieces;
  for (int i = 0; i < whole; ++i) {
    const int col_lo = (i / bands) * width, row_lo = (i % bands) * height;
    const BeamRect piece{row_lo, std::min(rows - 1, row_lo + height - 1), col_lo,
                         std::min(columns - 1, col_lo + width - 1)};
    const bool cut = i >= whole - threads;
    const int tile_cols = cut ? OcclusionTiles::kCoarseWidth : width;
    const int tile_rows = cut ? OcclusionTiles::kCoarseRings : height;
    for (int c = piece.col_lo; c <= piece.col_hi; c += tile_cols) {
      for (int r = piece.row_lo; r <= piece.row_hi; r += tile_rows) {
        pieces.push_back(BeamRect{r, std::min(piece.row_hi, r + tile_rows - 1), c,
                                  std::min(piece.col_hi, c + tile_cols - 1)});
      }
    }
  }
  return pieces;
}


}  // namespace

ReuseKey relativeInputs(const Scene& scene, const FramePoses& poses,
                        const Eigen::Isometry3d& world_from_sensor, const ScanPattern& pattern,
                        const CastConfig& config) {
  const bool sensor_ok = isValidPose(world_from_sensor);
  const std::size_t frame_count = scene.frames().size();
  ReuseKey key;
  key.scene_version = scene.version();
  key.config = config;
  key.angle_min = pattern.angleMin();
  key.angle_increment = pattern.angleIncrement();
  key.azimuths = pattern.azimuthCount();
  key.elevations = pattern.elevations();
  key.sensor_from_frame.assign(frame_count, Eigen::Isometry3d::Identity());
  key.valid.assign(frame_count, 0);
  for (std::size_t f = 0; f < frame_count; ++f) {
    // A pose marked valid but not a finite rigid transform (FramePoses filled by hand rather than
    // by resolveFramePoses) would be inverted by transposing its rotation: treat it as unknown.
    key.valid[f] = sensor_ok && poses.valid[f] && isValidPose(poses.pose[f]);
    if (key.valid[f]) key.sensor_from_frame[f] = relativePose(world_from_sensor, poses.pose[f]);
  }
  return key;
}

void resetResult(int beams, int bodies, bool sensor_ok, bool with_normals, ScanResult* result,
                 bool overwritten) {
  if (overwritten) {
    result->range.resize(beams);
    result->body.resize(beams);
    result->triangle.resize(beams);
  } else {
    result->range.assign(beams, sensor_ok ? kInf : std::numeric_limits<double>::quiet_NaN());
    result->body.assign(beams, -1);
    result->triangle.assign(beams, -1);
  }
  if (with_normals) {
    result->normal.assign(beams, Eigen::Vector3d::Zero());
  } else {
    result->normal.clear();
  }
  result->cos_incidence.clear();
  result->stats = CastStats{};
  result->stats.bodies = bodies;
}

void computeIncidence(const std::vector<Eigen::Vector3d>& dirs, ScanResult* result) {
  result->cos_incidence.assign(dirs.size(), 0.0);
  for (std::size_t i = 0; i < dirs.size(); ++i) {
    if (result->body[i] < 0) continue;
    result->cos_incidence[i] = std::min(1.0, std::abs(dirs[i].dot(result->normal[i])));
  }
}

Caster::Caster() : state_(std::make_unique<CasterState>()) {}
Caster::~Caster() = default;
Caster::Caster(Caster&&) noexcept = default;
Caster& Caster::operator=(Caster&&) noexcept = default;

void Caster::forget() { state_->previous.reset(); }

const ScanResult& Caster::cast(const Scene& scene, const FramePoses& poses,
                               const Eigen::Isometry3d& world_from_sensor,
                               const ScanPattern& pattern, const CastConfig& config) {
  config.validate();
  checkFramePoses(scene, poses);
  const bool sensor_ok = isValidPose(world_from_sensor);
  ReuseKey key = relativeInputs(scene, poses, world_from_sensor, pattern, config);
  if (sensor_ok && state_->previous && *state_->previous == key) {
    result_.stats.reused = true;
    return result_;
  }
  state_->previous.reset();
  resetResult(pattern.size(), static_cast<int>(scene.bodies().size()), sensor_ok,
              config.compute_incidence, &result_);
  if (!sensor_ok) return result_;

  state_->placeGroups(scene, key, pattern, &state_->placed, &result_.stats.bodies_skipped);
  // The walks offer each hit to the BeamSet reset here on result_; BeamSet::keepNearestHit
  // (beams/beam_set.h) decides every beam's range, body and triangle.
  state_->castBodies(scene, pattern, config, &result_);
  if (config.compute_incidence) computeIncidence(pattern.directions(), &result_);
  state_->previous = std::move(key);
  return result_;
}

const SceneIndex& CasterState::indexOf(const Scene& scene) {
  if (!index || index->sceneVersion() != scene.version()) {
    index = std::make_unique<SceneIndex>(scene);
  }
  return *index;
}

// Where each frame's body tree is this scan, nearest first; the bodies of frames without a pose
// are skipped.
void CasterState::placeGroups(const Scene& scene, const ReuseKey& key,
                                const ScanPattern& pattern, std::vector<PlacedGroup>* out,
                                int* skipped) {
  std::vector<PlacedGroup>& placed = *out;
  placed.clear();
  for (const auto& group : indexOf(scene).groups()) {
    if (!key.valid[group->frame]) {
      *skipped += static_cast<int>(group->bodies.size());
      continue;
    }
    const Eigen::Isometry3d& pose = key.sensor_from_frame[group->frame];
    const Aabb& bounds = group->tree.bounds();
    const View view =
        boxView(bounds.center(), bounds.extent() * 0.5, pose.linear(), pose.linear().cwiseAbs(),
                pose.translation(), pattern.angleMin(), !pattern.planar());
    placed.push_back(PlacedGroup{group.get(), &pose, view.near});
  }
  std::stable_sort(placed.begin(), placed.end(),
                   [](const PlacedGroup& a, const PlacedGroup& b) { return a.near < b.near; });
}

// Every frame's bodies, nearest frame first, against the open beams of the pattern; with threads,
// each thread takes pieces of the pattern's columns (all rows) in turn.
void CasterState::castBodies(const Scene& scene, const ScanPattern& pattern,
                               const CastConfig& config, ScanResult* result) {
  KeptSlices* kept = nullptr;
  if (pattern.planar() && config.planar_fast_path && config.keep_slices) {
    kept = &keptSlices();
    kept->newScan();
  }
  // Planar fans: each frame's kept slice by this plane, where there is one.
  std::vector<std::pair<ScanPlane, const KeptSlice*>> slices;
  if (pattern.planar() && config.planar_fast_path) {
    for (const PlacedGroup& p : placed) {
      slices.emplace_back(ScanPlane(*p.sensor_from_frame), nullptr);
      if (kept) slices.back().second = kept->find(scene, *p.group, slices.back().first);
      result->stats.kept_slices += slices.back().second != nullptr;
    }
  }
  castOnThreads(scene, pattern, config, result, [&](const BeamRect& within) {
    for (std::size_t g = 0; g < placed.size(); ++g) {
      const PlacedGroup& p = placed[g];
      if (g < slices.size() && slices[g].second) {
        walkSlice(beams, scene, *slices[g].second, slices[g].first, *p.sensor_from_frame, config,
                  within, &cast);
      } else {
        walkFrame(beams, scene, *p.group, *p.sensor_from_frame, config, within, &cast);
      }
    }
  });
}

void CasterState::castOnThreads(const Scene& scene, const ScanPattern& pattern,
                                  const CastConfig& config, ScanResult* result,
                                  const std::function<void(const BeamRect&)>& castWithin,
                                  const BeamSet::Bundle* bundle) {
  beams.reset(pattern, config, result, bundle);
  const std::size_t bodies = scene.bodies().size();
  if (cast.size() != bodies) cast = std::vector<std::atomic<char>>(bodies);
  for (auto& mark : cast) mark.store(0, std::memory_order_relaxed);
  const int threads = castThreads(config, pattern.size(), kMinBeamsPerThread);
  if (threads == 1) {
    castWithin(beams.grid().all());
  } else {
    if (!pool || pool->threads() != threads) pool = std::make_unique<ThreadPool>(threads);
    const std::vector<BeamRect> pieces =
        cutPieces(beams.grid().all().row_hi + 1, pattern.azimuthCount(), threads);
    pool->run(static_cast<int>(pieces.size()), [&](int i) { castWithin(pieces[i]); });
  }
  int cast_count = 0;
  for (const auto& mark : cast) cast_count += mark.load(std::memory_order_relaxed);
  result->stats.bodies_culled = static_cast<int>(bodies) - result->stats.bodies_skipped - cast_count;
}

}  // namespace core
}  // namespace laser_raycast
