// Reading received scans in rostests: an index past a scan's end (a scan that never came) fails the
// test with a message instead of crashing the test binary.
#pragma once

#include <gtest/gtest.h>
#include <sensor_msgs/LaserScan.h>

#include <cstddef>
#include <limits>

namespace laser_raycast_test {

// The range of `beam`, or NaN (with a failure) if the scan has no such beam.
inline double rangeOf(const sensor_msgs::LaserScan& scan, std::size_t beam) {
  if (beam >= scan.ranges.size()) {
    ADD_FAILURE() << "the scan has " << scan.ranges.size() << " beams, not " << beam + 1;
    return std::numeric_limits<double>::quiet_NaN();
  }
  return scan.ranges[beam];
}

}  // namespace laser_raycast_test
