// The sensor's and the scene frames' poses at each column of a rotating sweep
// (Caster::castSweep, and a calibrated lidar's columns in Caster::castBeamsSweep).
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "beams/column_motion.h"
#include "laser_raycast/core/pose.h"
#include "laser_raycast/core/pose_samples.h"
#include "laser_raycast/core/scene.h"
#include "scene/scene_index.h"

namespace laser_raycast {
namespace core {

// The poses of a sweep's columns: the sensor's, and each frame with bodies (static frames, at one
// pose in every sample, are checked once and not interpolated). The same poses as
// PoseSamples::sensorAt and frameAt give, to an ulp or two (interpolatePose's slerp from the
// samples' quaternions, converted once here rather than at every column, with the angle between
// two samples found once and the sines of its fractions from their series). Column c is at
// times[c] (s after the first sample's time; in any order: a calibrated lidar's columns count
// down in azimuth as their times go up).
class ColumnPoses {
 public:
  struct Bracket {
    std::size_t i, j;
    double s;
  };
  // What it finds of its columns, in storage the caller keeps from sweep to sweep (a calibrated
  // Velodyne's turn has 28,928 columns: written, not made and zeroed anew).
  struct Storage {
    std::vector<Bracket> brackets;
    std::vector<char> sensor_valid;
  };
  // Column c at times[c]; times, like storage, kept by the caller while this lives.
  ColumnPoses(const Scene& scene, const SceneIndex& index, const PoseSamples& samples,
              const std::vector<double>& times, Storage* storage)
      : samples_(samples),
        times_(times),
        brackets_(storage->brackets),
        sensor_valid_(storage->sensor_valid) {
    const int columns = static_cast<int>(times_.size());
    const std::size_t n = samples.times.size();
    sample_sensor_ok_.resize(n);
    for (std::size_t k = 0; k < n; ++k) {
      sample_sensor_ok_[k] = isValidPose(samples.world_from_sensor[k]);
    }
    findBrackets(columns);
    sample_rotation_.set(samples.world_from_sensor, arcs_used_);
    sensor_valid_.resize(columns);
    for (int c = 0; c < columns; ++c) {
      const Bracket& b = brackets_[c];
      sensor_valid_[c] = sample_sensor_ok_[b.i] && sample_sensor_ok_[b.j];
    }
    prepareFrames(scene, index);
  }

  int columns() const { return static_cast<int>(times_.size()); }
  double time(int col) const { return times_[col]; }
  // The samples the column lies between (i == j: at sample i, or beyond the samples).
  const Bracket& bracket(int col) const { return brackets_[col]; }
  const std::vector<double>& sampleTimes() const { return samples_.times; }
  bool sensorValid(int col) const { return sensor_valid_[col]; }
  // The sensor's pose at the column's time (sensorValid(col)).
  Eigen::Isometry3d sensor(int col) const {
    Eigen::Isometry3d pose;
    interpolate(samples_.world_from_sensor, sample_rotation_, brackets_[col], &pose);
    return pose;
  }

