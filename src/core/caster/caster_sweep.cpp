// Caster::castSweep: a rotating scan, each azimuth column cast from the poses at its own time.
//
// The columns are cast in blocks: a block is walked once, as a scan from the poses at its middle
// column's time (its reference), with windows widened by how far its columns' poses stray from the
// reference (beams/column_motion.h, the Spread of beams/beam_window.h), and every beam is tested
// exactly as the ray its column's poses give it. So a sweep costs about what a scan from one pose
// does, and each beam's range is the one its column's own cast would give (to the rounding of
// double).
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "caster/caster_state.h"
#include "caster/column_poses.h"
#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/pose.h"
#include "walk/frame_walk.h"
#include "walk/slice_walk.h"

namespace laser_raycast {
namespace core {
namespace {

// How the columns are cut into blocks. These change only the speed, never a range: a wider block
// pays for its columns' spread with wider windows, a narrower one walks the scene's trees more
// often. A block of at most `columns` columns is halved while its poses turn by more than `turn`
// (or `turn_per_increment` times the pattern's azimuth increment, if less: in 3D a turn of a column
// or more widens every triangle's raster by that many beams) or move by more than `shift`, or a
// frame's pose or the sensor's is valid at some of its columns only.
struct BlockLimits {
  int columns;
  double turn;  // rad
  double turn_per_increment;
  double shift;  // m
};
// In 3D the column raster follows each column's origin (column_raster.h), so a block's shift costs
// its triangles nothing and only its nodes' windows widen: on a VLP-16 sweep at 1 m/s along a
// warehouse aisle (20 poses, instructions counted), 128 columns cast in 0.85 of 32's, 64 and 96
// columns within 2% of 128, 192 and 256 columns 10-15% slower.
constexpr BlockLimits kLimits3d{128, 0.02, 0.5, 0.01};
// A planar fan has one beam a column and its walk (a kept slice, 2D) pays little for a wider
// window, so its blocks are longer: on the benchmark's rotating LDS-01 (360 columns at 5 Hz along
// a 1 m/s path; bench --quick on box_room, tb3, forest, million and warehouse), 128 columns,
// 0.1 rad, 4 increments and 6 cm raised its speed against Embree, in the same runs, by 1.1-1.45x
// over the 3D limits of the time (32 columns, 0.02 rad, half an increment, 1 cm); 256 columns
// did no better.
constexpr BlockLimits kLimitsPlanar{128, 0.1, 4, 0.06};
// A calibrated lidar's columns, each from its own origin (an Ouster's, 12 mm off its axis): the
// shift widens every box, and a triangle whose plane passes within twice it of the reference is
// tested with every beam of its leaf's window (a shelf at the sensor's height). An OS1-64 along a
// warehouse aisle (10 poses), from one pose / sweeping at 1 m/s, in ms a scan: 2 mm 13 / 20,
// 3 mm 20 / 24, 5 mm 33 / 33, 1 cm 49 / 45, ray by ray 33 / 60; on the benchmark's scenes 2 mm
// ran at 0.47-1.21 times Embree's speed, 3 mm at 0.52-1.27.
constexpr BlockLimits kLimitsOrigins{128, 0.02, 0.5, 0.002};

class BlockPlanner {
 public:
  // origins: where each column's beams leave from in its sensor frame (null: the sensor's origin);
  // turn: how far the beams may turn from the pattern's directions (a calibrated lidar's, cast as
  // a bundle: ColumnMotion's extra turn).
  // The pattern's column c is poses' column base + c (base + k * columns + c for row class k).
  // sweep_poses: storage for the sensor's poses at poses' columns, as many.
  BlockPlanner(const Scene& scene, const ColumnPoses& poses, int base, const ScanPattern& pattern,
               const CastConfig& config, const SweepBeams& beams,
               std::vector<ColumnMotion::Pose>* sweep_poses)
      : scene_(scene),
        poses_(poses),
        sweep_poses_(sweep_poses),
        base_(base),
        pattern_(pattern),
        config_(config),
        beams_(beams) {
    steepest_ = steepestElevation(pattern);
    limits_ = pattern.planar() ? kLimitsPlanar : beams.origins ? kLimitsOrigins : kLimits3d;
  }

  // Blocks over [lo, hi], every column of which has a sensor pose, in column order.
  void plan(int lo, int hi, std::vector<SweepBlock>* out) {
    for (int start = lo; start <= hi; start += limits_.columns) {
      split(start, std::min(hi, start + limits_.columns - 1), out);
    }
  }

