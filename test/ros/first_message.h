// The first message on a topic, for rostests that check what a node publishes once it runs.
#pragma once

#include <ros/ros.h>

#include <mutex>
#include <string>

namespace laser_raycast_test {

// Subscribes to topic and waits up to timeout (wall time) for its first message; null if none
// came. Needs a spinner running (the rostests' AsyncSpinner).
template <class M>
typename M::ConstPtr firstMessage(const std::string& topic, double timeout) {
  ros::NodeHandle nh;
  std::mutex mutex;
  typename M::ConstPtr first;
  const ros::Subscriber sub = nh.subscribe<M>(topic, 1, [&](const typename M::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex);
    if (!first) first = m;
  });
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(timeout);
  while (ros::ok() && ros::WallTime::now() < give_up) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (first) break;
    }
    ros::WallDuration(0.01).sleep();
  }
  std::lock_guard<std::mutex> lock(mutex);
  return first;
}

}  // namespace laser_raycast_test
