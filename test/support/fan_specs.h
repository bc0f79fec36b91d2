// FanSpec in one line for the unit tests: by sample count or by angular increment.
#pragma once

#include "laser_raycast/core/scan_pattern.h"

namespace laser_raycast {
namespace test {

inline core::FanSpec fanBySamples(double min, double max, int samples) {
  core::FanSpec fan;
  fan.angle_min = min;
  fan.angle_max = max;
  fan.samples = samples;
  return fan;
}

inline core::FanSpec fanByIncrement(double min, double max, double increment) {
  core::FanSpec fan;
  fan.angle_min = min;
  fan.angle_max = max;
  fan.angle_increment = increment;
  return fan;
}

}  // namespace test
}  // namespace laser_raycast
