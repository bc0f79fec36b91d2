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

// The poses of a sweep's columns: the sensor's, and each frame with bodies (static frames, at one
// pose in every sample, are checked once and not interpolated). The same poses as
// PoseSamples::sensorAt and frameAt give, to an ulp or two (interpolatePose's slerp from the
// samples' quaternions, converted once here rather than at every column, with the angle between
// two samples found once and the sines of its fractions from their series), with each column's
// bracket of samples found by one pass.
class ColumnPoses {
 public:
  ColumnPoses(const Scene& scene, const SceneIndex& index, const PoseSamples& samples,
              int columns, double time_increment)
      : samples_(samples), dt_(time_increment) {
    const std::size_t n = samples.times.size();
    sample_sensor_ok_.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      sample_sensor_ok_[k] = isValidPose(samples.world_from_sensor[k]);
    }
    findBrackets(columns);
    sample_rotation_.set(samples.world_from_sensor, arcs_used_);
    sensor_.resize(columns);
    sensor_valid_.resize(columns);
    for (int c = 0; c < columns; ++c) {
      const Bracket& b = brackets_[c];
      sensor_valid_[c] = sample_sensor_ok_[b.i] && sample_sensor_ok_[b.j];
      if (sensor_valid_[c]) {
        sensor_[c] = interpolate(samples.world_from_sensor, sample_rotation_, b);
      }
    }
    prepareFrames(scene, index);
  }

  double time(int col) const { return col * dt_; }
  bool sensorValid(int col) const { return sensor_valid_[col]; }
  const Eigen::Isometry3d& sensor(int col) const { return sensor_[col]; }
  const std::vector<int>& framesWithBodies() const { return frames_; }
  bool isStatic(int frame) const { return frame_[frame].is_static; }
  // The frame's pose at the column's time; false if it has none then.
  bool frameAt(int col, int frame, Eigen::Isometry3d* pose) const {
    const Frame& f = frame_[frame];
    if (f.is_static) {
      *pose = samples_.frames.front().pose[frame];
      return true;
    }
    const Bracket& b = brackets_[col];
    if (!(f.ok[b.i] && f.ok[b.j])) return false;
    *pose = interpolate(f.pose, f.rotation, b);
    return true;
  }

 private:
  struct Bracket {
    std::size_t i, j;
    double s;
  };
  // The samples' rotations as quaternions, and the slerp between two of them as Eigen's
  // QuaternionBase::slerp computes it, with the angle between each sample and the next and its
  // sine worked out once rather than at every column, and the sines of its fractions by smallSin.
  // Only the samples some column is interpolated between (arc_used[k]: between k and k + 1) are
  // converted: with a sample at every column's time (cast_scan's sweeps), none is.
  class Rotations {
   public:
    void set(const std::vector<Eigen::Isometry3d>& poses, const std::vector<char>& arc_used) {
      q_.resize(poses.size());
      arc_.resize(poses.size());
      for (std::size_t k = 0; k + 1 < poses.size(); ++k) {
        if (!arc_used[k]) continue;
        q_[k] = Eigen::Quaterniond(poses[k].linear());
        q_[k + 1] = Eigen::Quaterniond(poses[k + 1].linear());
        arc_[k] = arcBetween(q_[k], q_[k + 1]);
      }
    }
    // The bracket's samples must be consecutive, with their arc used.
    Eigen::Quaterniond slerp(const Bracket& b) const {
      const Arc& arc = arc_[b.i];
      const double t = b.s;
      double scale0, scale1;
      if (arc.linear) {
        scale0 = 1 - t;
        scale1 = t;
      } else {
        scale0 = smallSin((1 - t) * arc.theta) / arc.sin_theta;
        scale1 = smallSin(t * arc.theta) / arc.sin_theta;
      }
      if (arc.flip) scale1 = -scale1;
      return Eigen::Quaterniond(scale0 * q_[b.i].coeffs() + scale1 * q_[b.j].coeffs());
    }

   private:
    // sin x: for |x| <= 1/4 (two samples of a sweep a few degrees apart at most) its Taylor series
    // to x^13, whose first term left out is below 2^-61 of |x| there, so that it is within an ulp
    // or two of std::sin; std::sin beyond.
    static double smallSin(double x) {
      if (!(std::abs(x) <= 0.25)) return std::sin(x);
      const double x2 = x * x;
      return x * (1 + x2 * (-1.0 / 6 + x2 * (1.0 / 120 + x2 * (-1.0 / 5040 + x2 * (1.0 / 362880 +
                  x2 * (-1.0 / 39916800 + x2 * (1.0 / 6227020800.0)))))));
    }
    struct Arc {
      bool linear = true, flip = false;
      double theta = 0, sin_theta = 0;
    };
    static Arc arcBetween(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
      const double d = a.dot(b), abs_d = std::abs(d);
      Arc arc;
      arc.flip = d < 0;
      arc.linear = abs_d >= 1 - std::numeric_limits<double>::epsilon();
      if (!arc.linear) {
        arc.theta = std::acos(abs_d);
        arc.sin_theta = std::sin(arc.theta);
      }
      return arc;
    }
    std::vector<Eigen::Quaterniond> q_;
    std::vector<Arc> arc_;
  };
  struct Frame {
    bool is_static = false;
    std::vector<char> ok;                       // by sample
    std::vector<Eigen::Isometry3d> pose;        // by sample
    Rotations rotation;                         // by sample
  };

  // PoseSamples::bracket for each column's time, in one pass (the times ascend).
  void findBrackets(int columns) {
    const std::vector<double>& times = samples_.times;
    brackets_.resize(columns);
    arcs_used_.assign(times.size(), 0);
    std::size_t k = 0;  // the last sample at or before t, once t reaches the first
    for (int c = 0; c < columns; ++c) {
      const double t = time(c);
      while (k + 1 < times.size() && times[k + 1] <= t) ++k;
      Bracket& b = brackets_[c];
      if (t < times.front() || k + 1 == times.size()) {
        b = Bracket{k, k, 0.0};
      } else {
        b = Bracket{k, k + 1, (t - times[k]) / (times[k + 1] - times[k])};
        if (b.s == 0) b.j = k;
      }
      if (b.j != b.i) arcs_used_[b.i] = 1;
    }
  }

  void prepareFrames(const Scene& scene, const SceneIndex& index) {
    frame_.resize(scene.frames().size());
    const std::size_t n = samples_.times.size();
    const FramePoses& first = samples_.frames.front();
    for (const auto& group : index.groups()) {
      const int f = group->frame;
      frames_.push_back(f);
      Frame& frame = frame_[f];
      // A frame that stays put (the whole world of racks and walls, frame after frame) is checked
      // once: the same validity and the same pose bits in every sample.
      bool same = first.valid[f] != 0;
      for (std::size_t k = 1; k < n && same; ++k) {
        const FramePoses& sample = samples_.frames[k];
        same = sample.valid[f] && sample.pose[f].matrix() == first.pose[f].matrix();
      }
      if (same && isValidPose(first.pose[f])) {
        frame.is_static = true;
        continue;
      }
      frame.ok.resize(n);
      frame.pose.resize(n);
      for (std::size_t k = 0; k < n; ++k) {
        const FramePoses& sample = samples_.frames[k];
        frame.ok[k] = sample.valid[f] && isValidPose(sample.pose[f]);
        frame.pose[k] = sample.pose[f];
      }
      frame.rotation.set(frame.pose, arcs_used_);
    }
  }

  // interpolatePose(a, b, s) of the bracket's samples, from their rotations as quaternions; a
  // column exactly at a sample has its pose.
  static Eigen::Isometry3d interpolate(const std::vector<Eigen::Isometry3d>& pose,
                                       const Rotations& rotation, const Bracket& b) {
    if (b.j == b.i) return pose[b.i];
    Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
    const Eigen::Vector3d& ta = pose[b.i].translation();
    out.translation() = ta + b.s * (pose[b.j].translation() - ta);
    out.linear() = rotation.slerp(b).toRotationMatrix();
    return out;
  }

  const PoseSamples& samples_;
  double dt_;
  std::vector<char> sample_sensor_ok_;
  Rotations sample_rotation_;
  std::vector<Bracket> brackets_;
  std::vector<char> arcs_used_;  // by sample: some column lies strictly between it and the next
  std::vector<Eigen::Isometry3d> sensor_;
  std::vector<char> sensor_valid_;
  std::vector<int> frames_;
  std::vector<Frame> frame_;  // by scene frame (only those with bodies are filled)
};

