#include "laser_raycast/core/pose.h"

namespace laser_raycast {
namespace core {

bool isValidPose(const Eigen::Isometry3d& pose) {
  if (!pose.matrix().allFinite()) return false;
  const Eigen::Matrix3d r = pose.linear();
  // Written so that a NaN fails: the tolerance is for poses built from normalised float
  // quaternions.
  const double orthonormality_error =
      (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  return orthonormality_error <= 1e-6 && r.determinant() > 0;
}

}  // namespace core
}  // namespace laser_raycast
