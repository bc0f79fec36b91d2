// Where a sensor's messages go: the node publishes them on the sensor's topics (TopicOutput);
// simulate_bag writes them into a bag. The sensor builds them; an output only sends them on.
#pragma once

#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>

#include <cstdint>
#include <string>

#include "laser_raycast/ScanLabels.h"
#include "laser_raycast/node/node_params.h"

namespace laser_raycast {

class ScanOutput {
 public:
  virtual ~ScanOutput() = default;

  // The scan topic as resolved, for the log.
  virtual std::string topic() const = 0;
  // Whether anyone takes the scans or the labels (otherwise the sensor is not cast), and the labels
  // (otherwise their message is not built).
  virtual bool wanted() const = 0;
  virtual bool labelsWanted() const = 0;

  virtual void send(const sensor_msgs::LaserScan& scan) = 0;
  virtual void send(const sensor_msgs::PointCloud2& cloud) = 0;
  virtual void send(const laser_raycast::ScanLabels& labels) = 0;
};

// The node's: a LaserScan (planar pattern) or PointCloud2 publisher on the sensor's topic, and one
// for the labels, advertised in nh.
class TopicOutput : public ScanOutput {
 public:
  TopicOutput(ros::NodeHandle& nh, const SensorParams& params);

  std::string topic() const override { return topic_; }
  bool wanted() const override;
  bool labelsWanted() const override { return labels_pub_.getNumSubscribers() > 0; }

  void send(const sensor_msgs::LaserScan& scan) override { scan_pub_.publish(scan); }
  void send(const sensor_msgs::PointCloud2& cloud) override { cloud_pub_.publish(cloud); }
  void send(const laser_raycast::ScanLabels& labels) override { labels_pub_.publish(labels); }

 private:
  // Scans queued for a slow subscriber before the oldest is dropped (1 s at the default rate).
  static constexpr std::uint32_t kPublishQueue = 10;

  std::string topic_;
  ros::Publisher scan_pub_, cloud_pub_, labels_pub_;
};

}  // namespace laser_raycast
