#include "pose_history.h"

#include <algorithm>

namespace laser_raycast {

PoseHistory::PoseHistory(ros::Duration keep, std::size_t max_entries)
    : keep_(keep), max_entries_(std::max<std::size_t>(max_entries, 2)) {}

void PoseHistory::add(const Entry& entry) {
  const auto later =
      std::upper_bound(entries_.begin(), entries_.end(), entry.stamp,
                       [](const ros::Time& t, const Entry& e) { return t < e.stamp; });
  if (later != entries_.begin() && std::prev(later)->stamp == entry.stamp) {
    *std::prev(later) = entry;
  } else {
    entries_.insert(later, entry);
  }
  const ros::Time newest = entries_.back().stamp;
  while (entries_.size() > max_entries_ ||
         (entries_.size() > 1 && newest - entries_.front().stamp > keep_)) {
    entries_.pop_front();
  }
}

PoseHistory::Query PoseHistory::at(const ros::Time& t, const ros::Duration& timeout) const {
  Query q;
  if (entries_.empty()) return q;
  const auto after =
      std::upper_bound(entries_.begin(), entries_.end(), t,
                       [](const ros::Time& time, const Entry& e) { return time < e.stamp; });
  if (after == entries_.begin()) {
    // Every pose is newer than t (a scan older than the history): nothing known at t.
    q.status = Status::kStale;
    q.age = (t - entries_.front().stamp).toSec();
    return q;
  }
  q.a = *std::prev(after);
  // After t the pose may have become unknown; up to then the newest known one is held.
  q.b = after == entries_.end() || !after->valid ? q.a : *after;
  q.age = (t - q.a.stamp).toSec();
  if (!q.a.valid) {
    q.status = Status::kInvalid;
  } else if (t - q.a.stamp > timeout) {
    q.status = Status::kStale;
  } else {
    q.status = Status::kOk;
    if (q.b.stamp > q.a.stamp) q.s = (t - q.a.stamp).toSec() / (q.b.stamp - q.a.stamp).toSec();
  }
  return q;
}

}  // namespace laser_raycast
