#include "bag_input.h"

#include <rosbag/view.h>
#include <tf2_msgs/TFMessage.h>

#include "laser_raycast/node/bag_simulation.h"

namespace laser_raycast {

const std::vector<std::string> kTfTopics = {"/tf", "/tf_static"};

namespace {

// The message's transforms; throws BagSimulationError (kInput) if it is no TF message.
tf2_msgs::TFMessage::ConstPtr transformsOf(const rosbag::MessageInstance& m,
                                           const std::string& bag) {
  const tf2_msgs::TFMessage::ConstPtr msg = m.instantiate<tf2_msgs::TFMessage>();
  if (!msg) {
    throw BagSimulationError(BagSimulationError::Kind::kInput,
                             bag + ": " + m.getTopic() + " carries " + m.getDataType() + ", not " +
                                 ros::message_traits::datatype<tf2_msgs::TFMessage>());
  }
  return msg;
}

}  // namespace

std::string tfFrameName(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

bool isTf(const rosbag::MessageInstance& m) {
  return m.getTopic() == kTfTopics[0] || m.getTopic() == kTfTopics[1];
}

TfSurvey surveyTf(const rosbag::Bag& bag) {
  TfSurvey survey;
  rosbag::View view(bag, rosbag::TopicQuery(kTfTopics));
  for (const rosbag::MessageInstance& m : view) {
    const tf2_msgs::TFMessage::ConstPtr msg = transformsOf(m, bag.getFileName());
    for (const auto& t : msg->transforms) {
      survey.frames.insert(tfFrameName(t.header.frame_id));
      survey.frames.insert(tfFrameName(t.child_frame_id));
    }
    if (survey.messages++ == 0) survey.first = m.getTime();
    survey.last = m.getTime();
  }
  if (survey.messages == 0) {
    throw BagSimulationError(BagSimulationError::Kind::kInput,
                             bag.getFileName() +
                                 ": has no messages on /tf or /tf_static, where the transforms "
                                 "of the sensors and the links are read from");
  }
  return survey;
}

std::size_t addTransforms(const rosbag::MessageInstance& m, tf2::BufferCore* buffer) {
  const bool is_static = m.getTopic() == kTfTopics[1];
  std::size_t refused = 0;
  const tf2_msgs::TFMessage::ConstPtr msg = transformsOf(m, "the input bag");
  for (const auto& t : msg->transforms) {
    refused += !buffer->setTransform(t, "simulate_bag", is_static);
  }
  return refused;
}

}  // namespace laser_raycast
