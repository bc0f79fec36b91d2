// One simulated sensor of the node: its beams, caster and encoder, where its pose comes from (TF or
// a pose topic), its publishers, and what it has done (published, skipped and why, cast time) for
// the log and the diagnostics. The node's cast thread calls it; its timer and the subscriber check
// run on the node's callback thread.
#pragma once

#include <ros/ros.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/scan_encoder.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/scene.h"
#include "laser_raycast/node/node_params.h"
#include "pose_topic.h"
#include "tf_source.h"

namespace laser_raycast {

// Why scans were not published, counted per sensor.
struct SkipCounts {
  std::uint64_t no_pose = 0;  // no sensor pose at the scan's time (TF or pose topic)
  std::uint64_t waiting = 0;  // transforms missing during the start-up grace period
  std::uint64_t behind = 0;   // dropped: the cast thread was too far behind
  std::uint64_t total() const { return no_pose + waiting + behind; }
};

// What a sensor has done so far; a copy, taken under the sensor's lock.
struct SensorStats {
  std::uint64_t published = 0;
  SkipCounts skipped;
  std::uint64_t missing_links = 0;  // link transforms left out of published scans, summed
  double last_cast_seconds = 0;     // wall time of the last cast (look-ups excluded)
  double last_hit_share = 0;        // share of the last scan's beams with a valid return
};

class Sensor {
 public:
  // TF publishers usually start with or after the node, so for this long after the sensor's first
  // scan attempt, until its first scan, scans that lack a transform are skipped without a warning
  // (RaycastNode::kTfGracePeriod).
  Sensor(ros::NodeHandle& nh, const SensorParams& params, const std::string& fixed_frame,
         double grace_period, ros::Duration history);

  const SensorParams& params() const { return params_; }
  // The sensor's name in the log: its frame.
  const std::string& name() const { return params_.frame_id; }
  // The TF chain its pose needs, as (target, source): fixed_frame <- frame_id, or, with a pose
  // topic, pose_frame <- frame_id.
  std::pair<std::string, std::string> tfChain() const;
  // Whether anyone listens to any of its topics (otherwise it is not cast).
  bool hasSubscribers() const;
  // Whether scans are being queued (someone listens): the first time not, it is logged; the rate
  // is measured only while active.
  void setActive(bool active, const ros::Time& now);
  // The pose sample times of a scan stamped at `stamp`.
  std::vector<ros::Time> sampleTimes(const ros::Time& stamp) const;
  const ros::Duration& period() const { return period_; }

  // The sensor pose in fixed_frame at t; false with the reason in *why.
  bool poseAt(const ros::Time& t, const TfSource& tf, Eigen::Isometry3d* pose, std::string* why);
  // Whether problems with the scan at `stamp` are reported quietly: no scan published yet and
  // stamp within the grace period of the first attempted scan's (the first call starts it).
  bool quiet(const ros::Time& stamp);

  // Casts the scan whose pose samples are at `times`, the frames and sensor poses at each, and
  // publishes it. missing_links: link transforms left out of it.
  void castAndPublish(const core::Scene& scene, const std::vector<double>& reflectivity,
                      const std::vector<ros::Time>& times,
                      const std::vector<core::FramePoses>& frames,
                      const std::vector<Eigen::Isometry3d>& poses, std::size_t missing_links);
  // A scan at `stamp` was not published: why (for the log), and which count it goes to.
  enum class Skip { kNoPose, kWaiting, kBehind };
  void skip(Skip kind, const ros::Time& stamp, const std::string& why);

  SensorStats stats() const;
  // Logs the achieved rate against the configured one over the last window (called each second).
  void reportRate(const ros::Time& now);

 private:
  void publishScan(const core::Scene& scene, const ros::Time& stamp);

  // A condition that lasts (no pose, late transforms) is warned about at most this often: every
  // scan (10 to 100 Hz) would flood the log.
  static constexpr double kWarnPeriod = 5.0;  // s
  // Scans queued for a slow subscriber before the oldest is dropped (1 s at the default rate).
  static constexpr std::uint32_t kPublishQueue = 10;
  // The achieved rate is measured over this long, and warned about below this share of the
  // configured one (a scan or two lost to jitter in a window is not worth a warning).
  static constexpr double kRateWindow = 10.0;  // s
  static constexpr double kRateWarnShare = 0.9;
  // A sensor nobody subscribes to for this long (ROS time) is logged as idle.
  static constexpr double kIdleLogDelay = 2.0;  // s

  SensorParams params_;
  std::string fixed_frame_;
  double grace_period_;
  ros::Duration period_;
  core::ScanPattern pattern_;
  core::CastConfig cast_config_;
  core::Caster caster_;
  core::ScanEncoder encoder_;
  core::EncodedScan encoded_;
  std::unique_ptr<PoseTopic> pose_topic_;
  ros::Publisher scan_pub_, labels_pub_;

  mutable std::mutex mutex_;  // the counters below: written by the cast thread, read by timers
  SensorStats stats_;
  ros::Time first_attempt_;
  ros::WallTime last_warning_;
  // The rate window: its start and the scans published before it; whether the last one warned.
  ros::Time window_start_;
  std::uint64_t window_published_ = 0, window_skipped_ = 0;
  bool rate_warned_ = false;
  bool active_ = false, idle_logged_ = false;
  ros::Time idle_since_;
};

}  // namespace laser_raycast