  // The sensor's poses at columns' times relative to one of them, each moved to an origin in its
  // own sensor frame (a calibrated lidar's column's): what relativePose(sensor(ref) moved to
  // ref_origin, sensor(col) moved to origin) gives, to the rounding of double, without the
  // columns' world poses. Between two samples, a column's rotation is the slerp a q_a + b q_b of
  // theirs, so relative to the reference's q_r it is a conj(q_r) q_a + b conj(q_r) q_b, and its
  // translation r^T (t_a - t_r) + s r^T (t_b - t_a): both products are made once for the pair,
  // and a column costs its slerp's weights and one rotation matrix.
  class Relative {
   public:
    // ref_origin: null for none (as at()'s origin).
    Relative(const ColumnPoses& poses, int ref, const Eigen::Vector3d* ref_origin) : poses_(poses) {
      const Bracket& b = poses.brackets_[ref];
      world_from_ref_ = poses.sensor(ref);
      q_ref_conj_ = b.j == b.i ? Eigen::Quaterniond(world_from_ref_.linear()).conjugate()
                               : poses.sample_rotation_.slerp(b).conjugate();
      if (ref_origin) world_from_ref_.translation() += world_from_ref_.linear() * *ref_origin;
      ref_rot_t_ = world_from_ref_.linear().transpose();
    }
    // The column's sensor pose moved to origin (its sensor frame; null: none), relative to the
    // reference, added to *reach; returns its translation (as out has it, without reading back
    // what was just stored).
    // (Inlined into the loops over a block's columns, which call it once a beam of a calibrated
    // Velodyne.)
    LASER_RAYCAST_HOT_INLINE Eigen::Vector3d at(int col, const Eigen::Vector3d* origin,
                                                ColumnMotion::Pose* out,
                                                ColumnMotion::Reach* reach) {
      const Bracket& b = poses_.brackets_[col];
      const std::vector<Eigen::Isometry3d>& pose = poses_.samples_.world_from_sensor;
      if (b.j == b.i) {
        // At a sample: its pose, taken relative as it is.
        *out = relativePose(ref_rot_t_, world_from_ref_.translation(), pose[b.i]);
        if (origin) out->translation() += out->linear() * *origin;
        reach->add(*out);
        return out->translation();
      }
      if (b.i != pair_) enterPair(b);
      double scale0, scale1;
      poses_.sample_rotation_.weights(b, &scale0, &scale1);
      const Eigen::Quaterniond q(scale0 * p_.coeffs() + scale1 * q_.coeffs());
      // The translation from the rotation's values, not read back from *out (their stores could
      // not be forwarded to its loads, and each column waited for them: a third of its time).
      Eigen::Vector3d t = alpha_ + b.s * beta_;
      const Eigen::Matrix3d r = rotationOf(q);
      if (origin) t += r * *origin;
      out->linear() = r;
      out->translation() = t;
      reach->add(q, r, t);
      return t;
    }

    // How a row class that fires `sigma` of the samples' interval after its column turns and moves
    // from the column's pose, for every column strictly between bracket b's samples whose class
    // is too (ColumnMotion::ClassDelta): between two samples the slerp turns at one rate about one
    // axis, q(s + sigma) = q(s) conj(q_a) slerp(q_a, q_b, sigma), and the translation moves
    // sigma (t_b - t_a), here in the reference's frame.
    ColumnMotion::ClassDelta classDelta(const Bracket& b, double sigma) {
      if (b.i != pair_) enterPair(b);
      double scale0, scale1;
      poses_.sample_rotation_.weights(Bracket{b.i, b.j, sigma}, &scale0, &scale1);
      Eigen::Quaterniond r(scale1 * step_.coeffs());
      r.w() += scale0;  // scale0 conj(q_a) q_a, q_a a unit quaternion
      return ColumnMotion::ClassDelta{rotationOf(r), sigma * beta_};
    }

   private:
    // The products of the bracket's two samples that its columns share (p_, q_, step_, alpha_,
    // beta_).
    void enterPair(const Bracket& b) {
      pair_ = b.i;
      const Rotations& rotation = poses_.sample_rotation_;
      const std::vector<Eigen::Isometry3d>& pose = poses_.samples_.world_from_sensor;
      p_ = q_ref_conj_ * rotation.sample(b.i);
      q_ = q_ref_conj_ * rotation.sample(b.j);
      step_ = rotation.sample(b.i).conjugate() * rotation.sample(b.j);
      const Eigen::Vector3d& ta = pose[b.i].translation();
      alpha_ = ref_rot_t_ * (ta - world_from_ref_.translation());
      beta_ = ref_rot_t_ * (pose[b.j].translation() - ta);
    }