 private:
  // The block [lo, hi], or its halves if it strays too far or its frames' validity changes.
  void split(int lo, int hi, std::vector<SweepBlock>* out) {
    SweepBlock block;
    if (make(lo, hi, &block) || lo == hi) {
      out->push_back(std::move(block));
      return;
    }
    const int mid = lo + (hi - lo) / 2;
    split(lo, mid, out);
    split(mid + 1, hi, out);
  }

  // False if the block should be halved (a single column never is: its reference is itself).
  bool make(int lo, int hi, SweepBlock* block) {
    const int ref = lo + (hi - lo) / 2;
    block->col_lo = lo;
    block->col_hi = hi;
    // The frames with bodies at the reference column, as the columns have them (the others are
    // never walked).
    const std::size_t frame_count = scene_.frames().size();
    FramePoses frames;
    frames.pose.assign(frame_count, Eigen::Isometry3d::Identity());
    frames.valid.assign(frame_count, 0);
    for (int f : poses_.framesWithBodies()) {
      if (!poses_.ridesWithSensor(f)) {
        frames.valid[f] = poses_.frameAt(column(0, ref), f, &frames.pose[f]);
      }
    }
    block->key = relativeInputs(scene_, frames, beamsFrom(0, ref), pattern_, config_);
    // A frame that rides with the sensor: where the sensor carries it, relative to the reference
    // column's origin, with no world pose in between (its own poses, interpolated on their own,
    // would stray from it by the chord of each turn between two samples).
    for (int f : poses_.framesWithBodies()) {
      if (!poses_.ridesWithSensor(f)) continue;
      Eigen::Isometry3d from_ref = poses_.sensorFromRider(f);
      if (beams_.origins) from_ref.translation() -= (*beams_.origins)[ref];
      block->key.valid[f] = 1;
      block->key.sensor_from_frame[f] = from_ref;
    }
    block->motion.assign(scene_.frames().size(), nullptr);
    std::shared_ptr<const ColumnMotion> static_motion, riding_motion;
    for (int f : poses_.framesWithBodies()) {
      if (!block->key.valid[f]) continue;
      if (poses_.isStatic(f)) {
        // A frame that stays put: each column's pose relative to the reference is the sensor's.
        if (!static_motion) static_motion = sensorMotion(lo, hi, ref);
        block->motion[f] = static_motion;
        continue;
      }
      if (poses_.ridesWithSensor(f)) {
        // A frame that rides with the sensor: every beam meets it where the reference's would, and
        // the columns differ only by their origins.
        if (!riding_motion) riding_motion = originsMotion(lo, hi, ref);
        block->motion[f] = riding_motion;
        continue;
      }
      ClassPoses ref_from = classPoses(lo, hi);
      for (int k = 0; k < beams_.classes; ++k) {
        for (int c = lo; c <= hi; ++c) {
          Eigen::Isometry3d world_from_frame;
          if (!poses_.frameAt(column(k, c), f, &world_from_frame)) return false;  // not throughout
          const Eigen::Isometry3d column_from_frame =
              relativePose(beamsFrom(k, c), world_from_frame);
          ref_from[k][c - lo] = block->key.sensor_from_frame[f] * column_from_frame.inverse();
        }
      }
      block->motion[f] = motion(lo, std::move(ref_from));
      if (!small(*block->motion[f], limits_)) return false;
    }
    // A frame valid at some column but not at the reference: halved until it is one or the other.
    for (int f : poses_.framesWithBodies()) {
      if (block->key.valid[f] || poses_.isStatic(f)) continue;
      Eigen::Isometry3d unused;
      for (int k = 0; k < beams_.classes; ++k) {
        for (int c = lo; c <= hi; ++c) {
          if (poses_.frameAt(column(k, c), f, &unused)) return false;
        }
      }
    }
    if (static_motion && !small(*static_motion, limits_)) return false;
    if (riding_motion && !small(*riding_motion, limits_)) return false;
    // A planar fan's longer blocks are for the 2D walk of its kept slices: a block whose columns
    // leave the reference's plane (a tilted or climbing sensor) is walked in 3D, so it keeps within
    // the 3D limits.
    if (pattern_.planar()) {
      bool in_plane = true;
      for (const auto& m : block->motion) in_plane = in_plane && (!m || m->inPlane());
      if (!in_plane) {
        if (hi - lo + 1 > kLimits3d.columns) return false;
        for (const auto& m : block->motion) {
          if (m && !small(*m, kLimits3d)) return false;
        }
      }
    }
    return true;
  }

