#include "scan_queue.h"

#include <algorithm>
#include <utility>

namespace laser_raycast {

std::optional<ScanJob> ScanQueue::push(const std::vector<ros::Time>& times, int sensor) {
  for (ScanJob& job : jobs_) {
    if (job.times == times) {
      if (std::find(job.sensors.begin(), job.sensors.end(), sensor) == job.sensors.end()) {
        job.sensors.push_back(sensor);
      }
      return std::nullopt;
    }
  }
  const auto after =
      std::upper_bound(jobs_.begin(), jobs_.end(), times.back(),
                       [](const ros::Time& last, const ScanJob& job) { return last < job.last(); });
  jobs_.insert(after, ScanJob{times, {sensor}});
  if (jobs_.size() <= capacity_) return std::nullopt;
  ScanJob dropped = std::move(jobs_.front());
  jobs_.pop_front();
  return dropped;
}

std::optional<ros::Time> ScanQueue::oldestStamp() const {
  std::optional<ros::Time> oldest;
  for (const ScanJob& job : jobs_) {
    if (!oldest || job.stamp() < *oldest) oldest = job.stamp();
  }
  return oldest;
}

ScanJob ScanQueue::pop() {
  ScanJob job = std::move(jobs_.front());
  jobs_.pop_front();
  return job;
}

}  // namespace laser_raycast
