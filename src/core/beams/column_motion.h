// The beams of a block of a rotating sweep's columns, each from its own column's pose, written in
// the sensor frame of one reference pose that the block is culled from (Caster::castSweep). For one
// scene frame: column c's beams start at refFromColumn(c) * 0 and point along
// refFromColumn(c).linear() * d, d the pattern's direction, which is the ray the sensor cast at
// column c's time against that frame where it was then. The walks cull the block as one scan from
// the reference pose with windows widened by spread() (beam_window.h), and test each beam exactly
// as this ray.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "beams/beam_window.h"
#include "laser_raycast/core/ray.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/triangle.h"
#include "util/turn.h"

namespace laser_raycast {
namespace core {

// The largest angle of pattern's directions from the horizontal (rad): ColumnMotion's steepest.
inline double steepestElevation(const ScanPattern& pattern) {
  double steepest = 0;
  for (double e : pattern.elevations()) steepest = std::max(steepest, std::abs(e));
  return steepest;
}

class ColumnMotion {
 public:
  // A column's pose relative to the reference: rotation and translation in 12 doubles (an
  // Isometry3d's 16 hold a constant last row), written once and read by the walks, whose memory
  // traffic is their cost.
  using Pose = Eigen::Transform<double, 3, Eigen::AffineCompact>;
  // Where a row class's beams leave from relative to their column's pose (a Velodyne's laser fires
  // a few microseconds after its sequence's first): the beam of class k at column c leaves from
  // refFromColumn(c).translation() + offset along refFromColumn(c).linear() * rot * d. Between two
  // pose samples the sensor turns at one rate about one axis (a slerp) and moves at one velocity,
  // so every column between the same two samples whose class fires the same time after it shares
  // one such delta: a sweep stores the columns' poses and a few deltas, not a pose for every
  // class at every column (a calibrated Velodyne's 28,928 a turn, whose making and memory traffic
  // were a tenth of a sweep's time).
  struct ClassDelta {
    Eigen::Matrix3d rot;     // in the column's sensor frame
    Eigen::Vector3d offset;  // in the reference sensor frame
    // Class 0's: the column's own pose.
    static ClassDelta identity() {
      return ClassDelta{Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero()};
    }
    // A class's pose (relative to the reference) taken relative to its column's.
    template <class ColumnPose, class ClassPose>
    static ClassDelta between(const ColumnPose& column, const ClassPose& pose) {
      return ClassDelta{column.linear().transpose() * pose.linear(),
                        pose.translation() - column.translation()};
    }
  };
  // A block of columns [col_lo, col_lo + ref_from_column.size()); steepest: the largest angle of a
  // pattern direction from the horizontal (rad). extra_turn (rad): how far more the beams' rays may
  // turn from their pattern directions (a bundle's sub-rays, Caster::castBundle), added to the
  // spread's turn.
  ColumnMotion(int col_lo, std::vector<Eigen::Isometry3d> ref_from_column, double steepest,
               double extra_turn = 0);
  // Rows that leave at times of their own (a Velodyne's lasers, each at its place in the firing
  // sequence): the beam at (row, col) leaves from the pose of class class_of_row[row] (grid rows)
  // at col, class 0 being ref_from_column, class k >= 1 ref_from_class[k - 1][col - col_lo] (kept
  // as each column's ClassDelta). The columns' poses above are class 0's; deviation() bounds how
  // far any beam's origin lies from its column's, and the spread holds every class's poses.
  ColumnMotion(int col_lo, std::vector<Eigen::Isometry3d> ref_from_column, double steepest,
               double extra_turn, std::vector<int> class_of_row,
               const std::vector<std::vector<Eigen::Isometry3d>>& ref_from_class);
  // How far a block's poses reach from the reference, gathered pose by pose (as they are written,
  // with their values at hand, rather than read back).
  struct Reach {
    double shift2 = 0, frobenius2 = 0, z_move2 = 0;
    bool translations_only = true, in_plane = true;
    // Of the poses added by quaternion: the largest |v|^2 and |q|^2 (v its vector part), and the
    // largest |q.x|, |q.y| and |t.z| (0 exactly where every one turns about z alone and stays in
    // the xy plane). Only maxima, each pose's own test deferred to turnFrobenius2() and
    // translationsOnly(): a sweep's block adds 128 poses.
    double v2 = 0, q2 = 0, off_plane = 0;
    // A pose, from its matrix.
    void add(const Pose& m) {
      const Eigen::Matrix3d& r = m.linear();
      shift2 = std::max(shift2, m.translation().squaredNorm());
      frobenius2 = std::max(frobenius2, (r - Eigen::Matrix3d::Identity()).squaredNorm());
      z_move2 = std::max(z_move2, (r.col(2) - Eigen::Vector3d::UnitZ()).squaredNorm());
      translations_only = translations_only && r == Eigen::Matrix3d::Identity();
      in_plane = in_plane && r(0, 2) == 0 && r(1, 2) == 0 && r(2, 0) == 0 && r(2, 1) == 0 &&
                 r(2, 2) == 1 && m.translation().z() == 0;
    }
    // The same for a pose of rotation r and translation t, r being QuaternionBase's
    // toRotationMatrix of q, taken from q where that costs less: r - I is 2 w [v]x + 2 [v]x^2,
    // whose |.|_F^2 is 8 |v|^2 |q|^2, at most 8 max |v|^2 max |q|^2 over the poses (raised by a
    // relative 2e-9 and 1e-21 to cover the rounding of r's entries, which moves |r - I|_F by a few
    // 1e-16: a turn of 1e-11 rad at most); r is exactly I where v = 0, and turns about z alone
    // exactly where v has no x and y (where it has, r is taken as turning, which only costs
    // speed).
    void add(const Eigen::Quaterniond& q, const Eigen::Matrix3d& r, const Eigen::Vector3d& t) {
      const double pose_v2 = q.vec().squaredNorm();
      shift2 = std::max(shift2, t.squaredNorm());
      v2 = std::max(v2, pose_v2);
      q2 = std::max(q2, q.w() * q.w() + pose_v2);
      z_move2 =
          std::max(z_move2, r(0, 2) * r(0, 2) + r(1, 2) * r(1, 2) + (r(2, 2) - 1) * (r(2, 2) - 1));
      off_plane = std::max(off_plane,
                           std::max(std::max(std::abs(q.x()), std::abs(q.y())), std::abs(t.z())));
    }
    // |r - I|_F^2 over every pose added (q2 > 0: some by quaternion, whose |q| is near 1).
    double turnFrobenius2() const {
      return q2 > 0 ? std::max(frobenius2, 8 * v2 * q2 * (1 + 2e-9) + 1e-21) : frobenius2;
    }
    bool translationsOnly() const { return translations_only && v2 == 0; }
    bool inPlane() const { return in_plane && off_plane == 0; }
    // Of the row classes' deltas from their columns' poses (ClassDelta): the largest |rot - I|_F,
    // |rot e_z - e_z| and |offset|. A class's pose is its column's composed with its delta, so it
    // turns, tilts and moves from the reference by at most the sums of the two (measure()).
    double delta_turn = 0, delta_tilt = 0, delta_offset = 0;
    bool deltas_identity = true, deltas_in_plane = true;
    void addDelta(const ClassDelta& d) {
      const Eigen::Matrix3d& r = d.rot;
      delta_turn = std::max(delta_turn, (r - Eigen::Matrix3d::Identity()).norm());
      delta_tilt = std::max(delta_tilt, (r.col(2) - Eigen::Vector3d::UnitZ()).norm());
      delta_offset = std::max(delta_offset, d.offset.norm());
      deltas_identity = deltas_identity && r == Eigen::Matrix3d::Identity();
      deltas_in_plane = deltas_in_plane && r(0, 2) == 0 && r(1, 2) == 0 && r(2, 0) == 0 &&
                        r(2, 1) == 0 && r(2, 2) == 1 && d.offset.z() == 0;
    }
  };
  // The same over poses the caller keeps while this lives (a sweep's, written in place block by
  // block: CasterState::sweep_poses): column c's pose is poses[c - col_lo], for `columns` columns;
  // with row classes (class_of_row not empty), class k's beams at column c leave from it moved by
  // deltas[delta_set[c - col_lo] * classes + k] (class 0's the identity); reach: every column's
  // pose and every delta added.
  ColumnMotion(int col_lo, int columns, const Pose* poses, const Reach& reach, double steepest,
               double extra_turn, std::vector<int> class_of_row = {},
               std::vector<ClassDelta> deltas = {}, std::vector<int> delta_set = {});
  // Its poses may be its own: not copied (a move keeps them where they are).
  ColumnMotion(const ColumnMotion&) = delete;
  ColumnMotion& operator=(const ColumnMotion&) = delete;
  ColumnMotion(ColumnMotion&&) = default;

