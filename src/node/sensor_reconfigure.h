// A sensor's live parameters through dynamic_reconfigure (cfg/Raycast.cfg): range limits, min-range
// policy, intensity, noise and its seed, range bias, resolution and dropout, and the rate. A change
// applies from the next scan cast; one the sensor refuses (e.g. range_min >= range_max) is logged
// and the previous values stay. Everything else needs a restart (the .cfg says so).
#pragma once

#include <dynamic_reconfigure/server.h>
#include <laser_raycast/RaycastConfig.h>
#include <ros/ros.h>

#include <boost/thread/recursive_mutex.hpp>
#include <functional>

#include "sensor.h"

namespace laser_raycast {

class SensorReconfigure {
 public:
  // Serves the sensor's live parameters in namespace nh (the node's private one for the one-sensor
  // shorthand, ~<name> for an entry of ~sensors). on_rate: called after the rate changed.
  SensorReconfigure(const ros::NodeHandle& nh, Sensor* sensor, std::function<void()> on_rate);

 private:
  void onConfig(RaycastConfig& config, std::uint32_t level);
  static RaycastConfig toConfig(const Sensor::Live& live);

  Sensor* sensor_;
  std::function<void()> on_rate_;
  bool started_ = false;
  boost::recursive_mutex mutex_;
  dynamic_reconfigure::Server<RaycastConfig> server_;
};

}  // namespace laser_raycast
