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
                           const std::vector<std::vector<Eigen::Isometry3d>>& ref_from_class)
    : col_lo_(col_lo),
      columns_(static_cast<int>(ref_from_column.size())),
      own_(ref_from_column.begin(), ref_from_column.end()),
      poses_(own_.data()),
      classes_(1 + static_cast<int>(ref_from_class.size())),
      class_of_row_(std::move(class_of_row)) {
  if (classes_ == 1) class_of_row_.clear();
  Reach reach;
  for (int c = 0; c < columns_; ++c) reach.add(poses_[c]);
  if (!class_of_row_.empty()) {
    // Each column's deltas of its own: its classes' poses taken relative to its pose.
    deltas_.reserve(static_cast<std::size_t>(columns_) * classes_);
    for (int c = 0; c < columns_; ++c) {
      delta_set_.push_back(c);
      deltas_.push_back(ClassDelta::identity());
      for (const auto& poses_of_class : ref_from_class) {
        deltas_.push_back(ClassDelta::between(poses_[c], poses_of_class[c]));
        reach.addDelta(deltas_.back());
      }
    }
  }
  measure(reach, steepest, extra_turn);
}

ColumnMotion::ColumnMotion(int col_lo, int columns, const Pose* poses, const Reach& reach,
                           double steepest, double extra_turn, std::vector<int> class_of_row,
                           std::vector<ClassDelta> deltas, std::vector<int> delta_set)
    : col_lo_(col_lo),
      columns_(columns),
      poses_(poses),
      classes_(class_of_row.empty()
                   ? 1
                   : 1 + *std::max_element(class_of_row.begin(), class_of_row.end())),
      deltas_(std::move(deltas)),
      delta_set_(std::move(delta_set)),
      class_of_row_(std::move(class_of_row)) {
  measure(reach, steepest, extra_turn);
}

void ColumnMotion::measure(const Reach& reach, double steepest, double extra_turn) {
  // The columns' turn, tilt and shift, and with row classes each raised by the most a class's
  // delta adds to it (|R D - I|_F <= |R - I|_F + |D - I|_F for rotations R, D, and so for the
  // z axis and the translation), widened for the rounding of the sums.
  const bool classes = !class_of_row_.empty();
  double frobenius2 = reach.turnFrobenius2(), z_move2 = reach.z_move2, shift2 = reach.shift2;
  if (classes) {
    auto raise = [](double square, double by) {
      const double sum = (std::sqrt(square) + by) * (1 + 1e-9);
      return sum * sum;
    };
    frobenius2 = raise(frobenius2, reach.delta_turn);
    z_move2 = raise(z_move2, reach.delta_tilt);
    shift2 = raise(shift2, reach.delta_offset);
  }
  translations_only_ = reach.translationsOnly() && (!classes || reach.deltas_identity);
  in_plane_ = reach.inPlane() && (!classes || reach.deltas_in_plane);
  // How far a beam's origin lies from its column's: its class's offset.
  deviation_ = classes ? reach.delta_offset * (1 + 1e-9) : 0;
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
  spread_ = Spread::of(std::sqrt(shift2), turn + extra_turn, tilt, steepest);
  sin_turn_ = std::sin(std::min(M_PI / 2, spread_.turn));
}

}  // namespace core
}  // namespace laser_raycast
