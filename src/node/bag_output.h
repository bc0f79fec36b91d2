// simulate_bag's output of one sensor: its messages written into the output bag, each at its
// stamp, on the topics the node would publish them on (resolved in its namespace). Every scan is
// wanted, and its labels too.
#pragma once

#include <rosbag/bag.h>
#include <rosbag/message_instance.h>

#include <cstdint>
#include <exception>
#include <string>

#include "laser_raycast/node/node_params.h"
#include "sensor_output.h"

namespace laser_raycast {

class BagOutput : public ScanOutput {
 public:
  // bag must outlive this; ns: the node's namespace (a global name).
  BagOutput(rosbag::Bag* bag, const SensorParams& params, const std::string& ns);

  std::string topic() const override { return topic_; }
  bool wanted() const override { return true; }
  bool labelsWanted() const override { return true; }

  // Each throws BagSimulationError (kOutput) if the bag cannot be written.
  void send(const sensor_msgs::LaserScan& scan) override;
  void send(const sensor_msgs::PointCloud2& cloud) override;
  void send(const laser_raycast::ScanLabels& labels) override;

  std::uint64_t written() const { return written_; }  // scans (not labels)

 private:
  const std::string topic_, labels_topic_;
  rosbag::Bag* bag_;
  std::uint64_t written_ = 0;
};

// Throws BagSimulationError (kOutput) naming the bag and what went wrong.
[[noreturn]] void throwWriteError(const rosbag::Bag& bag, const std::exception& e);

// Writes msg on topic at time t, or throws BagSimulationError (kOutput).
template <class Message>
void writeToBag(rosbag::Bag* bag, const std::string& topic, const ros::Time& t,
                const Message& msg) {
  try {
    bag->write(topic, t, msg);
  } catch (const rosbag::BagException& e) {
    throwWriteError(*bag, e);
  }
}

// The same for a copy of another bag's message, which keeps the header of its connection (so
// /tf_static stays latched when played).
void writeToBag(rosbag::Bag* bag, const std::string& topic, const ros::Time& t,
                const rosbag::MessageInstance& msg);

}  // namespace laser_raycast
