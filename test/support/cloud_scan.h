// The small scan the point cloud tests build clouds from (test_point_cloud, test_point_layouts):
// two rings of three azimuths, and a measured scan with a return, no return, too close and NaN
// among its six beams.
#pragma once

#include <cmath>
#include <limits>

#include "laser_raycast/core/measurement_model.h"
#include "laser_raycast/core/scan_spec.h"

namespace laser_raycast_test {

// Two rings (given high first: ring 0 is the lower, -0.3 rad; ring 1 at 0.2) of three azimuths
// -pi/2, 0, pi/2.
inline laser_raycast::core::ScanPattern twoRings() {
  laser_raycast::core::ScanSpec spec;
  spec.fan.angle_min = -M_PI / 2;
  spec.fan.angle_max = M_PI / 2;
  spec.fan.samples = 3;
  spec.elevations = {0.2, -0.3};
  return spec.pattern();
}

// Ring-major: ring 0 = {2 m, no return, 1.5 m}, ring 1 = {too close, 3 m, NaN}; intensities 0.5,
// 0.25 and 0.75 for the returns.
inline laser_raycast::core::MeasuredScan sixBeams() {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  laser_raycast::core::MeasuredScan scan;
  scan.ranges = {2.0f, kInf, 1.5f, -kInf, 3.0f, std::numeric_limits<float>::quiet_NaN()};
  scan.intensities = {0.5f, 0.0f, 0.25f, 0.0f, 0.75f, 0.0f};
  scan.labels = {0, -1, 0, 0, 0, -1};
  return scan;
}

}  // namespace laser_raycast_test
