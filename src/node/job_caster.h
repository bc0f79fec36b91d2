// The work on one job of the scan queue, without a thread: whether every transform it needs is in
// (tf_timing.h's policy at a given time: covered, stale or missing, none still late), and its
// cast: each sensor's pose, the link poses looked up once per time for every sensor due then
// (link_poses.h), and the sensor's cast. The node's cast thread calls it as TF arrives, with ROS
// time; simulate_bag as it reads a bag, with the bag's time.
#pragma once

#include <ros/time.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "laser_raycast/core/scene.h"
#include "link_poses.h"
#include "scan_queue.h"
#include "sensor.h"
#include "tf_source.h"

namespace laser_raycast {

class JobCaster {
 public:
  // Everything it reads; it must outlive this.
  struct Context {
    const core::Scene* scene = nullptr;
    const std::vector<double>* reflectivity = nullptr;  // by label
    const std::vector<char>* reflectivity_fixed = nullptr;  // by label (scene_source.h)
    const TfSource* tf = nullptr;
    std::vector<std::unique_ptr<Sensor>>* sensors = nullptr;
    std::string fixed_frame;
    ros::Duration tf_timeout;
  };

  explicit JobCaster(Context context);

  const Context& context() const { return context_; }
  // Whether every transform the job needs is covered, stale or missing at `now` (none still late).
  bool ready(const ScanJob& job, const ros::Time& now);
  // Casts the job's sensors (each one skipped, and counted by its monitor, without a pose).
  void cast(const ScanJob& job);
  // After `job` was cast: forgets the link poses that no job still queued needs (oldest_queued: the
  // earliest stamp in the queue, if any).
  void done(const ScanJob& job, const std::optional<ros::Time>& oldest_queued);
  // TF look-ups of link poses so far (LinkPoses::lookups).
  std::uint64_t linkLookups() const { return link_poses_.lookups(); }

 private:
  // Which transforms the front job still waits for; reset when another job comes to the front.
  struct Wait {
    ros::Time last;
    std::vector<std::pair<std::string, std::string>> chains;  // (target, source)
    std::vector<FrameAvailability> state;
  };

  // The sensor's poses at the job's times; false (the scan counted as skipped) without one.
  bool sensorPoses(Sensor& sensor, const ScanJob& job, bool quiet,
                   std::vector<Eigen::Isometry3d>* poses);
  // Whether the scan goes ahead without the links in links.missing (warned about, throttled).
  bool acceptMissing(Sensor& sensor, const ScanJob& job, bool quiet, const LinkPosesAt& links);
  void castSensor(Sensor& sensor, const ScanJob& job);

  // A condition that lasts (missing link transforms) is warned about at most this often.
  static constexpr double kWarnPeriod = 5.0;  // s
  // Link names a warning lists before "... (N more)".
  static constexpr std::size_t kLinksInWarning = 5;

  Context context_;
  Wait wait_;
  LinkPoses link_poses_;
  ros::WallTime last_link_warning_;
};

}  // namespace laser_raycast
