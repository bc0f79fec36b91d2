// The sensor pose from a topic (geometry_msgs/PoseStamped or PoseWithCovarianceStamped) instead of
// TF: the messages are kept (PoseHistory) and each scan takes the pose at its own time, brought
// into the fixed frame with TF at the message's stamp. A pose older than ~pose_timeout at a scan's
// time, or a non-finite one, gives no pose: the scan is skipped. The node's subscriber
// (PoseSubscriber) adds the messages as they arrive, simulate_bag as it reads them from a bag.
#pragma once

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <ros/ros.h>
#include <std_msgs/Header.h>
#include <topic_tools/shape_shifter.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>

#include "pose_history.h"
#include "tf_source.h"

namespace laser_raycast {

class PoseTopic {
 public:
  // topic: its resolved name, for messages. keep: how long messages are kept (s; it must exceed
  // the oldest time a scan can still need).
  PoseTopic(std::string topic, std::string fixed_frame, ros::Duration timeout, ros::Duration keep);

  // Adds a message's pose (any thread).
  void add(const PoseHistory::Entry& entry);
  // The pose the topic gives, in fixed_frame, at time t; false with the reason in *why (naming the
  // topic, and the pose's age if it is stale). Failed TF look-ups (a message's frame to
  // fixed_frame) are added to *tf_failures.
  bool poseAt(const ros::Time& t, const TfSource& tf, Eigen::Isometry3d* pose, std::string* why,
              std::uint64_t* tf_failures);

  const std::string& topic() const { return topic_; }
  const std::string& fixedFrame() const { return fixed_frame_; }

 private:
  // An entry's pose in fixed_frame (TF at its stamp if it is given in another frame).
  bool inFixedFrame(const PoseHistory::Entry& e, const TfSource& tf, Eigen::Isometry3d* pose,
                    std::string* why, std::uint64_t* tf_failures) const;

  // At most this many messages are kept, whatever the publisher's rate (10 s at 1 kHz).
  static constexpr std::size_t kMaxEntries = 10000;

  const std::string topic_, fixed_frame_;
  std::mutex mutex_;  // the history is filled by the subscriber, read by the cast thread
  const ros::Duration timeout_;
  PoseHistory history_;
};

// The history entry of a message's header and pose: in the header's frame (fixed_frame if it has
// none), at its stamp (`received` if it has none: a publisher that leaves the stamp unset means
// "now"), invalid if the pose is not finite or its quaternion is not unit length.
PoseHistory::Entry poseEntry(const std_msgs::Header& header, const geometry_msgs::Pose& pose,
                             const std::string& fixed_frame, const ros::Time& received);

// The same from a message of either pose type, as a topic_tools::ShapeShifter or a
// rosbag::MessageInstance gives it (both tell their type and instantiate it); nullopt for another
// type.
template <class Message>
std::optional<PoseHistory::Entry> poseEntry(const Message& msg, const std::string& fixed_frame,
                                            const ros::Time& received) {
  using geometry_msgs::PoseStamped;
  using geometry_msgs::PoseWithCovarianceStamped;
  const std::string& type = msg.getDataType();
  if (type == ros::message_traits::datatype<PoseStamped>()) {
    const auto m = msg.template instantiate<PoseStamped>();
    return poseEntry(m->header, m->pose, fixed_frame, received);
  }
  if (type == ros::message_traits::datatype<PoseWithCovarianceStamped>()) {
    const auto m = msg.template instantiate<PoseWithCovarianceStamped>();
    return poseEntry(m->header, m->pose.pose, fixed_frame, received);
  }
  return std::nullopt;
}

// "~pose_topic /x carries T; expected geometry_msgs/PoseStamped or ...".
std::string wrongPoseType(const std::string& topic, const std::string& type);

// The node's subscription to a pose topic, adding each message to a PoseTopic.
class PoseSubscriber {
 public:
  // Subscribes to `topic` (resolved in nh); poses must outlive this.
  PoseSubscriber(ros::NodeHandle& nh, const std::string& topic, PoseTopic* poses);

 private:
  void onPose(const topic_tools::ShapeShifter::ConstPtr& msg);

  // A wrong message type is a set-up error that does not go away by itself: reported this often.
  static constexpr double kErrorPeriod = 10.0;  // s
  // Messages queued for the callback; every one is kept in the history.
  static constexpr std::uint32_t kQueue = 100;

  PoseTopic* poses_;
  ros::Subscriber sub_;
  ros::WallTime last_type_error_;
};

}  // namespace laser_raycast