  // The sensor's poses at columns lo..hi relative to the reference, written into the sweep's
  // poses (their place there is their column's in poses_: blocks hold columns of their own, and a
  // block that is halved is dropped before its halves write theirs), and each row class's delta
  // from them (ColumnMotion::ClassDelta).
  std::shared_ptr<const ColumnMotion> sensorMotion(int lo, int hi, int ref) const {
    const std::vector<Eigen::Vector3d>* origins = beams_.origins;
    auto origin = [origins](int c) { return origins ? &(*origins)[c] : nullptr; };
    ColumnPoses::Relative relative(poses_, column(0, ref), origin(ref));
    // Column c's pose is out[first + c].
    ColumnMotion::Pose* const out = sweep_poses_->data();
    const int first = column(0, 0), classes = beams_.classes;
    ColumnMotion::Reach reach;
    for (int c = lo; c <= hi; ++c) relative.at(first + c, origin(c), &out[first + c], &reach);
    if (classes == 1) {
      return std::make_shared<ColumnMotion>(lo, hi - lo + 1, &out[first + lo], reach, steepest_,
                                            beams_.turn);
    }
    // The columns strictly between two samples whose classes are too, each at the same fraction
    // of the samples' interval after its column (within kSameTime, the rounding of their times),
    // share one set of deltas; any other column (a class beyond the next sample, at a sample, or
    // beams from origins of their own) has its own, from its classes' poses.
    std::vector<ColumnMotion::ClassDelta> deltas;
    std::vector<int> delta_set(hi - lo + 1);
    std::vector<double> sigma(classes, 0.0), shared_sigma(classes, 0.0);
    int shared = -1;  // the set the previous column took from its pair, or -1
    std::size_t shared_pair = 0;
    double tolerance = 0;  // kSameTime as a fraction of the shared pair's interval
    const std::vector<double>& sample_times = poses_.sampleTimes();
    for (int c = lo; c <= hi; ++c) {
      const ColumnPoses::Bracket& b = poses_.bracket(first + c);
      bool between = !origins && b.j != b.i;
      for (int k = 1; k < classes && between; ++k) {
        const ColumnPoses::Bracket& bk = poses_.bracket(column(k, c));
        between = bk.i == b.i && bk.j != bk.i;
        sigma[k] = bk.s - b.s;
      }
      if (between && shared >= 0 && b.i == shared_pair) {
        bool same = true;
        for (int k = 1; k < classes && same; ++k) {
          same = std::abs(sigma[k] - shared_sigma[k]) <= tolerance;
        }
        if (same) {
          delta_set[c - lo] = shared;
          continue;
        }
      }
      const int set = static_cast<int>(deltas.size()) / classes;
      delta_set[c - lo] = set;
      deltas.push_back(ColumnMotion::ClassDelta::identity());
      if (between) {
        for (int k = 1; k < classes; ++k) deltas.push_back(relative.classDelta(b, sigma[k]));
        shared = set;
        shared_pair = b.i;
        shared_sigma = sigma;
        tolerance = kSameTime / (sample_times[b.j] - sample_times[b.i]);
      } else {
        for (int k = 1; k < classes; ++k) {
          ColumnMotion::Pose pose;
          ColumnMotion::Reach unused;
          relative.at(column(k, c), origin(c), &pose, &unused);
          deltas.push_back(ColumnMotion::ClassDelta::between(out[first + c], pose));
        }
        shared = -1;
      }
      for (int k = 1; k < classes; ++k) reach.addDelta(deltas[set * classes + k]);
    }
    return std::make_shared<ColumnMotion>(lo, hi - lo + 1, &out[first + lo], reach, steepest_,
                                          beams_.turn, beams_.class_of_row, std::move(deltas),
                                          std::move(delta_set));
  }
  // How far apart two beams' times may be and still share a delta: a femtosecond, far below any
  // motion's resolution (1e-13 rad at 100 rad/s) and far above the rounding of times within a
  // second (2e-16 s).
  static constexpr double kSameTime = 1e-15;  // s

  // The columns' beams from a sensor that does not move relative to the frame: each from its own
  // origin, relative to the reference's, with the sensor's axes (one class: the rows' times do not
  // matter).
  std::shared_ptr<const ColumnMotion> originsMotion(int lo, int hi, int ref) const {
    std::vector<Eigen::Isometry3d> columns(hi - lo + 1, Eigen::Isometry3d::Identity());
    if (beams_.origins) {
      for (int c = lo; c <= hi; ++c) {
        columns[c - lo].translation() = (*beams_.origins)[c] - (*beams_.origins)[ref];
      }
    }
    return std::make_shared<ColumnMotion>(lo, std::move(columns), steepest_, beams_.turn);
  }

