#include "sensor_monitor.h"

#include <ros/console.h>

#include <utility>

namespace laser_raycast {

SensorMonitor::SensorMonitor(std::string name, std::string topic, double grace_period)
    : name_(std::move(name)), topic_(std::move(topic)), grace_period_(grace_period) {}

bool SensorMonitor::quiet(const ros::Time& stamp) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (first_attempt_.isZero()) first_attempt_ = stamp;
  return stats_.published == 0 && (stamp - first_attempt_).toSec() < grace_period_;
}

void SensorMonitor::published(const ros::Time& stamp, std::size_t missing_links,
                              double cast_seconds, double hit_share) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (stats_.published == 0) {
    ROS_INFO(
        "sensor '%s': first scan at t = %.3f, %.3f s after the first attempt (%lu skipped "
        "while waiting for transforms)",
        name_.c_str(), stamp.toSec(), (stamp - first_attempt_).toSec(),
        static_cast<unsigned long>(stats_.skipped.total()));
    restartWindow(stamp);
  }
  ++stats_.published;
  stats_.missing_links += missing_links;
  stats_.last_cast_seconds = cast_seconds;
  stats_.last_hit_share = hit_share;
}

void SensorMonitor::lookupFailures(std::uint64_t failures) {
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.tf_failures += failures;
}

void SensorMonitor::skipped(Skip kind, const ros::Time& stamp, const std::string& why) {
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.last_skip = why;
  switch (kind) {
    case Skip::kNoTransform:
      ++stats_.skipped.no_transform;
      break;
    case Skip::kStalePose:
      ++stats_.skipped.stale_pose;
      break;
    case Skip::kWaiting:
      ++stats_.skipped.waiting;
      ROS_DEBUG("sensor '%s': waiting for the first transforms: %s", name_.c_str(), why.c_str());
      return;
    case Skip::kBehind:
      ++stats_.skipped.behind;
      break;
  }
  const ros::WallTime now = ros::WallTime::now();
  if (!last_warning_.isZero() && (now - last_warning_).toSec() < kWarnPeriod) return;
  last_warning_ = now;
  ROS_WARN("sensor '%s': scan skipped (t = %.3f): %s (%lu of %lu so far)", name_.c_str(),
           stamp.toSec(), why.c_str(), static_cast<unsigned long>(stats_.skipped.total()),
           static_cast<unsigned long>(stats_.skipped.total() + stats_.published));
}

void SensorMonitor::setActive(bool active, const ros::Time& now) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (active && !stats_.active) {
    restartWindow(now);
  } else if (!active && (stats_.active || idle_since_.isZero())) {
    idle_since_ = now;
  }
  stats_.active = active;
  if (!active && !idle_logged_ && (now - idle_since_).toSec() >= kIdleLogDelay) {
    idle_logged_ = true;
    ROS_INFO("sensor '%s': nobody subscribes to %s: not cast until someone does (logged once)",
             name_.c_str(), topic_.c_str());
  }
}

void SensorMonitor::restartWindow(const ros::Time& now) {
  window_start_ = now;
  window_published_ = stats_.published;
  window_skipped_ = stats_.skipped.total();
}

void SensorMonitor::reportRate(const ros::Time& now, double rate) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!stats_.active || stats_.published == 0 || (now - window_start_).toSec() < kRateWindow) {
    return;
  }
  const double seconds = (now - window_start_).toSec();
  const double achieved = (stats_.published - window_published_) / seconds;
  const std::uint64_t skipped = stats_.skipped.total() - window_skipped_;
  if (achieved < kRateWarnShare * rate) {
    ROS_WARN(
        "sensor '%s': %.1f Hz of the configured %.1f Hz over the last %.0f s (%lu scans "
        "skipped; the warnings above say why)",
        name_.c_str(), achieved, rate, seconds, static_cast<unsigned long>(skipped));
    rate_warned_ = true;
  } else if (rate_warned_) {
    ROS_INFO("sensor '%s': back to %.1f Hz of the configured %.1f Hz", name_.c_str(), achieved,
             rate);
    rate_warned_ = false;
  } else {
    ROS_DEBUG("sensor '%s': %.1f Hz of %.1f Hz", name_.c_str(), achieved, rate);
  }
  restartWindow(now);
}

SensorStats SensorMonitor::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

}  // namespace laser_raycast