  int colLo() const { return col_lo_; }
  int colHi() const { return col_lo_ + columns_ - 1; }
  const Pose& refFromColumn(int col) const { return poses_[col - col_lo_]; }
  const Spread& spread() const { return spread_; }
  // sin(spread().turn), at most 1: how far a turned beam's unit direction may leave a plane through
  // the sensor that the unturned one lies on (the column raster's widening, per triangle).
  double sinTurn() const { return sin_turn_; }
  // True if every column's pose differs from the reference by a turn about the sensor's z axis and
  // a move in its xy plane, exactly (as a level sensor driving on a floor gives): every column scans
  // the reference's plane.
  bool inPlane() const { return in_plane_; }
  // True if no column's pose turns from the reference's (a calibrated lidar's columns, each from
  // its own origin: Caster::castBeams).
  bool translationsOnly() const { return translations_only_; }

  // The most any beam's origin lies from its column's (0 without row classes).
  double deviation() const { return deviation_; }

  // Beam d of column col as a ray in the reference sensor frame.
  Ray ray(int col, const Eigen::Vector3d& d, double tmin) const {
    return rayFrom(refFromColumn(col), d, tmin);
  }
  // Beam d at (row, col), from its row's class's pose.
  LASER_RAYCAST_HOT_INLINE Ray ray(int row, int col, const Eigen::Vector3d& d,
                                   double tmin) const {
    Ray r;
    beam(row, col, d, &r.origin, &r.dir);
    r.tmin = tmin;
    return r;
  }
  // The same as where it leaves from and its direction, without a Ray to fill (the walks' exact
  // tests prepare one from them, for every beam a triangle's raster lets through).
  LASER_RAYCAST_HOT_INLINE void beam(int row, int col, const Eigen::Vector3d& d,
                                     Eigen::Vector3d* origin, Eigen::Vector3d* dir) const {
    const Pose& m = refFromColumn(col);
    if (class_of_row_.empty()) {
      *origin = m.translation();
      // Turning by the identity gives d's bits: skipped where no column turns.
      *dir = translations_only_ ? d : turn(m.linear(), d);
      return;
    }
    const ClassDelta& x = deltaOf(row, col);
    *origin = m.translation() + x.offset;
    // The class's turn first, then the column's (util/turn.h: inlined, Eigen's sums).
    *dir = translations_only_ ? d : turn(m.linear(), turn(x.rot, d));
  }
  // The direction of beam d at (row, col) in the reference sensor frame (ray(row, col, d).dir).
  LASER_RAYCAST_HOT_INLINE Eigen::Vector3d direction(int row, int col,
                                                     const Eigen::Vector3d& d) const {
    if (translations_only_) return d;
    if (class_of_row_.empty()) return turn(refFromColumn(col).linear(), d);
    return turn(refFromColumn(col).linear(), turn(deltaOf(row, col).rot, d));  // as ray() does
  }
  // A unit normal in the reference sensor frame as column col's sensor frame has it (the frame
  // ScanResult's normals are in).
  Eigen::Vector3d toColumn(int col, const Eigen::Vector3d& n) const {
    if (translations_only_) return n;
    return refFromColumn(col).linear().transpose() * n;
  }
  // The same in the frame of the beam at (row, col).
  Eigen::Vector3d toBeam(int row, int col, const Eigen::Vector3d& n) const {
    if (translations_only_) return n;
    const Eigen::Vector3d column_n = refFromColumn(col).linear().transpose() * n;
    if (class_of_row_.empty()) return column_n;
    return deltaOf(row, col).rot.transpose() * column_n;
  }
  // Each column's origin (refFromColumn(c).translation()) rounded to float, one array per axis,
  // for the columns from colLo() rounded down to a multiple of 4 to colHi() rounded up to one less
  // than a multiple of 4 (the padding repeats the nearest column's): originX(base)[j] is column
  // base + j's, base a multiple of 4 (the column raster's groups, column_raster.h).
  const float* originX(int base) const { return origin_[0].data() + (base - padded_lo_); }
  const float* originY(int base) const { return origin_[1].data() + (base - padded_lo_); }
  const float* originZ(int base) const { return origin_[2].data() + (base - padded_lo_); }
  // For inPlane(): a point of the scan plane, the reference sensor's x, y, in column col's.
  Eigen::Vector2d pointToColumn(int col, const Eigen::Vector2d& p) const {
    const Pose& m = refFromColumn(col);
    return m.linear().topLeftCorner<2, 2>().transpose() * (p - m.translation().head<2>());
  }

