// Where the sensor and every frame of a scene are at a few times across one scan, and their poses
// in between: linear in position, spherical (slerp) in rotation. A rotating scanner takes each
// beam at its own time; the caster places the sensor and every moving body at that time from these
// samples (Caster::castSweep).
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "laser_raycast/core/scene.h"

namespace laser_raycast {
namespace core {

// The pose a fraction s of the way from a to b (s = 0: a, s = 1: b): the translation interpolated
// linearly, the rotation along the shorter great arc.
Eigen::Isometry3d interpolatePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double s);

struct PoseSamples {
  std::vector<double> times;                         // s, strictly ascending, at least one
  std::vector<Eigen::Isometry3d> world_from_sensor;  // one per time
  std::vector<FramePoses> frames;                    // one per time, each for every scene frame

  // Throws std::invalid_argument naming the problem: no samples, sizes that differ, times that
  // are not finite or not strictly ascending, a FramePoses of the wrong size for scene.
  void validate(const Scene& scene) const;

  // The poses at time t, interpolated between the samples around it; before the first sample or
  // after the last, that sample's (no extrapolation). The sensor pose is not a valid pose (NaN) if
  // either neighbouring sample's is not; a frame is invalid if it is invalid in either.
  Eigen::Isometry3d sensorAt(double t) const;
  void framesAt(double t, FramePoses* out) const;
  // One frame's pose at time t as framesAt gives it; false (and *pose untouched) if it is invalid.
  bool frameAt(double t, std::size_t frame, Eigen::Isometry3d* pose) const;

 private:
  // The samples around t and the fraction of the way from the first to the second.
  void bracket(double t, std::size_t* i, std::size_t* j, double* s) const;
};

}  // namespace core
}  // namespace laser_raycast