    const ColumnPoses& poses_;
    Eigen::Isometry3d world_from_ref_;
    Eigen::Matrix3d ref_rot_t_;
    Eigen::Quaterniond q_ref_conj_;
    std::size_t pair_ = std::numeric_limits<std::size_t>::max();  // the sample pair p_.. are of
    Eigen::Quaterniond p_, q_, step_;
    Eigen::Vector3d alpha_, beta_;
  };
  const std::vector<int>& framesWithBodies() const { return frames_; }
  bool isStatic(int frame) const { return frame_[frame].is_static; }
  // True if the frame rides with the sensor: both have a pose at every sample, and the frame's pose
  // relative to the sensor's is the same at each to within kRideTolerance (a link of the robot
  // that carries the sensor, which TF moves with it). A beam then meets it where it would at any
  // other time of the sweep, its own origin and direction in the sensor frame being the same.
  bool ridesWithSensor(int frame) const { return frame_[frame].rides; }
  // For a frame that rides with the sensor: its pose relative to the sensor's (at the first
  // sample), where every beam meets it.
  const Eigen::Isometry3d& sensorFromRider(int frame) const { return frame_[frame].sensor_from; }
  // m, and in each entry of the rotation: far below a range's resolution, and far above the
  // rounding of the poses' products at the distances of a scene (1e-13 at 1 km).
  static constexpr double kRideTolerance = 1e-9;
  // The frame's pose at the column's time; false if it has none then.
  bool frameAt(int col, int frame, Eigen::Isometry3d* pose) const {
    const Frame& f = frame_[frame];
    if (f.is_static) {
      *pose = samples_.frames.front().pose[frame];
      return true;
    }
    const Bracket& b = brackets_[col];
    if (!(f.ok[b.i] && f.ok[b.j])) return false;
    interpolate(f.pose, f.rotation, b, pose);
    return true;
  }

 private:
  // The samples' rotations as quaternions, and the slerp between two of them as Eigen's
  // QuaternionBase::slerp computes it, with the angle between each sample and the next and the
  // reciprocal of its sine worked out once rather than at every column (a product an ulp from
  // Eigen's quotient), and the sines of its fractions by smallSin.
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
      double scale0, scale1;
      weights(b, &scale0, &scale1);
      return Eigen::Quaterniond(scale0 * q_[b.i].coeffs() + scale1 * q_[b.j].coeffs());
    }
    // The slerp's weights of the bracket's two samples' quaternions.
    void weights(const Bracket& b, double* scale0, double* scale1) const {
      const Arc& arc = arc_[b.i];
      const double t = b.s;
      if (arc.linear) {
        *scale0 = 1 - t;
        *scale1 = t;
      } else if (arc.terms == 3) {
        *scale0 = sin3((1 - t) * arc.theta) * arc.inv_sin_theta;
        *scale1 = sin3(t * arc.theta) * arc.inv_sin_theta;
      } else if (arc.terms == 4) {
        *scale0 = sin4((1 - t) * arc.theta) * arc.inv_sin_theta;
        *scale1 = sin4(t * arc.theta) * arc.inv_sin_theta;
      } else {
        *scale0 = smallSin((1 - t) * arc.theta) * arc.inv_sin_theta;
        *scale1 = smallSin(t * arc.theta) * arc.inv_sin_theta;
      }
      if (arc.flip) *scale1 = -*scale1;
    }
    // Sample k's quaternion (k or k - 1 must have its arc used).
    const Eigen::Quaterniond& sample(std::size_t k) const { return q_[k]; }

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
    // The same series to x^5 and to x^7, for the arcs short enough that the first term left out is
    // below 2^-64 of |x| (kSin3Arc: x^7 / 5040 <= 2^-54 / 5040 |x|; kSin4Arc: x^9 / 362880 <=
    // 2^-48 / 362880 |x|): two TF samples 10 ms apart differ by a few 1e-4 rad as a robot sways,
    // and every beam of a sweep takes two of these sines.
    static constexpr double kSin3Arc = 1.0 / 512, kSin4Arc = 1.0 / 64;
    static double sin3(double x) {
      const double x2 = x * x;
      return x * (1 + x2 * (-1.0 / 6 + x2 * (1.0 / 120)));
    }
    static double sin4(double x) {
      const double x2 = x * x;
      return x * (1 + x2 * (-1.0 / 6 + x2 * (1.0 / 120 + x2 * (-1.0 / 5040))));
    }
    struct Arc {
      bool linear = true, flip = false;
      int terms = 7;  // of the sine's series its weights take (sin3, sin4 or smallSin's)
      double theta = 0, inv_sin_theta = 0;  // 1 / sin(theta): a product a column, not a quotient
    };
    static Arc arcBetween(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
      const double d = a.dot(b), abs_d = std::abs(d);
      Arc arc;
      arc.flip = d < 0;
      arc.linear = abs_d >= 1 - std::numeric_limits<double>::epsilon();
      if (!arc.linear) {
        arc.theta = std::acos(abs_d);
        arc.inv_sin_theta = 1 / std::sin(arc.theta);
        // Both fractions of the arc are within it.
        arc.terms = arc.theta <= kSin3Arc ? 3 : arc.theta <= kSin4Arc ? 4 : 7;
      }
      return arc;
    }
    std::vector<Eigen::Quaterniond> q_;
    std::vector<Arc> arc_;
  };
  struct Frame {
    bool is_static = false;
    bool rides = false;                   // ridesWithSensor
    Eigen::Isometry3d sensor_from;        // sensorFromRider
    std::vector<char> ok;                 // by sample
    std::vector<Eigen::Isometry3d> pose;  // by sample
    Rotations rotation;                   // by sample
  };