class BlockPlanner {
 public:
  BlockPlanner(const Scene& scene, const ColumnPoses& poses, const ScanPattern& pattern,
               const CastConfig& config)
      : scene_(scene), poses_(poses), pattern_(pattern), config_(config) {
    steepest_ = steepestElevation(pattern);
    limits_ = pattern.planar() ? kLimitsPlanar : kLimits3d;
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
      frames.valid[f] = poses_.frameAt(ref, f, &frames.pose[f]);
    }
    block->key = relativeInputs(scene_, frames, poses_.sensor(ref), pattern_, config_);
    block->motion.assign(scene_.frames().size(), nullptr);
    std::shared_ptr<const ColumnMotion> static_motion;
    for (int f : poses_.framesWithBodies()) {
      if (!block->key.valid[f]) continue;
      if (poses_.isStatic(f)) {
        // A frame that stays put: each column's pose relative to the reference is the sensor's.
        if (!static_motion) static_motion = sensorMotion(lo, hi, ref);
        block->motion[f] = static_motion;
        continue;
      }
      std::vector<Eigen::Isometry3d> ref_from_column(hi - lo + 1);
      for (int c = lo; c <= hi; ++c) {
        Eigen::Isometry3d world_from_frame;
        if (!poses_.frameAt(c, f, &world_from_frame)) return false;  // not valid throughout
        const Eigen::Isometry3d column_from_frame =
            relativePose(poses_.sensor(c), world_from_frame);
        ref_from_column[c - lo] = block->key.sensor_from_frame[f] * column_from_frame.inverse();
      }
      block->motion[f] = std::make_shared<ColumnMotion>(lo, std::move(ref_from_column), steepest_);
      if (!small(*block->motion[f], limits_)) return false;
    }
    // A frame valid at some column but not at the reference: halved until it is one or the other.
    for (int f : poses_.framesWithBodies()) {
      if (block->key.valid[f] || poses_.isStatic(f)) continue;
      Eigen::Isometry3d unused;
      for (int c = lo; c <= hi; ++c) {
        if (poses_.frameAt(c, f, &unused)) return false;
      }
    }
    if (static_motion && !small(*static_motion, limits_)) return false;
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

