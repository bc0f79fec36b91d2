#include "laser_raycast/node/bag_simulation.h"

#include <ros/console.h>
#include <ros/names.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <tf2/buffer_core.h>

#include <chrono>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <utility>

#include "bag_input.h"
#include "bag_output.h"
#include "cast_thread.h"
#include "job_caster.h"
#include "param_reader.h"
#include "pose_topic.h"
#include "scan_queue.h"
#include "scene_source.h"
#include "sensor.h"
#include "tf_source.h"
#include "tf_timing.h"
#include "yaml_params.h"

namespace laser_raycast {
namespace {

using Kind = BagSimulationError::Kind;

// Frames a message lists before "... (N more)".
constexpr std::size_t kFramesInMessage = 20;

// The node waits for the first transforms for a grace period and then publishes without the links
// still missing; offline, a sensor's scans start at the first time every transform covers.
constexpr double kQuietUntilTheFirstScan = std::numeric_limits<double>::infinity();

// The node's parameters from the YAML file, checked as the node checks them; threads from the
// options if given.
NodeParams readConfig(const BagSimulationOptions& options) {
  std::string why;
  if (!ros::names::validate(options.ns, why) || options.ns.empty() || options.ns[0] != '/') {
    throw BagSimulationError(Kind::kConfig, "namespace '" + options.ns +
                                                "' is not a global name (e.g. / or " + "/robot1)" +
                                                (why.empty() ? "" : ": " + why));
  }
  XmlRpc::XmlRpcValue values;
  try {
    values = loadYamlParams(options.config);
  } catch (const YamlParamsError& e) {
    throw BagSimulationError(Kind::kConfig, e.what());
  }
  NodeParams params;
  ParamReport report;
  const std::string error = parseNodeParams(values, options.ns, &params, &report);
  for (const std::string& line : report.values) ROS_INFO_STREAM(line);
  for (const std::string& warning : report.warnings) {
    ROS_WARN_STREAM(options.config << ": " << warning);
  }
  if (!error.empty()) throw BagSimulationError(Kind::kConfig, options.config + ": " + error);
  for (std::size_t i = 0; i < params.models.size(); ++i) {
    if (params.models[i].param.empty()) continue;
    throw BagSimulationError(Kind::kConfig,
                             options.config + ": ~models[" + std::to_string(i) + "] is parameter " +
                                 params.models[i].param +
                                 (values.hasMember("models") ? "" : " (the default)") +
                                 ", but simulate_bag has no parameter server: give the URDF as "
                                 "{file: PATH} (a path or a package:// URI)");
  }
  if (options.threads >= 0) params.threads = options.threads;
  return params;
}

// Every frame the scans need a transform for, as (frame, who needs it): the links of the models
// (their root is fixed_frame or has a transform to it) and each sensor's chain.
std::map<std::string, std::string> neededFrames(
    const NodeParams& params, const core::Scene& scene,
    const std::vector<std::unique_ptr<Sensor>>& sensors) {
  std::map<std::string, std::string> needed;
  const auto need = [&](const std::string& target, const std::string& source,
                        const std::string& who) {
    if (target == source) return;
    needed.emplace(target, who);
    needed.emplace(source, who);
  };
  for (const std::string& frame : scene.frames()) {
    need(params.fixed_frame, frame, "a link of ~models");
  }
  for (const auto& sensor : sensors) {
    const auto [target, source] = sensor->tfChain();
    need(target, source, "sensor '" + sensor->name() + "'");
  }
  return needed;
}

// Refuses a bag whose TF never names a frame the scans need.
void checkFrames(const std::string& bag, const TfSurvey& survey,
                 const std::map<std::string, std::string>& needed) {
  std::vector<std::string> missing;
  for (const auto& [frame, who] : needed) {
    if (!survey.frames.count(frame)) missing.push_back("'" + frame + "' (" + who + ")");
  }
  if (missing.empty()) return;
  const std::vector<std::string> present(survey.frames.begin(), survey.frames.end());
  throw BagSimulationError(Kind::kInput,
                           bag + ": its /tf and /tf_static never name " +
                               (missing.size() == 1 ? "a frame" : "frames") +
                               " the configuration needs: " + joinFirst(missing, kFramesInMessage) +
                               "; the frames they name: " + joinFirst(present, kFramesInMessage));
}

// The pose topics of the sensors that have one, each with the PoseTopics it fills.
using PoseFeeds = std::map<std::string, std::vector<PoseTopic*>>;

// Refuses a bag without messages of a pose type on a pose topic the configuration names.
void checkPoseTopics(const rosbag::Bag& bag, const PoseFeeds& feeds) {
  for (const auto& [topic, poses] : feeds) {
    rosbag::View view(bag, rosbag::TopicQuery(topic));
    if (view.size() == 0) {
      throw BagSimulationError(Kind::kInput, bag.getFileName() +
                                                 ": has no messages on ~pose_topic " + topic +
                                                 ", where a sensor's pose is read from");
    }
    for (const rosbag::ConnectionInfo* c : view.getConnections()) {
      const std::string& type = c->datatype;
      if (type != ros::message_traits::datatype<geometry_msgs::PoseStamped>() &&
          type != ros::message_traits::datatype<geometry_msgs::PoseWithCovarianceStamped>()) {
        throw BagSimulationError(Kind::kInput,
                                 bag.getFileName() + ": " + wrongPoseType(topic, type));
      }
    }
  }
}

// The simulation of one bag: the node's sensors, queue and job caster, driven by the bag's time.
class Simulation {
 public:
  Simulation(const BagSimulationOptions& options, NodeParams params)
      : options_(options),
        params_(std::move(params)),
        tf_buffer_(ros::Duration(params_.tfCache())),
        tf_(tf_buffer_) {}

