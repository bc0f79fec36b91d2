// The node's editing services and its scans as the run-time editing test (test_node_edit.cpp)
// uses them: calls to ~spawn_model, ~delete_model and ~list_models, a subscriber that keeps the
// scans and their labels, and the node's process and resident memory from /proc.
#pragma once

#include <dirent.h>
#include <gtest/gtest.h>
#include <laser_raycast/DeleteModel.h>
#include <laser_raycast/ListModels.h>
#include <laser_raycast/ScanLabels.h>
#include <laser_raycast/SpawnModel.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <mutex>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

namespace laser_raycast_test {

inline std::string service(const std::string& name) { return "/laser_raycast/" + name; }

inline geometry_msgs::Pose poseAt(double x, double y) {
  geometry_msgs::Pose pose;
  pose.position.x = x;
  pose.position.y = y;
  pose.orientation.w = 1;
  return pose;
}

class Scans {
 public:
  // Room for every scan of a long service call (the test does not spin while it waits): 50 s of
  // them at 20 Hz.
  static constexpr std::size_t kKept = 1000;
  Scans() {
    sub_ = nh_.subscribe("scan", kKept, &Scans::onScan, this);
    labels_sub_ = nh_.subscribe("scan_labels", kKept, &Scans::onLabels, this);
  }

  // The first scan stamped after t whose labels come too: the two topics connect one after the
  // other, so a scan published before the labels' connection is up never gets its labels here;
  // once a labels message has arrived, every later scan's labels follow it.
  sensor_msgs::LaserScan after(const ros::Time& t) {
    const auto scan = waitFor([&]() -> const sensor_msgs::LaserScan* {
      for (const auto& scan : scans_) {
        if (scan.header.stamp > t && !labels_.empty() &&
            scan.header.stamp >= labels_.front().header.stamp) {
          return &scan;
        }
      }
      return nullptr;
    });
    if (!scan) ADD_FAILURE() << "no scan stamped after " << t;
    return scan.value_or(sensor_msgs::LaserScan());
  }
  // The labels of the scan stamped at stamp (they come beside it on scan_labels).
  laser_raycast::ScanLabels labelsOf(const ros::Time& stamp) {
    const auto labels = waitFor([&]() -> const laser_raycast::ScanLabels* {
      for (const auto& labels : labels_) {
        if (labels.header.stamp == stamp) return &labels;
      }
      return nullptr;
    });
    if (!labels) ADD_FAILURE() << "no labels stamped " << stamp;
    return labels.value_or(laser_raycast::ScanLabels());
  }
  // Scans kept (the last kKept) stamped in [from, to].
  std::vector<sensor_msgs::LaserScan> stampedBetween(const ros::Time& from, const ros::Time& to) {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<sensor_msgs::LaserScan> found;
    std::copy_if(scans_.begin(), scans_.end(), std::back_inserter(found),
                 [&](const sensor_msgs::LaserScan& scan) {
                   return scan.header.stamp >= from && scan.header.stamp <= to;
                 });
    return found;
  }
  std::size_t count() {
    std::lock_guard<std::mutex> lock(mutex_);
    return received_;
  }

 private:
  // Spins for up to 20 s of wall time until find() (called under the lock) points at a message;
  // a copy of it, or nothing.
  template <class Find>
  auto waitFor(Find&& find) -> std::optional<std::decay_t<decltype(*find())>> {
    const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(20.0);
    while (ros::ok() && ros::WallTime::now() < give_up) {
      ros::spinOnce();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (const auto* found = find()) return *found;
      }
      ros::WallDuration(0.005).sleep();
    }
    return std::nullopt;
  }
  void onScan(const sensor_msgs::LaserScan::ConstPtr& scan) {
    std::lock_guard<std::mutex> lock(mutex_);
    scans_.push_back(*scan);
    if (scans_.size() > kKept) scans_.erase(scans_.begin());
    ++received_;
  }
  void onLabels(const laser_raycast::ScanLabels::ConstPtr& labels) {
    std::lock_guard<std::mutex> lock(mutex_);
    labels_.push_back(*labels);
    if (labels_.size() > kKept) labels_.erase(labels_.begin());
  }

  ros::NodeHandle nh_;
  ros::Subscriber sub_, labels_sub_;
  std::mutex mutex_;
  std::vector<sensor_msgs::LaserScan> scans_;
  std::vector<laser_raycast::ScanLabels> labels_;
  std::size_t received_ = 0;
};

inline laser_raycast::SpawnModel::Response spawn(const std::string& name, const std::string& urdf,
                                                 const std::string& file, double x, double y) {
  laser_raycast::SpawnModel srv;
  srv.request.name = name;
  srv.request.urdf = urdf;
  srv.request.file = file;
  srv.request.pose = poseAt(x, y);
  EXPECT_TRUE(ros::service::call(service("spawn_model"), srv));
  return srv.response;
}

inline laser_raycast::DeleteModel::Response remove(const std::string& name) {
  laser_raycast::DeleteModel srv;
  srv.request.name = name;
  EXPECT_TRUE(ros::service::call(service("delete_model"), srv));
  return srv.response;
}

inline std::vector<std::string> listed() {
  laser_raycast::ListModels srv;
  EXPECT_TRUE(ros::service::call(service("list_models"), srv));
  EXPECT_EQ(srv.response.names.size(), srv.response.sources.size());
  return srv.response.names;
}

// The node's pid, from its command line (__name:=laser_raycast); 0 if not found.
inline int nodePid() {
  DIR* proc = opendir("/proc");
  if (!proc) return 0;
  int found = 0;
  while (dirent* entry = readdir(proc)) {
    const int pid = std::atoi(entry->d_name);
    if (pid <= 0) continue;
    std::ifstream file("/proc/" + std::to_string(pid) + "/cmdline");
    std::string cmdline((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
    if (cmdline.find("laser_raycast_node") != std::string::npos &&
        cmdline.find("__name:=laser_raycast ") != std::string::npos) {
      found = pid;
    }
  }
  closedir(proc);
  return found;
}

// The resident memory of process pid (VmRSS), in kB.
inline long residentKb(int pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.compare(0, 6, "VmRSS:") == 0) return std::atol(line.c_str() + 6);
  }
  return -1;
}

}  // namespace laser_raycast_test
