// simulate_bag's input: what a bag's TF holds, surveyed before the simulation so that a bag
// without the frames a configuration needs is refused before anything is cast, and the bag's TF
// messages put into a tf2 buffer as the node's listener would.
#pragma once

#include <rosbag/bag.h>
#include <rosbag/message_instance.h>
#include <tf2/buffer_core.h>

#include <cstdint>
#include <set>
#include <string>
#include <vector>

namespace laser_raycast {

// The topics TF is read from: tf2's listener's.
extern const std::vector<std::string> kTfTopics;

// Every frame a bag's /tf and /tf_static name (parent or child, without a leading '/'), and the
// receive times of the first and the last of their messages.
struct TfSurvey {
  std::set<std::string> frames;
  ros::Time first, last;
  std::uint64_t messages = 0;
};

// Reads the bag's TF messages once. Throws BagSimulationError (kInput) if it has none, or one of
// another type than tf2_msgs/TFMessage.
TfSurvey surveyTf(const rosbag::Bag& bag);

// Whether m is on one of kTfTopics.
bool isTf(const rosbag::MessageInstance& m);

// Puts the transforms of a TF message into the buffer, static ones (on /tf_static) as static.
// Returns how many the buffer refused (tf2 logs why).
std::size_t addTransforms(const rosbag::MessageInstance& m, tf2::BufferCore* buffer);

// A frame as tf2 keeps it, without tf1's leading '/'.
std::string tfFrameName(const std::string& frame);

}  // namespace laser_raycast
