#include "sensor.h"

#include <sensor_msgs/LaserScan.h>

#include <chrono>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "laser_raycast/ScanLabels.h"
#include "tf_timing.h"

namespace laser_raycast {

Sensor::Sensor(ros::NodeHandle& nh, const SensorParams& params, const std::string& fixed_frame,
               double grace_period, ros::Duration history)
    : params_(params),
      fixed_frame_(fixed_frame),
      grace_period_(grace_period),
      period_(1.0 / params.rate),
      pattern_(params.scan.pattern()),
      cast_config_(params.scan.castConfig()),
      encoder_(params.scan.output) {
  scan_pub_ = nh.advertise<sensor_msgs::LaserScan>("scan", kPublishQueue);
  labels_pub_ = nh.advertise<laser_raycast::ScanLabels>("scan_labels", kPublishQueue);
  if (!params_.pose_topic.empty()) {
    pose_topic_ = std::make_unique<PoseTopic>(nh, params_.pose_topic, fixed_frame_,
                                              ros::Duration(params_.pose_timeout), history);
  }
}

std::pair<std::string, std::string> Sensor::tfChain() const {
  if (!pose_topic_) return {fixed_frame_, params_.frame_id};
  return {params_.pose_frame.empty() ? params_.frame_id : params_.pose_frame, params_.frame_id};
}

bool Sensor::hasSubscribers() const {
  return scan_pub_.getNumSubscribers() > 0 || labels_pub_.getNumSubscribers() > 0;
}

void Sensor::setActive(bool active, const ros::Time& now) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (active && !active_) {
    window_start_ = now;
    window_published_ = stats_.published;
    window_skipped_ = stats_.skipped.total();
    ROS_DEBUG("sensor '%s': subscribed: casting", name().c_str());
  } else if (!active && (active_ || idle_since_.isZero())) {
    idle_since_ = now;
  }
  active_ = active;
  // Subscribers connect a moment after the node starts: only a lasting absence is logged.
  if (!active && !idle_logged_ && (now - idle_since_).toSec() >= kIdleLogDelay) {
    idle_logged_ = true;
    ROS_INFO("sensor '%s': nobody subscribes to %s: not cast until someone does (logged once)",
             name().c_str(), scan_pub_.getTopic().c_str());
  }
}

std::vector<ros::Time> Sensor::sampleTimes(const ros::Time& stamp) const { return {stamp}; }

bool Sensor::poseAt(const ros::Time& t, const TfSource& tf, Eigen::Isometry3d* pose,
                    std::string* why) {
  // Without a pose topic the sensor is a TF frame like any other; with one, the topic gives the
  // pose of pose_frame, and TF (usually a static mount) the sensor relative to it.
  Eigen::Isometry3d world_from_pose_frame = Eigen::Isometry3d::Identity();
  if (pose_topic_ && !pose_topic_->poseAt(t, tf, &world_from_pose_frame, why)) return false;
  const auto [target, source] = tfChain();
  Eigen::Isometry3d target_from_sensor;
  std::string error;
  if (!tf.lookup(target, source, t, &target_from_sensor, &error)) {
    std::ostringstream s;
    s << "no transform from '" << source << "' to '" << target << "' at t = " << std::fixed
      << std::setprecision(3) << t.toSec() << " (" << error << ")";
    *why = s.str();
    return false;
  }
  *pose = world_from_pose_frame * target_from_sensor;
  return true;
}

bool Sensor::quiet(const ros::Time& stamp) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (first_attempt_.isZero()) first_attempt_ = stamp;
  return stats_.published == 0 && (stamp - first_attempt_).toSec() < grace_period_;
}

