// The node's TF input: look-ups in a tf2 buffer, which the node's listener fills as transforms
// arrive and simulate_bag as it reads a bag. It answers two questions without ever waiting (the
// cast thread decides how long a scan waits, tf_timing.h): how recent a transform is, and what it
// is at a time.
#pragma once

#include <ros/ros.h>
#include <tf2/buffer_core.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <Eigen/Geometry>
#include <optional>
#include <string>

#include "tf_timing.h"

namespace laser_raycast {

class TfSource {
 public:
  // buffer must outlive this; it may be filled from another thread (tf2 locks it).
  explicit TfSource(const tf2::BufferCore& buffer) : buffer_(buffer) {}

  // The newest time target <- source can be looked up at (ros::Time(0): static only), nullopt if
  // TF has no chain between them (TF's message in *error).
  std::optional<ros::Time> latest(const std::string& target, const std::string& source,
                                  std::string* error) const;
  // Whether TF has a chain target <- source made of static transforms only (the same at every
  // time).
  bool isStatic(const std::string& target, const std::string& source) const {
    const std::optional<ros::Time> t = latest(target, source, nullptr);
    return t && t->isZero();
  }
  // Whether target <- source can serve a scan whose last beam is at `needed` (tf_timing.h). The
  // same frame twice is always covered.
  FrameAvailability availability(const std::string& target, const std::string& source,
                                 const ros::Time& needed, const ros::Time& now,
                                 const ros::Duration& tf_timeout) const;
  // The pose of `source` in `target` at t (identity for the same frame); false with TF's message
  // in *error.
  bool lookup(const std::string& target, const std::string& source, const ros::Time& t,
              Eigen::Isometry3d* pose, std::string* error) const;

 private:
  const tf2::BufferCore& buffer_;
};

// The node's buffer, filled by a listener on its own thread (TF arrives while scans are cast).
class TfListener {
 public:
  // cache: how far back the buffer keeps transforms (tf2's default is 10 s).
  TfListener(const ros::NodeHandle& nh, ros::Duration cache)
      : buffer_(cache), listener_(buffer_, nh), source_(buffer_) {}

  const TfSource& source() const { return source_; }

 private:
  tf2_ros::Buffer buffer_;
  tf2_ros::TransformListener listener_;
  TfSource source_;
};

}  // namespace laser_raycast