 private:
  // Sets the spread and the columns' origins from the poses' reach.
  void measure(const Reach& reach, double steepest, double extra_turn);

  LASER_RAYCAST_HOT_INLINE const ClassDelta& deltaOf(int row, int col) const {
    return deltas_[delta_set_[col - col_lo_] * classes_ + class_of_row_[row]];
  }

  int col_lo_;
  int columns_;
  std::vector<Pose> own_;  // the poses, where they are this motion's own
  const Pose* poses_;      // column c's at poses_[c - col_lo_]
  int classes_ = 1;
  std::vector<ClassDelta> deltas_;  // by set and class
  std::vector<int> delta_set_;      // by column
  Spread spread_;
  double sin_turn_ = 0;
  LASER_RAYCAST_HOT_INLINE Ray rayFrom(const Pose& m, const Eigen::Vector3d& d,
                                       double tmin) const {
    Ray r;
    r.origin = m.translation();
    // Turning by the identity gives d's bits: skipped where no column turns.
    r.dir = translations_only_ ? d : turn(m.linear(), d);
    r.tmin = tmin;
    return r;
  }

  bool in_plane_ = true;
  bool translations_only_ = true;
  std::vector<int> class_of_row_;
  double deviation_ = 0;
  int padded_lo_;
  std::vector<float> origin_[3];
};

}  // namespace core
}  // namespace laser_raycast
