// What a sensor's monitor (sensor_monitor.h) counts and logs, without roscore: the counts the
// diagnostics publish, and the log lines, caught by a rosconsole appender.
#include <gtest/gtest.h>
#include <ros/console.h>

#include <mutex>
#include <string>
#include <utility>
#include <vector>

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

// Every line logged through rosconsole while it exists (INFO and above: the default level).
class LogCatcher : public ros::console::LogAppender {
 public:
  LogCatcher() { ros::console::register_appender(this); }
  ~LogCatcher() override { ros::console::deregister_appender(this); }
  void log(ros::console::Level level, const char* str, const char*, const char*, int) override {
    std::lock_guard<std::mutex> lock(mutex_);
    lines_.push_back({level, str});
  }
  // The lines at `level` containing `part`.
  int count(ros::console::Level level, const std::string& part) {
    std::lock_guard<std::mutex> lock(mutex_);
    int n = 0;
    for (const auto& [l, text] : lines_) n += l == level && text.find(part) != std::string::npos;
    return n;
  }

 private:
  std::mutex mutex_;
  std::vector<std::pair<ros::console::Level, std::string>> lines_;
};

// A sensor nobody subscribes to is logged once, 2 s (ROS time) after the idle time began, and never
// again: not while it stays idle, nor when it becomes idle again after a subscriber left. The timer
// calls setActive every tick (here 10 Hz).
TEST(SensorMonitor, NobodySubscribesIsLoggedOnce) {
  LogCatcher log;
  const std::string idle = "sensor 'idle': nobody subscribes to /idle/scan";
  SensorMonitor monitor("idle", "/idle/scan", 5.0);
  double t = 100.0;
  for (; t < 101.95; t += 0.1) monitor.setActive(false, at(t));
  EXPECT_EQ(log.count(ros::console::levels::Info, idle), 0) << "logged before 2 s";
  for (; t < 110; t += 0.1) monitor.setActive(false, at(t));
  EXPECT_EQ(log.count(ros::console::levels::Info, idle), 1);
  // A subscriber comes and goes; the sensor is idle again for 10 s.
  for (; t < 112; t += 0.1) monitor.setActive(true, at(t));
  for (; t < 122; t += 0.1) monitor.setActive(false, at(t));
  EXPECT_EQ(log.count(ros::console::levels::Info, idle), 1);
  // Each sensor logs its own.
  SensorMonitor other("front", "/front/scan", 5.0);
  for (double u = 100; u < 103; u += 0.1) other.setActive(false, at(u));
  EXPECT_EQ(log.count(ros::console::levels::Info, "sensor 'front': nobody subscribes"), 1);
  EXPECT_EQ(log.count(ros::console::levels::Info, idle), 1);
}

}  // namespace
}  // namespace laser_raycast_test