  // PoseSamples::bracket for each column's time: the last sample at or before it (the first if
  // none is) and the next.
  void findBrackets(int columns) {
    const std::vector<double>& times = samples_.times;
    brackets_.resize(columns);
    arcs_used_.assign(times.size(), 0);
    std::size_t above = 0;
    for (int c = 0; c < columns; ++c) {
      const double t = time(c);
      // The first sample after t: the previous column's, or its next, where the columns' times go
      // up a little at a time (a sweep's); else searched for.
      if (!(above <= times.size() && (above == 0 || times[above - 1] <= t) &&
            (above == times.size() || t < times[above]))) {
        if (above < times.size() && times[above] <= t &&
            (above + 1 == times.size() || t < times[above + 1])) {
          ++above;
        } else {
          above = std::upper_bound(times.begin(), times.end(), t) - times.begin();
        }
      }
      const std::size_t k = above == 0 ? 0 : above - 1;
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
      frame.rides = ridesWith(&frame);
    }
  }

  // Sets frame->sensor_from to the frame's pose relative to the sensor's at the first sample, and
  // returns whether it is that at every sample.
  bool ridesWith(Frame* frame) const {
    for (std::size_t k = 0; k < samples_.times.size(); ++k) {
      if (!(frame->ok[k] && sample_sensor_ok_[k])) return false;
      const Eigen::Isometry3d relative =
          relativePose(samples_.world_from_sensor[k], frame->pose[k]);
      if (k == 0) {
        frame->sensor_from = relative;
      } else if (!((relative.matrix() - frame->sensor_from.matrix()).cwiseAbs().maxCoeff() <=
                   kRideTolerance)) {
        return false;
      }
    }
    return true;
  }

  // interpolatePose(a, b, s) of the bracket's samples, from their rotations as quaternions, into
  // *out; a column exactly at a sample has its pose.
  static void interpolate(const std::vector<Eigen::Isometry3d>& pose, const Rotations& rotation,
                          const Bracket& b, Eigen::Isometry3d* out) {
    if (b.j == b.i) {
      *out = pose[b.i];
      return;
    }
    const Eigen::Vector3d& ta = pose[b.i].translation();
    const Eigen::Vector3d t = ta + b.s * (pose[b.j].translation() - ta);
    out->linear() = rotationOf(rotation.slerp(b));
    out->translation() = t;
    out->makeAffine();
  }

  // QuaternionBase::toRotationMatrix's expression.
  static Eigen::Matrix3d rotationOf(const Eigen::Quaterniond& q) {
    const double tx = 2 * q.x(), ty = 2 * q.y(), tz = 2 * q.z();
    const double twx = tx * q.w(), twy = ty * q.w(), twz = tz * q.w();
    const double txx = tx * q.x(), txy = ty * q.x(), txz = tz * q.x();
    const double tyy = ty * q.y(), tyz = tz * q.y(), tzz = tz * q.z();
    Eigen::Matrix3d m;
    m << 1 - (tyy + tzz), txy - twz, txz + twy,  //
        txy + twz, 1 - (txx + tzz), tyz - twx,   //
        txz - twy, tyz + twx, 1 - (txx + tyy);
    return m;
  }

  const PoseSamples& samples_;
  const std::vector<double>& times_;  // by column
  std::vector<char> sample_sensor_ok_;
  Rotations sample_rotation_;
  std::vector<Bracket>& brackets_;
  std::vector<char> arcs_used_;  // by sample: some column lies strictly between it and the next
  std::vector<char>& sensor_valid_;
  std::vector<int> frames_;
  std::vector<Frame> frame_;  // by scene frame (only those with bodies are filled)
};

}  // namespace core
}  // namespace laser_raycast
