#include "beams/column_motion.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace laser_raycast {
namespace core {

ColumnMotion::ColumnMotion(int col_lo, std::vector<Eigen::Isometry3d> ref_from_column,
                           double steepest)
    : col_lo_(col_lo), ref_from_column_(std::move(ref_from_column)) {
  double shift = 0, turn = 0, tilt = 0;
  for (const Eigen::Isometry3d& m : ref_from_column_) {
    shift = std::max(shift, m.translation().norm());
    // A rotation by angle a moves the unit axes by |R - I|_F = 2 sqrt(2) sin(a / 2), and the z
    // axis by |R e_z - e_z| = 2 sin(tilt / 2): both well conditioned for small angles.
    const double frobenius = (m.linear() - Eigen::Matrix3d::Identity()).norm();
    turn = std::max(turn, 2 * std::asin(std::min(1.0, frobenius / (2 * std::sqrt(2.0)))));
    const double z_move = (m.linear().col(2) - Eigen::Vector3d::UnitZ()).norm();
    tilt = std::max(tilt, 2 * std::asin(std::min(1.0, z_move / 2)));
  }
  spread_ = Spread::of(shift, turn, tilt, steepest);
}

}  // namespace core
}  // namespace laser_raycast
