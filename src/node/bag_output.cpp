#include "bag_output.h"

#include <ros/names.h>

#include "laser_raycast/node/bag_simulation.h"

namespace laser_raycast {

void throwWriteError(const rosbag::Bag& bag, const std::exception& e) {
  throw BagSimulationError(BagSimulationError::Kind::kOutput,
                           bag.getFileName() + ": cannot be written (" + e.what() + ")");
}

void writeToBag(rosbag::Bag* bag, const std::string& topic, const ros::Time& t,
                const rosbag::MessageInstance& msg) {
  try {
    bag->write(topic, t, msg, msg.getConnectionHeader());
  } catch (const rosbag::BagException& e) {
    throwWriteError(*bag, e);
  }
}

BagOutput::BagOutput(rosbag::Bag* bag, const SensorParams& params, const std::string& ns)
    : topic_(ros::names::resolve(ns, params.topic, false)),
      labels_topic_(ros::names::resolve(ns, params.labelsTopic(), false)),
      bag_(bag) {}

void BagOutput::send(const sensor_msgs::LaserScan& scan) {
  writeToBag(bag_, topic_, scan.header.stamp, scan);
  ++written_;
}

void BagOutput::send(const sensor_msgs::PointCloud2& cloud) {
  writeToBag(bag_, topic_, cloud.header.stamp, cloud);
  ++written_;
}

void BagOutput::send(const laser_raycast::ScanLabels& labels) {
  writeToBag(bag_, labels_topic_, labels.header.stamp, labels);
}

}  // namespace laser_raycast
