// The poses a pose topic has given, kept for a few seconds so that each scan takes the sensor pose
// at its own time: interpolated between the messages around it, or the newest one held for at most
// ~pose_timeout. A non-finite message says the pose is unknown from its stamp on. Pure (no ROS
// communication), so unit tests check it directly.
#pragma once

#include <ros/time.h>

#include <Eigen/Geometry>
#include <cstddef>
#include <deque>
#include <string>

namespace laser_raycast {

class PoseHistory {
 public:
  struct Entry {
    ros::Time stamp;
    std::string frame;  // the frame the pose is given in (header.frame_id)
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    bool valid = true;  // false: the message was not finite (the pose is unknown from stamp on)
  };

  enum class Status {
    kOk,       // a pose (a, b, s below)
    kNone,     // nothing received yet
    kStale,    // the newest pose at or before t is older than the timeout (or none is before t)
    kInvalid,  // the pose at t is unknown: a non-finite message at or before t is the latest
  };

  // What the pose at a time is made of: a and b (equal when held), s the fraction from a to b.
  struct Query {
    Status status = Status::kNone;
    double age = 0;  // s from the pose used (the newest at or before t) to t
    Entry a, b;
    double s = 0;
  };

  // keep: how far back from the newest message entries are kept (s); max_entries bounds memory
  // whatever the publisher's rate.
  PoseHistory(ros::Duration keep, std::size_t max_entries);

  // Adds a message; one with the stamp of an existing entry replaces it, an older one is inserted
  // in order.
  void add(const Entry& entry);
  // The pose at time t: between the entries around t, or the newest held if t is after it; stale
  // if the newest entry at or before t is more than `timeout` older than t.
  Query at(const ros::Time& t, const ros::Duration& timeout) const;

  bool empty() const { return entries_.empty(); }
  std::size_t size() const { return entries_.size(); }
  const Entry& newest() const { return entries_.back(); }

 private:
  ros::Duration keep_;
  std::size_t max_entries_;
  std::deque<Entry> entries_;  // by stamp, ascending
};

}  // namespace laser_raycast