  std::shared_ptr<const ColumnMotion> sensorMotion(int lo, int hi, int ref) const {
    std::vector<Eigen::Isometry3d> ref_from_column(hi - lo + 1);
    for (int c = lo; c <= hi; ++c) {
      ref_from_column[c - lo] = relativePose(poses_.sensor(ref), poses_.sensor(c));
    }
    return std::make_shared<ColumnMotion>(lo, std::move(ref_from_column), steepest_);
  }

  bool small(const ColumnMotion& m, const BlockLimits& limits) const {
    const double max_turn =
        std::min(limits.turn, limits.turn_per_increment * std::abs(pattern_.angleIncrement()));
    return m.spread().turn <= max_turn && m.spread().shift <= limits.shift;
  }

  const Scene& scene_;
  const ColumnPoses& poses_;
  const ScanPattern& pattern_;
  const CastConfig& config_;
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
  const ColumnPoses poses(scene, state_->indexOf(scene), samples, azimuths, time_increment);
  // Blocks over each run of columns with a sensor pose; the others' beams are NaN.
  BlockPlanner planner(scene, poses, pattern, config);
  std::vector<SweepBlock> blocks;
  for (int c = 0; c < azimuths;) {
    if (!poses.sensorValid(c)) {
      ++c;
      continue;
    }
    int end = c;
    while (end + 1 < azimuths && poses.sensorValid(end + 1)) ++end;
    planner.plan(c, end, &blocks);
    c = end + 1;
  }
  resetResult(pattern.size(), static_cast<int>(scene.bodies().size()), true,
              config.compute_incidence, &result_);
  const bool slices = pattern.planar() && config.planar_fast_path && config.keep_slices;
  if (slices) state_->keptSlices().newScan();
  for (SweepBlock& block : blocks) {
    int skipped = 0, kept = 0;
    state_->placeGroups(scene, block.key, pattern, &block.placed, &skipped);
    result_.stats.bodies_skipped = std::max(result_.stats.bodies_skipped, skipped);
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
      block.slices[g] = state_->keptSlices().find(scene, group, ref);
      kept += block.slices[g] != nullptr;
    }
    result_.stats.kept_slices = std::max(result_.stats.kept_slices, kept);
  }
  state_->castBlocks(scene, blocks, pattern, config, &result_);
  const int rows = pattern.ringCount();
  for (int c = 0; c < azimuths; ++c) {
    if (poses.sensorValid(c)) continue;
    for (int ring = 0; ring < rows; ++ring) {
      result_.range[ring * azimuths + c] = std::numeric_limits<double>::quiet_NaN();
    }
  }
  if (config.compute_incidence) computeIncidence(pattern, &result_);
  return result_;
}

void CasterState::castBlocks(const Scene& scene, const std::vector<SweepBlock>& blocks,
                               const ScanPattern& pattern, const CastConfig& config,
                               ScanResult* result) {
  castOnThreads(scene, pattern, config, result, [&](const BeamRect& within) {
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
  });
}

}  // namespace core
}  // namespace laser_raycast
