// The node's cast thread. Sensor timers only queue scans (ScanQueue); this thread takes them in the
// order their transforms become due, waits until TF covers each one's last beam (tf_timing.h: a
// late transform is waited for up to ~tf_timeout, a dead one not at all) and casts it
// (job_caster.h: the link poses looked up once per time for every sensor due then). So a wait for
// TF never costs the timers their rate: scans queue up behind it and are cast as the transforms
// come. The scene is taken from a SharedScene at the start of each job (shared_scene.h): a scene
// swapped in meanwhile serves the next job, never part of one.
#pragma once

#include <ros/ros.h>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "job_caster.h"
#include "scan_queue.h"
#include "shared_scene.h"

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
  void run();

  // How often the front job's transforms are checked while it waits (wall time): short against
  // any scan period, long against a TF look-up (microseconds).
  static constexpr double kPollPeriod = 0.002;  // s

  std::mutex mutex_;  // queue_ and stop_
  std::condition_variable wake_;
  ScanQueue queue_;
  bool stop_ = false;
  // Takes the shared scene if it changed: a new JobCaster for it (its link poses and its wait for
  // TF start anew, for its frames).
  void takeScene();

  Context context_;
  std::shared_ptr<const CastScene> scene_;  // the one caster_ casts
  std::unique_ptr<JobCaster> caster_;       // the cast thread's own
  std::uint64_t earlier_lookups_ = 0;       // of the casters of earlier scenes
  std::atomic<std::uint64_t> link_lookups_{0};
  std::thread thread_;
};

// The cast queue's capacity for these sensors at their live rates: enough scans to wait out
// tf_timeout (s) at every sensor's rate.
std::size_t castQueueCapacity(const std::vector<std::unique_ptr<Sensor>>& sensors,
                              double tf_timeout);

// Counts the scans of a job dropped from a full queue (`queued` jobs still in it) as skipped by
// its sensors, cast behind their rate.
void reportDropped(const ScanJob& dropped, std::size_t queued,
                   const std::vector<std::unique_ptr<Sensor>>& sensors);

}  // namespace laser_raycast