  // Each row class's poses at columns lo..hi relative to the reference (class 0's are the
  // columns'), to be filled (each class's made on its own: a copy of one made would write every
  // pose twice, and a calibrated Velodyne's block has 16 a column).
  using ClassPoses = std::vector<std::vector<Eigen::Isometry3d>>;
  ClassPoses classPoses(int lo, int hi) const {
    ClassPoses out(beams_.classes);
    for (auto& poses : out) poses.resize(hi - lo + 1);
    return out;
  }
  // The block's motion from them.
  std::shared_ptr<const ColumnMotion> motion(int lo, ClassPoses ref_from) const {
    std::vector<Eigen::Isometry3d> columns = std::move(ref_from.front());
    if (beams_.classes == 1) {
      return std::make_shared<ColumnMotion>(lo, std::move(columns), steepest_, beams_.turn);
    }
    ref_from.erase(ref_from.begin());
    return std::make_shared<ColumnMotion>(lo, std::move(columns), steepest_, beams_.turn,
                                          beams_.class_of_row, std::move(ref_from));
  }

  // poses' column of row class k's column c.
  int column(int k, int c) const { return base_ + k * pattern_.azimuthCount() + c; }
  // Where row class k's beams of column c leave from, with the sensor's axes: the sensor's pose
  // at their time, moved to the column's origin.
  Eigen::Isometry3d beamsFrom(int k, int c) const {
    Eigen::Isometry3d pose = poses_.sensor(column(k, c));
    if (beams_.origins) pose.translation() += pose.linear() * (*beams_.origins)[c];
    return pose;
  }

  // The limits bound the block's own motion: a bundle's turn (beams_.turn) is the same whatever
  // the block.
  bool small(const ColumnMotion& m, const BlockLimits& limits) const {
    const double max_turn =
        std::min(limits.turn, limits.turn_per_increment * std::abs(pattern_.angleIncrement()));
    return m.spread().turn <= max_turn + beams_.turn && m.spread().shift <= limits.shift;
  }

