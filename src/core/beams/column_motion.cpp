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
      ref_from_column_(std::move(ref_from_column)),
      class_of_row_(std::move(class_of_row)),
      ref_from_class_(std::move(ref_from_class)) {
  double shift2 = 0, frobenius2 = 0, z_move2 = 0, deviation2 = 0;
  auto add = [&](const Eigen::Isometry3d& m) {
    shift2 = std::max(shift2, m.translation().squaredNorm());
    frobenius2 = std::max(frobenius2, (m.linear() - Eigen::Matrix3d::Identity()).squaredNorm());
    z_move2 = std::max(z_move2, (m.linear().col(2) - Eigen::Vector3d::UnitZ()).squaredNorm());
    const Eigen::Matrix3d& r = m.linear();
    translations_only_ = translations_only_ && r == Eigen::Matrix3d::Identity();
    in_plane_ = in_plane_ && r(0, 2) == 0 && r(1, 2) == 0 && r(2, 0) == 0 && r(2, 1) == 0 &&
                r(2, 2) == 1 && m.translation().z() == 0;
  };
  for (const Eigen::Isometry3d& m : ref_from_column_) add(m);
  for (const auto& poses_of_class : ref_from_class_) {
    for (std::size_t c = 0; c < poses_of_class.size(); ++c) {
      add(poses_of_class[c]);
      deviation2 = std::max(
          deviation2,
          (poses_of_class[c].translation() - ref_from_column_[c].translation()).squaredNorm());
    }
  }
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
  spread_ = Spread::of(std::sqrt(shift2), turn + extra_turn, tilt, steepest);
}

}  // namespace core
}  // namespace laser_raycast
