// Rigid poses composed for sensor-relative arithmetic.
#pragma once

#include <Eigen/Geometry>

namespace laser_raycast {
namespace core {

// a_from_b, given w_from_a as its rotation's transpose and its translation, and w_from_b, in a
// common frame w. The translations are subtracted before rotating, so two poses 10^6 m from the
// origin but close to each other give a relative pose as accurate as near the origin (Sterbenz:
// the difference of nearby doubles is exact). For many poses relative to one, the transpose is
// taken once.
inline Eigen::Isometry3d relativePose(const Eigen::Matrix3d& a_rot_t, const Eigen::Vector3d& w_a,
                                      const Eigen::Isometry3d& w_from_b) {
  Eigen::Isometry3d a_from_b;
  a_from_b.linear() = a_rot_t * w_from_b.linear();
  a_from_b.translation() = a_rot_t * (w_from_b.translation() - w_a);
  a_from_b.makeAffine();
  return a_from_b;
}

// a_from_b, given both poses in a common frame w (the same expressions as above).
inline Eigen::Isometry3d relativePose(const Eigen::Isometry3d& w_from_a,
                                      const Eigen::Isometry3d& w_from_b) {
  return relativePose(Eigen::Matrix3d(w_from_a.linear().transpose()), w_from_a.translation(),
                      w_from_b);
}

// True if every entry is finite and the rotation part is orthonormal with determinant +1 to within
// 1e-6 (poses from messages and TF are normalised quaternions; anything farther off is a bad
// input).
bool isValidPose(const Eigen::Isometry3d& pose);

}  // namespace core
}  // namespace laser_raycast
