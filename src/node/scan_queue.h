// The scans waiting to be cast, in the order their transforms can become available: by the time of
// their last beam. Sensors due at the same times share one job. Sensors due at one stamp with
// different times (an instantaneous and a rotating scan) are separate jobs, so that neither waits
// for the other's transforms; they share their link look-ups through LinkPoses (link_poses.h).
// Bounded: when the cast thread falls behind, the oldest job is dropped rather than memory grown.
// Not thread-safe (the cast thread's owner locks around it); pure, so unit tests check it.
#pragma once

#include <ros/time.h>

#include <cstddef>
#include <deque>
#include <optional>
#include <vector>

namespace laser_raycast {

struct ScanJob {
  // The pose sample times: the first is the stamp (the first beam), the last the last beam's time
  // (the same for an instantaneous scan). Ascending.
  std::vector<ros::Time> times;
  std::vector<int> sensors;  // the sensors cast at these times, in the order they were added

  const ros::Time& stamp() const { return times.front(); }
  const ros::Time& last() const { return times.back(); }
};

class ScanQueue {
 public:
  explicit ScanQueue(std::size_t capacity = 64) : capacity_(capacity) {}

  // Adds `sensor`'s scan at `times` (non-empty, ascending): to the job with equal times if there is
  // one (once per sensor), else as a new job ordered by last time, after jobs with an equal one.
  // If that puts the queue over capacity, the job with the earliest last time is removed and
  // returned: its scans are lost.
  std::optional<ScanJob> push(const std::vector<ros::Time>& times, int sensor);

  // At least 1. A smaller capacity takes effect at the next push.
  void setCapacity(std::size_t capacity) { capacity_ = capacity > 0 ? capacity : 1; }
  std::size_t capacity() const { return capacity_; }
  bool empty() const { return jobs_.empty(); }
  std::size_t size() const { return jobs_.size(); }
  // The job whose transforms are due first. Not empty() first.
  const ScanJob& front() const { return jobs_.front(); }
  // The earliest stamp of any job (nullopt when empty): no queued scan needs a time before it.
  std::optional<ros::Time> oldestStamp() const;
  ScanJob pop();

 private:
  std::size_t capacity_;
  std::deque<ScanJob> jobs_;  // ascending by last time
};

}  // namespace laser_raycast
