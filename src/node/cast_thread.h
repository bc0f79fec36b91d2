// The node's cast thread. Sensor timers only queue scans (ScanQueue); this thread takes them in the
// order their transforms become due, waits until TF covers each one's last beam (tf_timing.h: a
// late transform is waited for up to ~tf_timeout, a dead one not at all) and casts it
// (job_caster.h: the link poses looked up once per time for every sensor due then). So a wait for
// TF never costs the timers their rate: scans queue up behind it and are cast as the transforms
// come.
#pragma once

#include <ros/ros.h>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "job_caster.h"
#include "scan_queue.h"

namespace laser_raycast {

class CastThread {
 public:
  using Context = JobCaster::Context;

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
  JobCaster caster_;  // the cast thread's own
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