void Sensor::castAndPublish(const core::Scene& scene, const std::vector<double>& reflectivity,
                            const std::vector<ros::Time>& times,
                            const std::vector<core::FramePoses>& frames,
                            const std::vector<Eigen::Isometry3d>& poses,
                            std::size_t missing_links) {
  const auto start = std::chrono::steady_clock::now();
  const core::ScanResult& result =
      caster_.cast(scene, frames.front(), poses.front(), pattern_, cast_config_);
  const double cast_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  encoder_.encode(scene, result, reflectivity, &encoded_);
  publishScan(scene, times.front());

  std::size_t hits = 0;
  for (const float r : encoded_.ranges) {
    hits += r >= params_.scan.output.range_min && r <= params_.scan.output.range_max;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (stats_.published == 0) {
    ROS_INFO(
        "sensor '%s': first scan at t = %.3f, %.3f s after the first attempt (%lu skipped "
        "while waiting for transforms)",
        name().c_str(), times.front().toSec(), (times.front() - first_attempt_).toSec(),
        static_cast<unsigned long>(stats_.skipped.total()));
  }
  if (stats_.published == 0) window_start_ = times.front();
  ++stats_.published;
  stats_.missing_links += missing_links;
  stats_.last_cast_seconds = cast_seconds;
  stats_.last_hit_share = encoded_.ranges.empty() ? 0.0 : double(hits) / encoded_.ranges.size();
}

void Sensor::publishScan(const core::Scene& scene, const ros::Time& stamp) {
  sensor_msgs::LaserScan scan;
  scan.header.stamp = stamp;  // every beam is cast at this instant
  scan.header.frame_id = params_.frame_id;
  scan.angle_min = static_cast<float>(pattern_.angleMin());
  scan.angle_max = static_cast<float>(pattern_.angleMax());
  scan.angle_increment = static_cast<float>(pattern_.angleIncrement());
  scan.time_increment = 0.0f;  // instantaneous: all beams share the stamp
  scan.scan_time = static_cast<float>(period_.toSec());
  scan.range_min = static_cast<float>(params_.scan.output.range_min);
  scan.range_max = static_cast<float>(params_.scan.output.range_max);
  scan.ranges = encoded_.ranges;
  scan.intensities = encoded_.intensities;
  scan_pub_.publish(scan);

  if (labels_pub_.getNumSubscribers() > 0) {
    laser_raycast::ScanLabels labels;
    labels.header = scan.header;
    labels.link_names = scene.labels();
    labels.labels.assign(encoded_.labels.begin(), encoded_.labels.end());
    labels_pub_.publish(labels);
  }
}

void Sensor::skip(Skip kind, const ros::Time& stamp, const std::string& why) {
  std::lock_guard<std::mutex> lock(mutex_);
  switch (kind) {
    case Skip::kNoPose:
      ++stats_.skipped.no_pose;
      break;
    case Skip::kWaiting:
      ++stats_.skipped.waiting;
      ROS_DEBUG("sensor '%s': waiting for the first transforms: %s", name().c_str(), why.c_str());
      return;
    case Skip::kBehind:
      ++stats_.skipped.behind;
      break;
  }
  const ros::WallTime now = ros::WallTime::now();
  if (!last_warning_.isZero() && (now - last_warning_).toSec() < kWarnPeriod) return;
  last_warning_ = now;
  ROS_WARN("sensor '%s': scan skipped (t = %.3f): %s (%lu of %lu so far)", name().c_str(),
           stamp.toSec(), why.c_str(), static_cast<unsigned long>(stats_.skipped.total()),
           static_cast<unsigned long>(stats_.skipped.total() + stats_.published));
}

SensorStats Sensor::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void Sensor::reportRate(const ros::Time& now) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!active_ || stats_.published == 0 || (now - window_start_).toSec() < kRateWindow) return;
  const double seconds = (now - window_start_).toSec();
  const double achieved = (stats_.published - window_published_) / seconds;
  const std::uint64_t skipped = stats_.skipped.total() - window_skipped_;
  if (achieved < kRateWarnShare * params_.rate) {
    ROS_WARN(
        "sensor '%s': %.1f Hz of the configured %.1f Hz over the last %.0f s (%lu scans "
        "skipped; the warnings above say why)",
        name().c_str(), achieved, params_.rate, seconds, static_cast<unsigned long>(skipped));
    rate_warned_ = true;
  } else if (rate_warned_) {
    ROS_INFO("sensor '%s': back to %.1f Hz of the configured %.1f Hz", name().c_str(), achieved,
             params_.rate);
    rate_warned_ = false;
  } else {
    ROS_DEBUG("sensor '%s': %.1f Hz of %.1f Hz", name().c_str(), achieved, params_.rate);
  }
  window_start_ = now;
  window_published_ = stats_.published;
  window_skipped_ = stats_.skipped.total();
}

}  // namespace laser_raycast
