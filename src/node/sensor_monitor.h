// What one sensor has done, for the log and the diagnostics: scans published and skipped (and
// why), link transforms left out, cast time, share of beams hit; the achieved rate against the
// configured one; whether anyone listens. Thread-safe: the cast thread writes, timers read.
#pragma once

#include <ros/time.h>

#include <cstdint>
#include <mutex>
#include <string>

namespace laser_raycast {

// Why scans were not published.
struct SkipCounts {
  std::uint64_t no_transform = 0;  // no TF transform for the sensor at the scan's time
  std::uint64_t stale_pose = 0;    // the pose topic's pose is missing, stale or non-finite
  std::uint64_t waiting = 0;       // transforms missing during the start-up grace period
  std::uint64_t behind = 0;        // dropped: the cast thread was too far behind
  std::uint64_t total() const { return no_transform + stale_pose + waiting + behind; }
};

struct SensorStats {
  std::uint64_t published = 0;
  SkipCounts skipped;
  std::uint64_t missing_links = 0;  // link transforms left out of published scans, summed
  // TF look-ups its scans needed that failed: its own pose's chain (to fixed_frame, or from
  // pose_frame) and its pose topic's frames, at each sample time; and each link at each sample
  // time (a look-up shared with other sensors due then counts for each of them).
  std::uint64_t tf_failures = 0;
  double last_cast_seconds = 0;  // wall time of the last cast (look-ups and publishing excluded)
  double last_hit_share = 0;     // share of the last scan's beams with a valid return
  bool active = false;           // someone subscribes: scans are queued
  std::string last_skip;         // why the last scan not published was skipped
};

class SensorMonitor {
 public:
  enum class Skip { kNoTransform, kStalePose, kWaiting, kBehind };

  // name and topic name the sensor in messages; grace: RaycastNode::kTfGracePeriod.
  SensorMonitor(std::string name, std::string topic, double grace_period);

  // Whether problems with the scan at `stamp` are reported quietly: no scan published yet and
  // stamp within the grace period of the first attempted scan's (the first call starts it).
  bool quiet(const ros::Time& stamp);
  void published(const ros::Time& stamp, std::size_t missing_links, double cast_seconds,
                 double hit_share);
  // Adds TF look-ups that failed (SensorStats::tf_failures).
  void lookupFailures(std::uint64_t failures);
  // Counts a scan not published and warns (at most every kWarnPeriod) why, except while waiting.
  void skipped(Skip kind, const ros::Time& stamp, const std::string& why);
  // Whether scans are queued (someone listens); a lasting absence is logged once.
  void setActive(bool active, const ros::Time& now);
  // Logs the achieved rate against `rate` over the last window (called every second).
  void reportRate(const ros::Time& now, double rate);
  SensorStats stats() const;

 private:
  // A condition that lasts (no pose, late transforms) is warned about at most this often: every
  // scan (10 to 100 Hz) would flood the log.
  static constexpr double kWarnPeriod = 5.0;  // s
  // The achieved rate is measured over this long, and warned about below this share of the
  // configured one (a scan or two lost to jitter in a window is not worth a warning).
  static constexpr double kRateWindow = 10.0;  // s
  static constexpr double kRateWarnShare = 0.9;
  // Subscribers connect a moment after the node starts: nobody subscribing for this long (ROS
  // time) is logged.
  static constexpr double kIdleLogDelay = 2.0;  // s

  void restartWindow(const ros::Time& now);

  const std::string name_, topic_;
  const double grace_period_;
  mutable std::mutex mutex_;
  SensorStats stats_;
  ros::Time first_attempt_;
  ros::WallTime last_warning_;
  ros::Time window_start_, idle_since_;
  std::uint64_t window_published_ = 0, window_skipped_ = 0;
  bool rate_warned_ = false, idle_logged_ = false;
};

}  // namespace laser_raycast