  const Scene& scene_;
  const ColumnPoses& poses_;
  std::vector<ColumnMotion::Pose>* sweep_poses_;
  int base_;
  const ScanPattern& pattern_;
  const CastConfig& config_;
  const SweepBeams& beams_;
  double steepest_ = 0;
  BlockLimits limits_;
};

// Whether any beam of the block's columns can meet the group's tree (its box's view from the
// reference pose, widened by the block's spread): a cheap test before any walk.
bool reachesBlock(const PlacedGroup& p, const SweepBlock& block, const ScanPattern& pattern,
                  const CastConfig& config) {
  const ColumnMotion* motion = block.motion[p.group->frame].get();
  const Aabb& bounds = p.group->tree.bounds();
  const Eigen::Matrix3d& rot = p.sensor_from_frame->linear();
  const View view =
      boxView(bounds.center(), bounds.extent() * 0.5, rot, rot.cwiseAbs(),
              p.sensor_from_frame->translation(), pattern.angleMin(), !pattern.planar(),
              motion ? motion->spread() : Spread());
  if (!(view.near <= config.tmax) || (pattern.planar() && !view.crosses)) return false;
  if (!view.azimuth_limited) return true;
  bool reaches = false;
  forEachBeamRange(pattern, view.azimuth_start, view.azimuth_width, [&](int first, int last) {
    reaches = reaches || (first <= block.col_hi && last >= block.col_lo);
  });
  return reaches;
}

}  // namespace

const ScanResult& Caster::castSweep(const Scene& scene, const PoseSamples& samples,
                                    const ScanPattern& pattern, const CastConfig& config,
                                    double time_increment) {
  config.validate();
  samples.validate(scene);
  if (!(std::isfinite(time_increment) && time_increment >= 0)) {
    std::ostringstream msg;
    msg << "time_increment must be finite and >= 0 s, got " << time_increment;
    throw std::invalid_argument(msg.str());
  }
  forget();  // a sweep is never reused, and the last single cast is not this one
  const int azimuths = pattern.azimuthCount();
  std::vector<double>& times = state_->sweep_column_times;
  times.resize(azimuths);
  for (int c = 0; c < azimuths; ++c) times[c] = c * time_increment;
  resetResult(pattern.size(), static_cast<int>(scene.bodies().size()), true,
              config.compute_incidence, &result_);
  const ColumnPoses poses(scene, state_->indexOf(scene), samples, times, &state_->sweep_columns);
  std::vector<char> column_valid;
  state_->sweepColumns(scene, poses, 0, pattern, SweepBeams{}, config, &result_, &column_valid);
  if (config.compute_incidence) computeIncidence(pattern.directions(), &result_);
  return result_;
}

void CasterState::sweepColumns(const Scene& scene, const ColumnPoses& poses, int base,
                               const ScanPattern& pattern, const SweepBeams& sweep_beams,
                               const CastConfig& config, ScanResult* result,
                               std::vector<char>* column_valid) {
  const int azimuths = pattern.azimuthCount();
  // A column has a sensor pose if each of its row classes has.
  auto valid = [&](int c) {
    for (int k = 0; k < sweep_beams.classes; ++k) {
      if (!poses.sensorValid(base + k * azimuths + c)) return false;
    }
    return true;
  };
  // Blocks over each run of columns with a sensor pose; the others' beams are NaN.
  sweep_poses.resize(poses.columns());
  BlockPlanner planner(scene, poses, base, pattern, config, sweep_beams, &sweep_poses);
  std::vector<SweepBlock> blocks;
  column_valid->assign(azimuths, 0);
  for (int c = 0; c < azimuths;) {
    if (!valid(c)) {
      ++c;
      continue;
    }
    int end = c;
    while (end + 1 < azimuths && valid(end + 1)) ++end;
    planner.plan(c, end, &blocks);
    std::fill(column_valid->begin() + c, column_valid->begin() + end + 1, 1);
    c = end + 1;
  }
  const bool slices = pattern.planar() && config.planar_fast_path && config.keep_slices;
  if (slices) keptSlices().newScan();
  for (SweepBlock& block : blocks) {
    int skipped = 0, kept = 0;
    placeGroups(scene, block.key, pattern, &block.placed, &skipped);
    result->stats.bodies_skipped = std::max(result->stats.bodies_skipped, skipped);
    // Only the frames a block can see: a scene of many frames (a warehouse of racks, each its own)
    // would otherwise be walked from every frame's root in every block.
    block.placed.erase(std::remove_if(block.placed.begin(), block.placed.end(),
                                      [&](const PlacedGroup& p) {
                                        return !reachesBlock(p, block, pattern, config);
                                      }),
                       block.placed.end());
    block.slices.assign(block.placed.size(), nullptr);
    for (std::size_t g = 0; g < block.placed.size() && slices; ++g) {
      const SceneIndex::Group& group = *block.placed[g].group;
      const ColumnMotion* motion = block.motion[group.frame].get();
      if (!motion || !motion->inPlane()) continue;
      const ScanPlane ref(block.key.sensor_from_frame[group.frame]);
      block.slices[g] = keptSlices().find(scene, group, ref);
      kept += block.slices[g] != nullptr;
    }
    result->stats.kept_slices = std::max(result->stats.kept_slices, kept);
  }
  castBlocks(scene, blocks, pattern, config, result, sweep_beams.bundle);
  const int rows = pattern.ringCount();
  for (int c = 0; c < azimuths; ++c) {
    if ((*column_valid)[c]) continue;
    for (int ring = 0; ring < rows; ++ring) {
      result->range[ring * azimuths + c] = std::numeric_limits<double>::quiet_NaN();
    }
  }
}

void CasterState::castBlocks(const Scene& scene, const std::vector<SweepBlock>& blocks,
                              const ScanPattern& pattern, const CastConfig& config,
                              ScanResult* result, const BeamSet::Bundle* bundle) {
  castOnThreads(
      scene, pattern, config, result,
      [&](const BeamRect& within) {
    for (const SweepBlock& block : blocks) {
      BeamRect rect = within;
      rect.col_lo = std::max(rect.col_lo, block.col_lo);
      rect.col_hi = std::min(rect.col_hi, block.col_hi);
      if (rect.empty()) continue;
      for (std::size_t g = 0; g < block.placed.size(); ++g) {
        const PlacedGroup& p = block.placed[g];
        const int f = p.group->frame;
        if (block.slices[g]) {
          walkSlice(beams, scene, *block.slices[g], ScanPlane(*p.sensor_from_frame),
                    *p.sensor_from_frame, config, rect, &cast, block.motion[f].get());
        } else {
          walkFrame(beams, scene, *p.group, *p.sensor_from_frame, config, rect, &cast,
                    block.motion[f].get());
        }
      }
    }
      },
      bundle);
}

}  // namespace core
}  // namespace laser_raycast
