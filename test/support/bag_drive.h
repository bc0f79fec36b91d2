// The drive of simulate_bag's tests (test_simulate_bag.cpp, simulate_bag_node.test): the robot of
// test/data/bag_robot.urdf driving through the room of sensors_room.urdf at a constant speed while
// turning at a constant rate, so that its pose at any time, and every range its sensors
// (simulate_bag_test.yaml) report, is worked out by hand; its transforms as TF messages; and the
// messages of a bag read back by topic and stamp.
#pragma once

#include <geometry_msgs/TransformStamped.h>
#include <ros/time.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <tf2_msgs/TFMessage.h>

#include <Eigen/Geometry>
#include <boost/make_shared.hpp>
#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace laser_raycast_test {

// base_link in world: from (-2, 0.5, 0), heading +x, at kSpeed along its heading's start direction
// (+x) and turning about z at kTurn; TF interpolates such a motion exactly between samples.
struct Drive {
  static constexpr double kSpeed = 0.8;  // m/s
  static constexpr double kTurn = 0.2;   // rad/s
  ros::Time start;

  Eigen::Isometry3d base(const ros::Time& t) const {
    const double s = (t - start).toSec();
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(-2 + kSpeed * s, 0.5, 0);
    pose.linear() = Eigen::AngleAxisd(kTurn * s, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    return pose;
  }
};

// A sensor frame's pose on base_link: x, z and yaw.
struct Mount {
  std::string frame;
  double x, z, yaw;

  Eigen::Isometry3d pose() const {
    Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
    p.translation() = Eigen::Vector3d(x, 0, z);
    p.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    return p;
  }
};

// laser: on the mast, 0.2 m ahead, 1 m up; bumper: 0.15 m behind the body's back face (x = -0.3)
// at 0.15 m, looking at it; lidar: 1.2 m up, turned a little.
inline const std::vector<Mount>& mounts() {
  static const std::vector<Mount> m = {
      {"laser", 0.2, 1.0, 0.0}, {"bumper", -0.45, 0.15, 0.0}, {"lidar", 0.0, 1.2, 0.3}};
  return m;
}

inline geometry_msgs::TransformStamped toMsg(const Eigen::Isometry3d& pose, const ros::Time& stamp,
                                             const std::string& parent, const std::string& child) {
  geometry_msgs::TransformStamped m;
  m.header.stamp = stamp;
  m.header.frame_id = parent;
  m.child_frame_id = child;
  m.transform.translation.x = pose.translation().x();
  m.transform.translation.y = pose.translation().y();
  m.transform.translation.z = pose.translation().z();
  const Eigen::Quaterniond q(pose.linear());
  m.transform.rotation.x = q.x();
  m.transform.rotation.y = q.y();
  m.transform.rotation.z = q.z();
  m.transform.rotation.w = q.w();
  return m;
}

// /tf_static: every mount.
inline tf2_msgs::TFMessage staticTf(const ros::Time& stamp) {
  tf2_msgs::TFMessage m;
  for (const Mount& mount : mounts()) {
    m.transforms.push_back(toMsg(mount.pose(), stamp, "base_link", mount.frame));
  }
  return m;
}

// /tf at t: base_link in world.
inline tf2_msgs::TFMessage driveTf(const Drive& drive, const ros::Time& t) {
  tf2_msgs::TFMessage m;
  m.transforms.push_back(toMsg(drive.base(t), t, "world", "base_link"));
  return m;
}

// The connection header of a latched publisher of M, as rosbag record keeps /tf_static's (a header
// given to Bag::write is written as it is, so it names the type itself).
template <class M>
boost::shared_ptr<ros::M_string> latchedHeader() {
  auto header = boost::make_shared<ros::M_string>();
  (*header)["type"] = ros::message_traits::datatype<M>();
  (*header)["md5sum"] = ros::message_traits::md5sum<M>();
  (*header)["message_definition"] = ros::message_traits::definition<M>();
  (*header)["callerid"] = "/static_publisher";
  (*header)["latching"] = "1";
  return header;
}

// The messages of type M on topic in a bag, by header stamp.
template <class M>
std::map<ros::Time, M> readBag(const std::string& path, const std::string& topic) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::map<ros::Time, M> out;
  for (const rosbag::MessageInstance& m : rosbag::View(bag, rosbag::TopicQuery(topic))) {
    const auto msg = m.instantiate<M>();
    if (msg) out[msg->header.stamp] = *msg;
  }
  return out;
}

}  // namespace laser_raycast_test
