#include "sensor_output.h"

namespace laser_raycast {

TopicOutput::TopicOutput(ros::NodeHandle& nh, const SensorParams& params)
    : topic_(nh.resolveName(params.topic)) {
  if (params.planar()) {
    scan_pub_ = nh.advertise<sensor_msgs::LaserScan>(params.topic, kPublishQueue);
  } else {
    cloud_pub_ = nh.advertise<sensor_msgs::PointCloud2>(params.topic, kPublishQueue);
  }
  labels_pub_ = nh.advertise<laser_raycast::ScanLabels>(params.labelsTopic(), kPublishQueue);
}

bool TopicOutput::wanted() const {
  return scan_pub_.getNumSubscribers() > 0 || cloud_pub_.getNumSubscribers() > 0 ||
         labels_pub_.getNumSubscribers() > 0;
}

}  // namespace laser_raycast
