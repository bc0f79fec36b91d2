// The ROS wrapper: parameters, scene loading, TF and pose input, timers, and the LaserScan and
// label publishers around the core. main() and the nodelet only construct it and call init().
#pragma once

#include <ros/ros.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>
#include <topic_tools/shape_shifter.h>

#include <Eigen/Geometry>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/scan_encoder.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/scene.h"
#include "laser_raycast/node/node_params.h"

namespace laser_raycast {

class RaycastNode {
 public:
  // TF publishers usually start with or after the node (robot_state_publisher, a driver, a
  // simulator), so for this long after the first scan attempt, until the first scan, scans that
  // lack a transform are skipped without a warning. ROS time, like the scan timer: under
  // use_sim_time it follows /clock, as the TF publishers do. Then missing transforms are warned
  // about.
  static constexpr double kTfGracePeriod = 5.0;  // s

  RaycastNode(ros::NodeHandle nh, ros::NodeHandle pnh);

  // Reads and validates the parameters, loads the scene, and starts publishing. Returns false after
  // logging (ROS_FATAL) what is wrong: a bad parameter, a missing URDF, or bad geometry.
  bool init();

 private:
  bool loadScene();
  void onTimer(const ros::TimerEvent& event);
  void onPose(const topic_tools::ShapeShifter::ConstPtr& msg);
  // The pose of frame_id in fixed_frame for this scan; false if unknown, with what is missing in
  // *why and TF's message (if any) in *detail.
  bool sensorPose(const ros::Time& stamp, const ros::Time& deadline, Eigen::Isometry3d* pose,
                  std::string* why, std::string* detail);
  // The link poses for this scan into frame_poses_. Links without a transform are left out with a
  // throttled warning; while `waiting` (for the first transforms) the scan is skipped quietly
  // instead (false).
  bool linkPoses(const ros::Time& stamp, const ros::Time& deadline, bool waiting);
  // The pose of `frame` in `target` from TF at stamp, waiting until deadline at most (identity if
  // they are the same frame); false with the reason in *error.
  bool lookup(const std::string& target, const std::string& frame, const ros::Time& stamp,
              const ros::Time& deadline, Eigen::Isometry3d* pose, std::string* error);

  // A condition that lasts (missing transforms, no pose yet, bad pose messages) is warned about at
  // most this often: every scan (10 to 100 Hz) would flood the log.
  static constexpr double kWarnPeriod = 5.0;  // s
  // A pose topic of the wrong message type is a set-up error that does not go away by itself.
  static constexpr double kErrorPeriod = 10.0;  // s
  // Scans queued for a slow subscriber before the oldest is dropped (1 s at the default rate).
  static constexpr std::uint32_t kPublishQueue = 10;
  // Pose messages queued for the callback; only the latest is used.
  static constexpr std::uint32_t kPoseQueue = 10;
  // Link names a message lists before "... (N more)": a few in the repeated warning about missing
  // transforms, more in the one-off error about an unknown reflectivity link.
  static constexpr std::size_t kLinksInWarning = 5, kLinksInError = 20;

  ros::NodeHandle nh_, pnh_;
  NodeParams params_;
  core::Scene scene_;
  std::unique_ptr<core::ScanPattern> pattern_;
  core::CastConfig cast_config_;
  core::Caster caster_;
  std::unique_ptr<core::ScanEncoder> encoder_;
  std::vector<double> reflectivity_by_label_;
  core::FramePoses frame_poses_;
  core::EncodedScan encoded_;

  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  ros::Publisher scan_pub_, labels_pub_;
  ros::Subscriber pose_sub_;
  ros::Timer timer_;

  // The latest pose from pose_topic (of pose_frame, in fixed_frame), guarded for multi-threaded
  // nodelet managers.
  std::mutex pose_mutex_;
  std::optional<Eigen::Isometry3d> topic_pose_;

  // Reported in the throttled warnings.
  std::uint64_t scans_ = 0, scans_skipped_ = 0, missing_link_poses_ = 0;
  ros::Time first_attempt_;  // the first timer tick with a non-zero time
};

}  // namespace laser_raycast