  // Throws BagSimulationError, the output removed if it was begun.
  BagSimulationResult run();

 private:
  BagSimulationResult simulate();
  // Closes and removes the output, if it was opened.
  void abandonOutput();
  void loadModels();
  void openBags();
  void makeSensors();
  // Queues every scan whose stamp the bag's time has reached, and casts those TF lets go.
  void advance(const ros::Time& now);
  void read(const rosbag::MessageInstance& m);
  BagSimulationResult result() const;

  const BagSimulationOptions& options_;
  NodeParams params_;
  core::Scene scene_;
  std::vector<double> reflectivity_;
  std::vector<char> reflectivity_fixed_;
  rosbag::Bag in_, out_;
  bool writing_ = false;
  TfSurvey survey_;
  tf2::BufferCore tf_buffer_;
  TfSource tf_;
  std::vector<std::unique_ptr<Sensor>> sensors_;
  std::vector<const BagOutput*> outputs_;
  PoseFeeds pose_feeds_;
  std::unique_ptr<JobCaster> caster_;
  ScanQueue queue_;
  std::vector<ros::Time> next_stamp_;  // per sensor, the next on its period's grid
  std::chrono::steady_clock::time_point start_;
};

void Simulation::loadModels() {
  // Every model is a file (readConfig refuses parameters).
  const auto no_param = [](const std::string&, std::string*, std::string*) { return false; };
  const std::string error = loadScene(params_, no_param, &scene_, &reflectivity_);
  if (!error.empty()) throw BagSimulationError(Kind::kScene, error);
  reflectivity_fixed_ = labelReflectivityFixed(params_, scene_);
}

void Simulation::openBags() {
  try {
    in_.open(options_.input, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    throw BagSimulationError(Kind::kInput,
                             options_.input + ": cannot be read as a bag (" + e.what() + ")");
  }
  survey_ = surveyTf(in_);
  std::error_code error;
  if (std::filesystem::equivalent(options_.input, options_.output, error)) {
    throw BagSimulationError(Kind::kConfig, options_.output + ": is the input bag; give another");
  }
  try {
    out_.open(options_.output, rosbag::bagmode::Write);
  } catch (const rosbag::BagException& e) {
    throw BagSimulationError(Kind::kOutput,
                             options_.output + ": cannot be written (" + e.what() + ")");
  }
  writing_ = true;
}

void Simulation::makeSensors() {
  for (const SensorParams& s : params_.sensors) {
    std::unique_ptr<PoseTopic> poses;
    if (!s.pose_topic.empty()) {
      const std::string topic = ros::names::resolve(options_.ns, s.pose_topic, false);
      poses = std::make_unique<PoseTopic>(topic, params_.fixed_frame, ros::Duration(s.pose_timeout),
                                          ros::Duration(params_.poseHistory(s)));
      pose_feeds_[topic].push_back(poses.get());
    }
    auto output = std::make_unique<BagOutput>(&out_, s, options_.ns);
    outputs_.push_back(output.get());
    sensors_.push_back(std::make_unique<Sensor>(s, params_.fixed_frame, kQuietUntilTheFirstScan,
                                                params_.threads, std::move(output),
                                                std::move(poses)));
  }
  JobCaster::Context context;
  context.scene = &scene_;
  context.reflectivity = &reflectivity_;
  context.reflectivity_fixed = &reflectivity_fixed_;
  context.tf = &tf_;
  context.sensors = &sensors_;
  context.fixed_frame = params_.fixed_frame;
  context.tf_timeout = ros::Duration(params_.tf_timeout);
  caster_ = std::make_unique<JobCaster>(context);
  queue_.setCapacity(castQueueCapacity(sensors_, params_.tf_timeout));
  // The first scan time of each sensor: the first multiple of its period after the bag's first
  // transform, as the node's timer would find it.
  for (const auto& sensor : sensors_) {
    next_stamp_.push_back(survey_.first + untilNextMultiple(survey_.first, sensor->period()));
  }
}

void Simulation::advance(const ros::Time& now) {
  for (std::size_t i = 0; i < sensors_.size(); ++i) {
    Sensor& sensor = *sensors_[i];
    for (; next_stamp_[i] <= now; next_stamp_[i] += sensor.period()) {
      const std::optional<ScanJob> dropped =
          queue_.push(sensor.sampleTimes(next_stamp_[i]), static_cast<int>(i));
      if (dropped) reportDropped(*dropped, queue_.size(), sensors_);
    }
  }
  while (!queue_.empty() && caster_->ready(queue_.front(), now)) {
    const ScanJob job = queue_.pop();
    caster_->cast(job);
    caster_->done(job, queue_.oldestStamp());
  }
}

void Simulation::read(const rosbag::MessageInstance& m) {
  if (isTf(m)) {
    writeToBag(&out_, m.getTopic(), m.getTime(), m);
    addTransforms(m, &tf_buffer_);
    return;
  }
  const auto feed = pose_feeds_.find(m.getTopic());
  if (feed == pose_feeds_.end()) return;
  const std::optional<PoseHistory::Entry> entry = poseEntry(m, params_.fixed_frame, m.getTime());
  if (!entry) return;  // checkPoseTopics refused other types
  for (PoseTopic* poses : feed->second) poses->add(*entry);
}

BagSimulationResult Simulation::run() {
  try {
    return simulate();
  } catch (const BagSimulationError&) {
    abandonOutput();
    throw;
  } catch (const ros::Exception& e) {
    // rosbag's, or a message that does not deserialise: the input is broken (writes throw ours).
    abandonOutput();
    throw BagSimulationError(Kind::kInput, options_.input + ": cannot be read (" + e.what() + ")");
  }
}

void Simulation::abandonOutput() {
  if (!writing_) return;
  writing_ = false;
  try {
    out_.close();
  } catch (const rosbag::BagException&) {
    // It is removed either way.
  }
  std::error_code error;
  std::filesystem::remove(options_.output, error);
}

BagSimulationResult Simulation::simulate() {
  start_ = std::chrono::steady_clock::now();
  loadModels();
  openBags();
  makeSensors();
  checkFrames(options_.input, survey_, neededFrames(params_, scene_, sensors_));
  checkPoseTopics(in_, pose_feeds_);

  std::vector<std::string> topics = kTfTopics;
  for (const auto& feed : pose_feeds_) topics.push_back(feed.first);
  rosbag::View view(in_, rosbag::TopicQuery(topics));
  BagProgress progress;
  progress.total = (survey_.last - survey_.first).toSec();
  for (const rosbag::MessageInstance& m : view) {
    read(m);
    advance(m.getTime());
    if (!options_.progress) continue;
    progress.done = (m.getTime() - survey_.first).toSec();
    progress.scans = 0;
    for (const BagOutput* output : outputs_) progress.scans += output->written();
    options_.progress(progress);
  }
  // The bag's clock stops at its last message: scans still waiting for TF are never cast.
  BagSimulationResult out = result();
  std::uint64_t written = 0;
  for (const SimulatedSensor& s : out.sensors) written += s.written;
  if (written == 0) {
    std::string why;
    for (const SimulatedSensor& s : out.sensors) {
      if (!s.last_problem.empty()) why = "; sensor '" + s.name + "': " + s.last_problem;
    }
    throw BagSimulationError(Kind::kInput, options_.input +
                                               ": not one scan could be cast: the transforms "
                                               "never covered a scan's times" +
                                               why);
  }
  try {
    out_.close();
  } catch (const rosbag::BagException& e) {
    throwWriteError(out_, e);
  }
  writing_ = false;
  out.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  return out;
}

BagSimulationResult Simulation::result() const {
  BagSimulationResult out;
  out.bag_seconds = (survey_.last - survey_.first).toSec();
  out.tf_messages = survey_.messages;
  std::vector<std::uint64_t> uncovered(sensors_.size(), 0);
  for (ScanQueue rest = queue_; !rest.empty();) {
    for (const int s : rest.pop().sensors) ++uncovered[s];
  }
  for (std::size_t i = 0; i < sensors_.size(); ++i) {
    const SensorStats stats = sensors_[i]->monitor().stats();
    SimulatedSensor s;
    s.name = sensors_[i]->name();
    s.topic = outputs_[i]->topic();
    s.written = outputs_[i]->written();
    s.before_transforms = stats.skipped.waiting;
    s.no_pose = stats.skipped.no_transform + stats.skipped.stale_pose;
    s.dropped = stats.skipped.behind;
    s.missing_links = stats.missing_links;
    s.uncovered_at_end = uncovered[i];
    s.last_problem = stats.last_skip;
    out.sensors.push_back(s);
  }
  return out;
}

}  // namespace

BagSimulationResult simulateBag(const BagSimulationOptions& options) {
  if (ros::console::set_logger_level(ROSCONSOLE_DEFAULT_NAME, options.verbose
                                                                  ? ros::console::levels::Info
                                                                  : ros::console::levels::Warn)) {
    ros::console::notifyLoggerLevelsChanged();
  }
  Simulation simulation(options, readConfig(options));
  return simulation.run();
}

}  // namespace laser_raycast
