// The node's cast thread. Sensor timers only queue scans (ScanQueue); this thread takes them in the
// order their transforms become due, waits until TF covers each one's last beam (tf_timing.h: a
// late transform is waited for up to ~tf_timeout, a dead one not at all), looks the link poses up
// once per time for every sensor due then (link_poses.h), and has each sensor cast and publish. So
// a wait for TF never costs the timers their rate: scans queue up behind it and are cast as the
// transforms come. The scene is taken from a SharedScene at the start of each job (shared_scene.h):
// a scene swapped in meanwhile serves the next job, never part of one.
#pragma once

#include <ros/ros.h>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "laser_raycast/core/scene.h"
#include "link_poses.h"
#include "scan_queue.h"
#include "sensor.h"
#include "shared_scene.h"
#include "tf_source.h"

namespace laser_raycast {

class CastThread {
 public:
  // Everything the thread reads; it must outlive the thread (the node owns both).
  struct Context {
    const SharedScene* scene = nullptr;
    const TfSource* tf = nullptr;
    std::vector<std::unique_ptr<Sensor>>* sensors = nullptr;
    std::string fixed_frame;
    ros::Duration tf_timeout;
  };

  explicit CastThread(Context context);
  ~CastThread();  // stops and joins

  // Queues sensor's scan whose poses are sampled at `times` (Sensor::sampleTimes).
  void schedule(int sensor, const std::vector<ros::Time>& times);
  // At most this many jobs wait; beyond, the oldest is dropped (counted as skipped by its sensors).
  void setCapacity(std::size_t capacity);
  // TF look-ups of link poses so far: one per link frame and scan time, for every sensor due then
  // (LinkPoses::lookups). Any thread.
  std::uint64_t linkLookups() const { return link_lookups_; }

 private:
  // Which transforms the front job still waits for; reset when another job comes to the front.
  struct Wait {
    ros::Time last;
    std::vector<std::pair<std::string, std::string>> chains;  // (target, source)
    std::vector<FrameAvailability> state;
  };

  void run();
  // Takes the shared scene if it changed: the link poses and the wait start anew for its frames.
  void takeScene();
  // Whether every transform the job needs is covered, stale or missing (none still late).
  bool ready(const ScanJob& job);
  void process(const ScanJob& job);
  // The sensor's poses at the job's times; false (the scan counted as skipped) without one.
  bool sensorPoses(Sensor& sensor, const ScanJob& job, bool quiet,
                   std::vector<Eigen::Isometry3d>* poses);
  // Whether the scan goes ahead without the links in links.missing (warned about, throttled).
  bool acceptMissing(Sensor& sensor, const ScanJob& job, bool quiet, const LinkPosesAt& links);
  void castSensor(Sensor& sensor, const ScanJob& job);

  // How often the front job's transforms are checked while it waits (wall time): short against
  // any scan period, long against a TF look-up (microseconds).
  static constexpr double kPollPeriod = 0.002;  // s
  // A condition that lasts (missing link transforms) is warned about at most this often.
  static constexpr double kWarnPeriod = 5.0;  // s
  // Link names a warning lists before "... (N more)".
  static constexpr std::size_t kLinksInWarning = 5;

  Context context_;
  std::mutex mutex_;  // queue_ and stop_
  std::condition_variable wake_;
  ScanQueue queue_;
  bool stop_ = false;
  // The cast thread's own: the scene of the job at hand, the wait for its transforms, its link
  // poses, and the link look-ups made for the scenes before it.
  std::shared_ptr<const CastScene> scene_;
  Wait wait_;
  std::unique_ptr<LinkPoses> link_poses_;
  std::uint64_t earlier_lookups_ = 0;
  std::atomic<std::uint64_t> link_lookups_{0};
  ros::WallTime last_link_warning_;
  std::thread thread_;
};

}  // namespace laser_raycast
