// The closed room of test/data/sensors_room.urdf, worked out by hand: its inner faces are the
// planes x = -5, x = 5, y = -4, y = 4, z = 0 and z = 4. Used by the sensors rostest and
// simulate_bag's tests.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <limits>

namespace laser_raycast_test {

// The distance from p (inside the room) along unit direction d to the room's inner faces.
inline double roomDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& d) {
  const Eigen::Vector3d lo(-5, -4, 0), hi(5, 4, 4);
  double t = std::numeric_limits<double>::infinity();
  for (int axis = 0; axis < 3; ++axis) {
    if (d[axis] > 0) t = std::min(t, (hi[axis] - p[axis]) / d[axis]);
    if (d[axis] < 0) t = std::min(t, (lo[axis] - p[axis]) / d[axis]);
  }
  return t;
}

// The axis of the inner face that the beam from p along unit d meets first (roomDistance's).
inline int roomFaceAxis(const Eigen::Vector3d& p, const Eigen::Vector3d& d) {
  const Eigen::Vector3d lo(-5, -4, 0), hi(5, 4, 4);
  double t = std::numeric_limits<double>::infinity();
  int face = -1;
  for (int axis = 0; axis < 3; ++axis) {
    const double s = d[axis] > 0 ? (hi[axis] - p[axis]) / d[axis]
                     : d[axis] < 0 ? (lo[axis] - p[axis]) / d[axis]
                                   : std::numeric_limits<double>::infinity();
    if (s < t) {
      t = s;
      face = axis;
    }
  }
  return face;
}

}  // namespace laser_raycast_test
