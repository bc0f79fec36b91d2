// The sensor pose from a topic (geometry_msgs/PoseStamped or PoseWithCovarianceStamped) instead of
// TF: the messages are kept (PoseHistory) and each scan takes the pose at its own time, brought
// into the fixed frame with TF at the message's stamp. A pose older than ~pose_timeout at a scan's
// time, or a non-finite one, gives no pose: the scan is skipped.
#pragma once

#include <ros/ros.h>
#include <topic_tools/shape_shifter.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <mutex>
#include <string>

#include "pose_history.h"
#include "tf_source.h"

namespace laser_raycast {

class PoseTopic {
 public:
  // Subscribes to `topic` (resolved in nh). keep: how long messages are kept (s; it must exceed
  // the oldest time a scan can still need).
  PoseTopic(ros::NodeHandle& nh, const std::string& topic, std::string fixed_frame,
            ros::Duration timeout, ros::Duration keep);

  // The pose the topic gives, in fixed_frame, at time t; false with the reason in *why (naming the
  // topic, and the pose's age if it is stale). Failed TF look-ups (a message's frame to
  // fixed_frame) are added to *tf_failures.
  bool poseAt(const ros::Time& t, const TfSource& tf, Eigen::Isometry3d* pose, std::string* why,
              std::uint64_t* tf_failures);

  std::string topic() const { return sub_.getTopic(); }

 private:
  void onPose(const topic_tools::ShapeShifter::ConstPtr& msg);
  // An entry's pose in fixed_frame (TF at its stamp if it is given in another frame).
  bool inFixedFrame(const PoseHistory::Entry& e, const TfSource& tf, Eigen::Isometry3d* pose,
                    std::string* why, std::uint64_t* tf_failures) const;

  // A wrong message type is a set-up error that does not go away by itself: reported this often.
  static constexpr double kErrorPeriod = 10.0;  // s
  // Messages queued for the callback; every one is kept in the history.
  static constexpr std::uint32_t kQueue = 100;
  // At most this many messages are kept, whatever the publisher's rate (10 s at 1 kHz).
  static constexpr std::size_t kMaxEntries = 10000;

  std::string fixed_frame_;
  ros::Subscriber sub_;
  std::mutex mutex_;  // the history is filled by the subscriber, read by the cast thread
  const ros::Duration timeout_;
  PoseHistory history_;
  ros::WallTime last_type_error_;
};

}  // namespace laser_raycast
