// FanSpec in one line for the unit tests: by sample count or by angular increment.
#pragma once

#include "laser_raycast/core/scan_pattern.h"

namespace laser_raycast_test {

inline laser_raycast::core::FanSpec fanBySamples(double min, double max, int samples) {
  laser_raycast::core::FanSpec fan;
  fan.angle_min = min;
  fan.angle_max = max;
  fan.samples = samples;
  return fan;
}

inline laser_raycast::core::FanSpec fanByIncrement(double min, double max, double increment) {
  laser_raycast::core::FanSpec fan;
  fan.angle_min = min;
  fan.angle_max = max;
  fan.angle_increment = increment;
  return fan;
}

}  // namespace laser_raycast_test
