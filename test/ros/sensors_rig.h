// The rig of the sensors rostest (node_sensors.test, nodelet_sensors.test; test_node_sensors.cpp):
// the sensors' transforms in the closed room of test/data/sensors_room.urdf (sensors_room.h: its
// distances worked out by hand), the static ones and the spinner's path, what the node publishes,
// and reading its diagnostics.
#pragma once

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "sensors_room.h"

namespace laser_raycast_test {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Ranges are floats: 1e-7 relative, well below this at 10 m.
constexpr double kTolerance = 1e-4;  // m
// The spinner's path (node_sensors.test): x = -3 + v (t - t0) along a 6 s ramp, then again.
constexpr double kSpeed = 1.0;  // m/s
constexpr double kRamp = 6.0;   // s

inline geometry_msgs::TransformStamped transform(const ros::Time& stamp, const std::string& child,
                                                 const Eigen::Vector3d& t, double yaw) {
  geometry_msgs::TransformStamped m;
  m.header.stamp = stamp;
  m.header.frame_id = "world";
  m.child_frame_id = child;
  m.transform.translation.x = t.x();
  m.transform.translation.y = t.y();
  m.transform.translation.z = t.z();
  m.transform.rotation.z = std::sin(yaw / 2);
  m.transform.rotation.w = std::cos(yaw / 2);
  return m;
}

// The sensor poses and what the node publishes, recorded from the spinner's threads.
class Rig {
 public:
  const Eigen::Vector3d front{0, 0, 1}, vlp{0.5, -0.3, 1.2}, sweep3d{1.0, 0.5, 1.0};
  const double vlp_yaw = 0.3, sweep3d_yaw = 0.4;

  Rig() {
    start_ = ros::Time::now();
    const ros::Time now = ros::Time::now();
    statics_.sendTransform({transform(now, "front", front, 0), transform(now, "vlp", vlp, vlp_yaw),
                            transform(now, "sweep3d", sweep3d, sweep3d_yaw),
                            transform(now, "idle", front, 0)});
    front_sub_ = nh_.subscribe("/front/scan", 100, &Rig::onFront, this);
    vlp_sub_ = nh_.subscribe("/vlp/points", 5, &Rig::onVlp, this);
    sweep3d_sub_ = nh_.subscribe("/sweep3d/points", 5, &Rig::onSweep3d, this);
    spinner_sub_ = nh_.subscribe("/spinner/scan", 20, &Rig::onSpinner, this);
    diagnostics_sub_ = nh_.subscribe("/diagnostics", 20, &Rig::onDiagnostics, this);
    timer_ = nh_.createTimer(ros::Duration(0.01), &Rig::publishSpinner, this);
  }

  // The spinner's x at time t (its y is 0, its height 1 m, no rotation).
  double spinnerX(const ros::Time& t) const {
    return -3 + kSpeed * std::fmod((t - start_).toSec(), kRamp);
  }
  // Whether [from, to] lies within one ramp of the path, away from its ends (the TF samples
  // around a jump are interpolated across it).
  bool withinOneRamp(const ros::Time& from, const ros::Time& to) const {
    const double a = (from - start_).toSec() - 0.05, b = (to - start_).toSec() + 0.05;
    return a > 0 && std::floor(a / kRamp) == std::floor(b / kRamp);
  }

  // Waits (wall time) for the first message in `slot` satisfying ok; nullptr after `seconds`.
  template <class M, class F>
  typename M::ConstPtr waitFor(std::vector<typename M::ConstPtr>* slot, F ok, double seconds) {
    const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(seconds);
    std::size_t seen = 0;
    while (ros::ok() && ros::WallTime::now() < give_up) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        for (; seen < slot->size(); ++seen) {
          if (ok(*(*slot)[seen])) return (*slot)[seen];
        }
      }
      ros::WallDuration(0.01).sleep();
    }
    return nullptr;
  }
  // Waits (wall time) for the first `count` messages in `slot` satisfying ok; fewer after
  // `seconds`.
  template <class M, class F>
  std::vector<typename M::ConstPtr> waitForSome(std::vector<typename M::ConstPtr>* slot, F ok,
                                                std::size_t count, double seconds) {
    std::vector<typename M::ConstPtr> found;
    const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(seconds);
    std::size_t seen = 0;
    while (ros::ok() && ros::WallTime::now() < give_up) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        for (; seen < slot->size(); ++seen) {
          if (ok(*(*slot)[seen])) found.push_back((*slot)[seen]);
          if (found.size() == count) return found;
        }
      }
      ros::WallDuration(0.01).sleep();
    }
    return found;
  }

  std::vector<sensor_msgs::LaserScan::ConstPtr> front_scans, spinner_scans;
  std::vector<sensor_msgs::PointCloud2::ConstPtr> clouds, sweep3d_clouds;
  std::vector<diagnostic_msgs::DiagnosticArray::ConstPtr> diagnostics;

 private:
  template <class M>
  void store(std::vector<M>* slot, const M& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    slot->push_back(m);
  }
  void onFront(const sensor_msgs::LaserScan::ConstPtr& m) { store(&front_scans, m); }
  void onSpinner(const sensor_msgs::LaserScan::ConstPtr& m) { store(&spinner_scans, m); }
  void onVlp(const sensor_msgs::PointCloud2::ConstPtr& m) { store(&clouds, m); }
  void onSweep3d(const sensor_msgs::PointCloud2::ConstPtr& m) { store(&sweep3d_clouds, m); }
  void onDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
    store(&diagnostics, m);
  }
  void publishSpinner(const ros::TimerEvent&) {
    const ros::Time now = ros::Time::now();
    broadcaster_.sendTransform(transform(now, "spinner", {spinnerX(now), 0, 1}, 0));
  }

  ros::NodeHandle nh_;
  ros::Time start_;
  tf2_ros::StaticTransformBroadcaster statics_;
  tf2_ros::TransformBroadcaster broadcaster_;
  ros::Subscriber front_sub_, vlp_sub_, sweep3d_sub_, spinner_sub_, diagnostics_sub_;
  ros::Timer timer_;
  std::mutex mutex_;
};

// The status whose name ("<node>: <task>") ends in `suffix`, or nullptr.
inline const diagnostic_msgs::DiagnosticStatus* statusIn(
    const diagnostic_msgs::DiagnosticArray& array, const std::string& suffix) {
  for (const auto& s : array.status) {
    if (s.name.size() >= suffix.size() &&
        s.name.compare(s.name.size() - suffix.size(), suffix.size(), suffix) == 0) {
      return &s;
    }
  }
  return nullptr;
}

// The status of `name` in the newest diagnostics that have it.
inline const diagnostic_msgs::DiagnosticStatus* findStatus(
    const std::vector<diagnostic_msgs::DiagnosticArray::ConstPtr>& arrays,
    const std::string& suffix) {
  for (auto a = arrays.rbegin(); a != arrays.rend(); ++a) {
    if (const auto* s = statusIn(**a, suffix)) return s;
  }
  return nullptr;
}

inline std::map<std::string, std::string> values(const diagnostic_msgs::DiagnosticStatus& s) {
  std::map<std::string, std::string> out;
  for (const auto& kv : s.values) out[kv.key] = kv.value;
  return out;
}

// A diagnostics value as a number (NaN with a failure if absent).
inline double number(const diagnostic_msgs::DiagnosticStatus& s, const std::string& key) {
  for (const auto& kv : s.values) {
    if (kv.key == key) return std::stod(kv.value);
  }
  ADD_FAILURE() << s.name << ": no '" << key << "'";
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace laser_raycast_test
