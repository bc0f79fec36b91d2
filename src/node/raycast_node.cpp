#include "laser_raycast/node/raycast_node.h"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_eigen/tf2_eigen.h>

#include <algorithm>
#include <iomanip>
#include <set>
#include <sstream>

#include "laser_raycast/ScanLabels.h"
#include "laser_raycast/core/pose.h"
#include "laser_raycast/loader/package_resolver.h"
#include "laser_raycast/loader/scene_loader.h"

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

std::string joinFirst(const std::vector<std::string>& names, std::size_t n) {
  std::ostringstream s;
  for (std::size_t i = 0; i < names.size() && i < n; ++i) s << (i ? ", " : "") << names[i];
  if (names.size() > n) s << ", ... (" << names.size() - n << " more)";
  return s.str();
}

}  // namespace

RaycastNode::RaycastNode(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(std::move(nh)), pnh_(std::move(pnh)) {}

bool RaycastNode::init() {
  std::string error;
  if (!readNodeParams(pnh_, &params_, &error)) {
    ROS_FATAL_STREAM(error);
    return false;
  }
  pattern_ = std::make_unique<core::ScanPattern>(params_.scan.pattern());
  encoder_ = std::make_unique<core::ScanEncoder>(params_.scan.output);
  cast_config_ = params_.scan.castConfig();
  if (!loadScene()) return false;

  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(tf_buffer_, nh_);
  scan_pub_ = nh_.advertise<sensor_msgs::LaserScan>("scan", kPublishQueue);
  labels_pub_ = nh_.advertise<laser_raycast::ScanLabels>("scan_labels", kPublishQueue);
  if (!params_.pose_topic.empty()) {
    pose_sub_ = nh_.subscribe(params_.pose_topic, kPoseQueue, &RaycastNode::onPose, this);
  }
  timer_ = nh_.createTimer(ros::Duration(1.0 / params_.rate), &RaycastNode::onTimer, this);
  ROS_INFO_STREAM("laser_raycast: "
                  << pattern_->size() << " beams from " << pattern_->angleMin() << " to "
                  << pattern_->angleMax() << " rad at " << params_.rate << " Hz in frame '"
                  << params_.frame_id << "', sensor pose from "
                  << (params_.pose_topic.empty() ? "TF" : "topic " + params_.pose_topic)
                  << "; publishing " << scan_pub_.getTopic());
  return true;
}

bool RaycastNode::loadScene() {
  SceneLoader loader(rosPackagePath);
  std::set<std::string> all_links;
  for (std::size_t i = 0; i < params_.models.size(); ++i) {
    const ModelSource& model = params_.models[i];
    LoaderOptions options;
    options.geometry = params_.geometry;
    options.skip_bad_geometry = params_.skip_bad_geometry;
    options.tf_prefix = model.tf_prefix;
    // ~ignore_links may name links with or without this model's prefix.
    for (const std::string& link : params_.ignore_links) {
      options.ignore_links.push_back(link);
      if (!model.tf_prefix.empty() &&
          link.compare(0, model.tf_prefix.size(), model.tf_prefix) == 0) {
        options.ignore_links.push_back(link.substr(model.tf_prefix.size()));
      }
    }
    LoadedModel loaded;
    try {
      if (!model.param.empty()) {
        std::string xml;
        if (!nh_.getParam(model.param, xml)) {
          ROS_FATAL_STREAM("~models[" << i << "]: parameter " << nh_.resolveName(model.param)
                                      << " is not set or is not a string: no URDF to load");
          return false;
        }
        loaded = loader.addUrdfString(xml, "", options, &scene_,
                                      "parameter " + nh_.resolveName(model.param));
      } else {
        loaded = loader.addUrdfFile(model.file, options, &scene_);
      }
    } catch (const SceneLoadError& e) {
      // The message starts with the URDF's source (file or parameter).
      ROS_FATAL_STREAM(e.what() << (params_.skip_bad_geometry
                                        ? ""
                                        : " (set ~skip_bad_geometry to skip bad elements)"));
      return false;
    }
    for (const std::string& warning : loaded.warnings) {
      ROS_WARN_STREAM("skipped: " << warning);
    }
    for (const auto& link : loaded.link_frames) all_links.insert(link.first);
    ROS_INFO(
        "model '%s' (%s): %zu links, %zu bodies, %zu triangles; loaded in %.3f s, BVHs built "
        "in %.3f s",
        loaded.name.c_str(), model.describe().c_str(), loaded.links, loaded.bodies,
        loaded.triangles, loaded.load_seconds, loaded.bvh_build_seconds);
  }
  for (const std::string& link : params_.ignore_links) {
    bool found = all_links.count(link) > 0;
    for (const ModelSource& model : params_.models)
      found |= all_links.count(model.tf_prefix + link) > 0;
    if (!found) ROS_WARN_STREAM("~ignore_links: no model has a link '" << link << "'");
  }

  // Reflectivity per label (labels are the links, with their TF prefix).
  const auto& labels = scene_.labels();
  for (const auto& entry : params_.reflectivity) {
    if (std::find(labels.begin(), labels.end(), entry.first) == labels.end()) {
      ROS_FATAL_STREAM("~reflectivity names link '"
                       << entry.first
                       << "', which has no geometry in any model (links "
                          "with geometry: "
                       << joinFirst(labels, kLinksInError) << ")");
      return false;
    }
  }
  reflectivity_by_label_.clear();
  for (const std::string& label : labels) {
    const auto it = params_.reflectivity.find(label);
    reflectivity_by_label_.push_back(
        it != params_.reflectivity.end() ? it->second : params_.default_reflectivity);
  }
  if (scene_.bodies().empty()) {
    ROS_WARN("the scene has no geometry: every beam will report +Inf");
  }
  return true;
}

bool RaycastNode::lookup(const std::string& target, const std::string& frame,
                         const ros::Time& stamp, const ros::Time& deadline, Eigen::Isometry3d* pose,
                         std::string* error) {
  if (frame == target) {
    pose->setIdentity();
    return true;
  }
  const ros::Duration timeout = std::max(ros::Duration(0), deadline - ros::Time::now());
  try {
    *pose = tf2::transformToEigen(tf_buffer_.lookupTransform(target, frame, stamp, timeout));
    return true;
  } catch (const tf2::TransformException& e) {
    *error = e.what();
    return false;
  }
}

bool RaycastNode::sensorPose(const ros::Time& stamp, const ros::Time& deadline,
                             Eigen::Isometry3d* pose, std::string* why, std::string* detail) {
  // Without a pose topic the sensor is a TF frame like any other; with one, the topic gives the
  // pose of pose_frame, and TF (usually a static mount) the sensor relative to it.
  Eigen::Isometry3d world_from_pose_frame = Eigen::Isometry3d::Identity();
  std::string pose_frame = params_.fixed_frame;
  if (!params_.pose_topic.empty()) {
    std::lock_guard<std::mutex> lock(pose_mutex_);
    if (!topic_pose_) {
      *why = "no pose received yet on " + pose_sub_.getTopic();
      return false;
    }
    world_from_pose_frame = *topic_pose_;
    pose_frame = params_.pose_frame.empty() ? params_.frame_id : params_.pose_frame;
  }
  Eigen::Isometry3d pose_frame_from_sensor;
  if (!lookup(pose_frame, params_.frame_id, stamp, deadline, &pose_frame_from_sensor, detail)) {
    std::ostringstream s;
    s << "no transform from '" << params_.frame_id << "' to '" << pose_frame
      << "' at t = " << std::fixed << std::setprecision(3) << stamp.toSec();
    *why = s.str();
    return false;
  }
  *pose = world_from_pose_frame * pose_frame_from_sensor;
  return true;
}

bool RaycastNode::linkPoses(const ros::Time& stamp, const ros::Time& deadline, bool waiting) {
  std::vector<std::string> missing;
  std::string first_error;
  core::resolveFramePoses(
      scene_,
      [&](const std::string& frame, Eigen::Isometry3d& pose) {
        std::string error;
        if (lookup(params_.fixed_frame, frame, stamp, deadline, &pose, &error)) return true;
        missing.push_back(frame);
        if (first_error.empty()) first_error = error;
        return false;
      },
      &frame_poses_);
  if (missing.empty()) return true;
  if (waiting) {
    ROS_DEBUG("waiting for the first transforms: %zu link frames have none yet (%s)",
              missing.size(), joinFirst(missing, kLinksInWarning).c_str());
    return false;
  }
  missing_link_poses_ += missing.size();
  ROS_WARN_THROTTLE(kWarnPeriod,
                    "%zu of %zu link frames have no transform to '%s' at t = %.3f; their "
                    "geometry is skipped this scan (%lu skipped so far): %s (%s)",
                    missing.size(), scene_.frames().size(), params_.fixed_frame.c_str(),
                    stamp.toSec(), static_cast<unsigned long>(missing_link_poses_),
                    joinFirst(missing, kLinksInWarning).c_str(), first_error.c_str());
  return true;  // cast without those links
}

void RaycastNode::onPose(const topic_tools::ShapeShifter::ConstPtr& msg) {
  const std::string& type = msg->getDataType();
  std_msgs::Header header;
  geometry_msgs::Pose pose_msg;
  if (type == "geometry_msgs/PoseStamped") {
    const auto m = msg->instantiate<geometry_msgs::PoseStamped>();
    header = m->header;
    pose_msg = m->pose;
  } else if (type == "geometry_msgs/PoseWithCovarianceStamped") {
    const auto m = msg->instantiate<geometry_msgs::PoseWithCovarianceStamped>();
    header = m->header;
    pose_msg = m->pose.pose;
  } else {
    ROS_ERROR_THROTTLE(kErrorPeriod,
                       "~pose_topic %s carries %s; expected geometry_msgs/PoseStamped or "
                       "geometry_msgs/PoseWithCovarianceStamped (message ignored)",
                       pose_sub_.getTopic().c_str(), type.c_str());
    return;
  }
  Eigen::Isometry3d pose;
  if (!poseFromMsg(pose_msg, &pose)) {
    ROS_WARN_THROTTLE(kWarnPeriod,
                      "pose on %s is not finite or its quaternion is not unit length: ignored",
                      pose_sub_.getTopic().c_str());
    return;
  }
  // A pose given in another frame is brought into fixed_frame with TF at its own stamp.
  if (!header.frame_id.empty() && header.frame_id != params_.fixed_frame) {
    try {
      pose = tf2::transformToEigen(
                 tf_buffer_.lookupTransform(params_.fixed_frame, header.frame_id, header.stamp)) *
             pose;
    } catch (const tf2::TransformException& e) {
      ROS_WARN_THROTTLE(kWarnPeriod,
                        "pose on %s is in '%s', which has no transform to '%s': ignored (%s)",
                        pose_sub_.getTopic().c_str(), header.frame_id.c_str(),
                        params_.fixed_frame.c_str(), e.what());
      return;
    }
  }
  std::lock_guard<std::mutex> lock(pose_mutex_);
  topic_pose_ = pose;
}

void RaycastNode::onTimer(const ros::TimerEvent&) {
  const ros::Time stamp = ros::Time::now();
  if (stamp.isZero()) return;  // simulated time has not started
  if (first_attempt_.isZero()) first_attempt_ = stamp;
  // Until the first scan, for a grace period, missing transforms are waited for without warnings.
  const bool waiting = scans_ == 0 && stamp - first_attempt_ < ros::Duration(kTfGracePeriod);
  const ros::Time deadline = stamp + ros::Duration(params_.tf_timeout);

  Eigen::Isometry3d world_from_sensor;
  std::string why, detail;
  if (!sensorPose(stamp, deadline, &world_from_sensor, &why, &detail)) {
    ++scans_skipped_;
    if (waiting) {
      ROS_DEBUG_STREAM("waiting for the first transforms: " << why);
    } else {
      ROS_WARN_THROTTLE(kWarnPeriod, "%s: scan skipped (%lu of %lu so far%s%s)", why.c_str(),
                        static_cast<unsigned long>(scans_skipped_),
                        static_cast<unsigned long>(scans_ + scans_skipped_),
                        detail.empty() ? "" : "; ", detail.c_str());
    }
    return;
  }
  if (!linkPoses(stamp, deadline, waiting)) {
    ++scans_skipped_;
    return;
  }
  if (scans_ == 0 && scans_skipped_ > 0) {
    ROS_INFO(
        "first scan at t = %.3f, %.3f s after the first attempt: %lu skipped while waiting "
        "for transforms",
        stamp.toSec(), (stamp - first_attempt_).toSec(),
        static_cast<unsigned long>(scans_skipped_));
  }

  const core::ScanResult& result =
      caster_.cast(scene_, frame_poses_, world_from_sensor, *pattern_, cast_config_);
  encoder_->encode(scene_, result, reflectivity_by_label_, &encoded_);

  sensor_msgs::LaserScan scan;
  scan.header.stamp = stamp;  // every beam is cast at this instant
  scan.header.frame_id = params_.frame_id;
  scan.angle_min = static_cast<float>(pattern_->angleMin());
  scan.angle_max = static_cast<float>(pattern_->angleMax());
  scan.angle_increment = static_cast<float>(pattern_->angleIncrement());
  scan.time_increment = 0.0f;  // instantaneous: all beams share the stamp
  scan.scan_time = static_cast<float>(1.0 / params_.rate);
  scan.range_min = static_cast<float>(params_.scan.output.range_min);
  scan.range_max = static_cast<float>(params_.scan.output.range_max);
  scan.ranges = encoded_.ranges;
  scan.intensities = encoded_.intensities;
  scan_pub_.publish(scan);

  if (labels_pub_.getNumSubscribers() > 0) {
    laser_raycast::ScanLabels labels;
    labels.header = scan.header;
    labels.link_names = scene_.labels();
    labels.labels.assign(encoded_.labels.begin(), encoded_.labels.end());
    labels_pub_.publish(labels);
  }
  ++scans_;
}

}  // namespace laser_raycast
