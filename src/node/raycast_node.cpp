#include "laser_raycast/node/raycast_node.h"

#include <algorithm>
#include <cmath>

#include "cast_thread.h"
#include "scene_source.h"
#include "sensor.h"
#include "tf_source.h"
#include "tf_timing.h"

namespace laser_raycast {

RaycastNode::RaycastNode(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(std::move(nh)), pnh_(std::move(pnh)) {}

RaycastNode::~RaycastNode() {
  report_timer_.stop();
  for (ros::Timer& t : align_timers_) t.stop();
  for (ros::Timer& t : timers_) t.stop();
  cast_thread_.reset();  // joins: nothing casts after this
}

bool RaycastNode::init() {
  std::string error;
  if (!readNodeParams(pnh_, &params_, &error)) {
    ROS_FATAL_STREAM(error);
    return false;
  }
  if (!loadScene(nh_, params_, &scene_, &reflectivity_)) return false;

  // TF and pose topics keep data as far back as the oldest time a queued scan can still need.
  double longest_scan = 0;
  for (const SensorParams& s : params_.sensors) longest_scan = std::max(longest_scan, 1.0 / s.rate);
  const double history = params_.tf_timeout + longest_scan + 1.0;
  tf_ = std::make_unique<TfSource>(nh_, ros::Duration(std::max(10.0, history)));
  std::size_t capacity = 0;
  for (const SensorParams& s : params_.sensors) {
    const double pose_history = history + std::min(s.pose_timeout, NodeParams::kMaxTfTimeout);
    sensors_.push_back(std::make_unique<Sensor>(nh_, s, params_.fixed_frame, kTfGracePeriod,
                                                ros::Duration(pose_history)));
    // Enough queued scans to wait out tf_timeout at full rate, and two to spare.
    capacity +=
        static_cast<std::size_t>(std::ceil(s.rate * (params_.tf_timeout + 1.0 / s.rate))) + 2;
  }
  CastThread::Context context;
  context.scene = &scene_;
  context.reflectivity = &reflectivity_;
  context.tf = tf_.get();
  context.sensors = &sensors_;
  context.fixed_frame = params_.fixed_frame;
  context.tf_timeout = ros::Duration(params_.tf_timeout);
  cast_thread_ = std::make_unique<CastThread>(context);
  cast_thread_->setCapacity(capacity);

  align_timers_.resize(sensors_.size());
  timers_.resize(sensors_.size());
  last_queued_.assign(sensors_.size(), ros::Time());
  for (std::size_t i = 0; i < sensors_.size(); ++i) {
    startTimer(static_cast<int>(i));
    const SensorParams& s = sensors_[i]->params();
    ROS_INFO_STREAM("laser_raycast: " << s.scan.pattern().size() << " beams from "
                                      << s.scan.fan.angle_min << " rad at " << s.rate
                                      << " Hz in frame '" << s.frame_id << "', sensor pose from "
                                      << (s.pose_topic.empty() ? "TF" : "topic " + s.pose_topic)
                                      << "; publishing " << nh_.resolveName("scan"));
  }
  report_timer_ = nh_.createTimer(ros::Duration(kReportPeriod), &RaycastNode::onReport, this);
  return true;
}

void RaycastNode::startTimer(int i) {
  // First a one-shot timer to the next multiple of the period, then the periodic timer from there:
  // scan times on the period's grid (tf_timing.h).
  const ros::Duration period = sensors_[i]->period();
  const ros::Duration delay = untilNextMultiple(ros::Time::now(), period);
  align_timers_[i] = nh_.createTimer(
      delay,
      [this, i, period](const ros::TimerEvent& event) {
        timers_[i] = nh_.createTimer(
            period, [this, i](const ros::TimerEvent& e) { onTick(i, e.current_expected); });
        onTick(i, event.current_expected);
      },
      true);
}

void RaycastNode::onTick(int i, const ros::Time& expected) {
  if (ros::Time::now().isZero()) return;  // simulated time has not started
  Sensor& sensor = *sensors_[i];
  const ros::Time stamp = nearestMultiple(expected, sensor.period());
  if (stamp <= last_queued_[i]) return;
  last_queued_[i] = stamp;
  const bool listened = sensor.hasSubscribers();
  sensor.setActive(listened, stamp);
  if (listened) cast_thread_->schedule(i, sensor.sampleTimes(stamp));
}

void RaycastNode::onReport(const ros::TimerEvent&) {
  const ros::Time now = ros::Time::now();
  for (const auto& sensor : sensors_) sensor->reportRate(now);
}

}  // namespace laser_raycast
