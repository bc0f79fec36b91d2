// What a sensor's monitor (sensor_monitor.h) counts, without roscore: the counts the diagnostics
// publish.
#include <gtest/gtest.h>

#include <string>

#include "sensor_monitor.h"

namespace laser_raycast_test {
namespace {

using laser_raycast::SensorMonitor;

ros::Time at(double s) { return ros::Time(s); }

// TF look-up failures are counted as reported, whatever else the scan did; they are not derived
// from the skips or the links left out (a rotating scan misses a link at each of its sample times
// but leaves it out once).
TEST(SensorMonitor, LookUpFailuresAreCountedAsReported) {
  SensorMonitor monitor("spinner", "/spinner/scan", 5.0);
  monitor.quiet(at(100));
  monitor.lookupFailures(11);  // one link at the 11 sample times of a rotating scan
  monitor.published(at(100), 1, 0.001, 1.0);
  monitor.lookupFailures(0);
  monitor.lookupFailures(1);  // the sensor's own transform
  monitor.skipped(SensorMonitor::Skip::kNoTransform, at(100.1), "no transform");
  monitor.skipped(SensorMonitor::Skip::kBehind, at(100.2), "behind");
  const laser_raycast::SensorStats stats = monitor.stats();
  EXPECT_EQ(stats.tf_failures, 12u);
  EXPECT_EQ(stats.missing_links, 1u);
  EXPECT_EQ(stats.skipped.no_transform, 1u);
  EXPECT_EQ(stats.skipped.behind, 1u);
}

}  // namespace
}  // namespace laser_raycast_test
