#include "beams/column_motion.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace laser_raycast {
namespace core {

ColumnMotion::ColumnMotion(int col_lo, std::vector<Eigen::Isometry3d> ref_from_column,
                           double steepest, double extra_turn)
    : ColumnMotion(col_lo, std::move(ref_from_column), steepest, extra_turn, {}, {}) {}

ColumnMotion::ColumnMotion(int col_lo, std::vector<Eigen::Isometry3d> ref_from_column,
                           double steepest, double extra_turn, std::vector<int> class_of_row,
                           std::vector<std::vector<Eigen::Isometry3d>> ref_from_class)
    : col_lo_(col_lo),
      columns_(static_cast<int>(ref_from_column.size())),
      own_(ref_from_column.begin(), ref_from_column.end()),
      stride_(columns_),
      classes_(1 + static_cast<int>(ref_from_class.size())),
      class_of_row_(std::move(class_of_row)) {
  for (const auto& poses_of_class : ref_from_class) {
    own_.insert(own_.end(), poses_of_class.begin(), poses_of_class.end());
  }
  poses_ = own_.data();
  measure(reachOf(), steepest, extra_turn);
}

ColumnMotion::ColumnMotion(int col_lo, int columns, const Pose* poses, int stride,
                           int classes, const Reach& reach, double steepest, double extra_turn,
                           std::vector<int> class_of_row)
    : col_lo_(col_lo),
      columns_(columns),
      poses_(poses),
      stride_(stride),
      classes_(classes),
      class_of_row_(std::move(class_of_row)) {
  measure(reach, steepest, extra_turn);
}

ColumnMotion::Reach ColumnMotion::reachOf() const {
  Reach reach;
  for (int c = 0; c < columns_; ++c) reach.add(poses_[c]);
  for (int k = 1; k < classes_; ++k) {
    for (int c = 0; c < columns_; ++c) {
      const Pose& m = poses_[k * stride_ + c];
      reach.add(m);
      reach.addDeviation(m.translation(), poses_[c].translation());
    }
  }
  return reach;
}

void ColumnMotion::measure(const Reach& reach, double steepest, double extra_turn) {
  const double frobenius2 = reach.turnFrobenius2(), z_move2 = reach.z_move2;
  const double deviation2 = reach.deviation2;
  translations_only_ = reach.translationsOnly();
  in_plane_ = reach.inPlane();
  // The largest norm (a square root is monotonic and correctly rounded: the root of the largest
  // square is the largest root), widened for its rounding.
  deviation_ = deviation2 > 0 ? std::sqrt(deviation2) * (1 + 1e-9) : 0;
  padded_lo_ = col_lo_ & ~3;
  const int padded_hi = colHi() | 3;
  for (std::vector<float>& axis : origin_) axis.resize(padded_hi - padded_lo_ + 1);
  for (int c = padded_lo_; c <= padded_hi; ++c) {
    const Eigen::Vector3d& o = refFromColumn(std::clamp(c, col_lo_, colHi())).translation();
    for (int k = 0; k < 3; ++k) origin_[k][c - padded_lo_] = static_cast<float>(o[k]);
  }
  // A rotation by angle a moves the unit axes by |R - I|_F = 2 sqrt(2) sin(a / 2), and the z axis
  // by |R e_z - e_z| = 2 sin(tilt / 2): both well conditioned for small angles, and increasing in
  // the angle, so the largest gives the largest angle.
  const double turn = 2 * std::asin(std::min(1.0, std::sqrt(frobenius2) / (2 * std::sqrt(2.0))));
  const double tilt = 2 * std::asin(std::min(1.0, std::sqrt(z_move2) / 2));
  spread_ = Spread::of(std::sqrt(reach.shift2), turn + extra_turn, tilt, steepest);
}

}  // namespace core
}  // namespace laser_raycast
