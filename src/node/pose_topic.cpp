#include "pose_topic.h"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "laser_raycast/core/pose_samples.h"

namespace laser_raycast {
namespace {

// A message's quaternion may be this far from unit length (relative) and is normalised; farther off
// is a bad message, not rounding: poses written with 3 or 4 decimals are within 0.1%.
constexpr double kQuaternionNormTolerance = 0.01;

// A pose from a message: finite, with a quaternion near unit length.
bool poseFromMsg(const geometry_msgs::Pose& msg, Eigen::Isometry3d* pose) {
  const Eigen::Vector3d t(msg.position.x, msg.position.y, msg.position.z);
  Eigen::Quaterniond q(msg.orientation.w, msg.orientation.x, msg.orientation.y, msg.orientation.z);
  const double norm = q.norm();
  if (!t.allFinite() || !(std::abs(norm - 1.0) <= kQuaternionNormTolerance)) return false;
  q.coeffs() /= norm;
  pose->setIdentity();
  pose->linear() = q.toRotationMatrix();
  pose->translation() = t;
  return true;
}

std::string seconds(double s) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << s;
  return out.str();
}

}  // namespace

PoseTopic::PoseTopic(std::string topic, std::string fixed_frame, ros::Duration timeout,
                     ros::Duration keep)
    : topic_(std::move(topic)),
      fixed_frame_(std::move(fixed_frame)),
      timeout_(timeout),
      history_(keep, kMaxEntries) {}

void PoseTopic::add(const PoseHistory::Entry& entry) {
  std::lock_guard<std::mutex> lock(mutex_);
  history_.add(entry);
}

PoseHistory::Entry poseEntry(const std_msgs::Header& header, const geometry_msgs::Pose& pose,
                             const std::string& fixed_frame, const ros::Time& received) {
  PoseHistory::Entry entry;
  entry.stamp = header.stamp.isZero() ? received : header.stamp;
  entry.frame = header.frame_id.empty() ? fixed_frame : header.frame_id;
  entry.valid = poseFromMsg(pose, &entry.pose);
  return entry;
}

std::string wrongPoseType(const std::string& topic, const std::string& type) {
  return "~pose_topic " + topic + " carries " + type + "; expected " +
         ros::message_traits::datatype<geometry_msgs::PoseStamped>() + " or " +
         ros::message_traits::datatype<geometry_msgs::PoseWithCovarianceStamped>();
}

bool PoseTopic::inFixedFrame(const PoseHistory::Entry& e, const TfSource& tf,
                             Eigen::Isometry3d* pose, std::string* why,
                             std::uint64_t* tf_failures) const {
  Eigen::Isometry3d fixed_from_frame;
  std::string error;
  if (!tf.lookup(fixed_frame_, e.frame, e.stamp, &fixed_from_frame, &error)) {
    ++*tf_failures;
    *why = "the pose on " + topic_ + " is in '" + e.frame + "', which has no transform to '" +
           fixed_frame_ + "' at its stamp (" + error + ")";
    return false;
  }
  *pose = fixed_from_frame * e.pose;
  return true;
}

bool PoseTopic::poseAt(const ros::Time& t, const TfSource& tf, Eigen::Isometry3d* pose,
                       std::string* why, std::uint64_t* tf_failures) {
  PoseHistory::Query q;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    q = history_.at(t, timeout_);
  }
  switch (q.status) {
    case PoseHistory::Status::kNone:
      *why = "no pose received yet on " + topic_;
      return false;
    case PoseHistory::Status::kInvalid:
      *why = "the pose on " + topic_ + " at t = " + seconds(q.a.stamp.toSec()) +
             " is not finite or its quaternion is not unit length";
      return false;
    case PoseHistory::Status::kStale:
      *why = "the pose on " + topic_ + " is " + seconds(q.age) +
             " s old at the scan's time t = " + seconds(t.toSec()) + " (~pose_timeout " +
             seconds(timeout_.toSec()) + " s)";
      return false;
    case PoseHistory::Status::kOk:
      break;
  }
  Eigen::Isometry3d a, b;
  if (!inFixedFrame(q.a, tf, &a, why, tf_failures) ||
      !inFixedFrame(q.b, tf, &b, why, tf_failures)) {
    return false;
  }
  *pose = core::interpolatePose(a, b, q.s);
  return true;
}

PoseSubscriber::PoseSubscriber(ros::NodeHandle& nh, const std::string& topic, PoseTopic* poses)
    : poses_(poses) {
  sub_ = nh.subscribe(topic, kQueue, &PoseSubscriber::onPose, this);
}

void PoseSubscriber::onPose(const topic_tools::ShapeShifter::ConstPtr& msg) {
  const std::optional<PoseHistory::Entry> entry =
      poseEntry(*msg, poses_->fixedFrame(), ros::Time::now());
  if (entry) {
    poses_->add(*entry);
    return;
  }
  const ros::WallTime now = ros::WallTime::now();
  if (last_type_error_.isZero() || (now - last_type_error_).toSec() >= kErrorPeriod) {
    last_type_error_ = now;
    ROS_ERROR_STREAM(wrongPoseType(sub_.getTopic(), msg->getDataType()) << " (message ignored)");
  }
}

}  // namespace laser_raycast
