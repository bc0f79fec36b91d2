#include "laser_raycast/node/raycast_node.h"

#include "cast_thread.h"
#include "map_topics.h"
#include "node_diagnostics.h"
#include "pose_topic.h"
#include "scene_editor.h"
#include "scene_source.h"
#include "sensor.h"
#include "sensor_reconfigure.h"
#include "shared_scene.h"
#include "tf_source.h"
#include "tf_timing.h"

namespace laser_raycast {

RaycastNode::RaycastNode(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(std::move(nh)), pnh_(std::move(pnh)) {}

RaycastNode::~RaycastNode() {
  report_timer_.stop();
  reconfigure_.clear();
  for (ros::Timer& t : align_timers_) t.stop();
  for (ros::Timer& t : timers_) t.stop();
  map_topics_.reset();   // joins its builder: no walls come after this
  editor_.reset();       // stops its services: no scene is swapped in after this
  cast_thread_.reset();  // joins: nothing casts after this
}

bool RaycastNode::init() {
  std::string error;
  if (!readNodeParams(nh_, pnh_, &params_, &error)) {
    ROS_FATAL_STREAM(error);
    return false;
  }
  auto base = std::make_shared<CastScene>();
  const auto urdf_param = [this](const std::string& name, std::string* xml, std::string* resolved) {
    *resolved = nh_.resolveName(name);
    return nh_.getParam(name, *xml);
  };
  std::vector<ScenePart> parts;
  error = loadSceneParts(params_, urdf_param, &parts, &base->reflectivity, &base->scene);
  if (!error.empty()) {
    ROS_FATAL_STREAM(error);
    return false;
  }
  base->reflectivity_fixed = labelReflectivityFixed(params_, base->scene);
  scene_ = std::make_unique<SharedScene>();
  scene_->set(base);

  tf_ = std::make_unique<TfListener>(nh_, ros::Duration(params_.tfCache()));
  for (const SensorParams& s : params_.sensors) {
    std::unique_ptr<PoseTopic> poses;
    if (!s.pose_topic.empty()) {
      poses = std::make_unique<PoseTopic>(nh_.resolveName(s.pose_topic), params_.fixed_frame,
                                          ros::Duration(s.pose_timeout),
                                          ros::Duration(params_.poseHistory(s)));
      pose_subscribers_.push_back(std::make_unique<PoseSubscriber>(nh_, s.pose_topic, poses.get()));
    }
    sensors_.push_back(
        std::make_unique<Sensor>(s, params_.fixed_frame, kTfGracePeriod, params_.threads,
                                 std::make_unique<TopicOutput>(nh_, s), std::move(poses)));
  }
  CastThread::Context context;
  context.scene = scene_.get();
  context.tf = &tf_->source();
  context.sensors = &sensors_;
  context.fixed_frame = params_.fixed_frame;
  context.tf_timeout = ros::Duration(params_.tf_timeout);
  cast_thread_ = std::make_unique<CastThread>(context);
  updateCapacity();
  diagnostics_ = std::make_unique<NodeDiagnostics>(
      nh_, pnh_, sensors_, [this] { return scene_->current()->scene.frames().size(); },
      [this] { return cast_thread_ ? cast_thread_->linkLookups() : 0; });
  const bool map_topics = std::any_of(params_.models.begin(), params_.models.end(),
                                      [](const ModelSource& m) { return !m.map_topic.empty(); });
  editor_ = std::make_unique<SceneEditor>(pnh_, params_, std::move(parts), scene_.get());
  if (map_topics) {
    map_topics_ = std::make_unique<MapTopics>(
        nh_, params_, [this](core::Scene walls) { editor_->setMapWalls(std::move(walls)); });
  }

  align_timers_.resize(sensors_.size());
  timers_.resize(sensors_.size());
  last_queued_.assign(sensors_.size(), ros::Time());
  const bool shorthand = params_.sensors.size() == 1 && params_.sensors[0].name.empty();
  for (std::size_t i = 0; i < sensors_.size(); ++i) {
    const int index = static_cast<int>(i);
    const SensorParams& s = params_.sensors[i];
    // The one sensor's live parameters are the node's own; an entry's are under ~<name>.
    const ros::NodeHandle live_ns = shorthand ? pnh_ : ros::NodeHandle(pnh_, s.name);
    reconfigure_.push_back(std::make_unique<SensorReconfigure>(live_ns, sensors_[i].get(), [=] {
      startTimer(index);
      updateCapacity();
    }));
    startTimer(index);
    const std::string beams =
        s.pattern
            ? std::to_string(s.points_per_scan) + " points a scan from '" + s.pattern_file + "'"
        : s.calibrated ? std::to_string(s.calibrated->size()) + " beams a turn from " +
                             (s.preset_head ? s.calibratedFrom() : "'" + s.calibratedFrom() + "'")
                       : std::to_string(s.scan.pattern().size()) + " beams (" +
                             std::to_string(s.scan.elevations.size()) + " rings)";
    ROS_INFO(
        "sensor '%s': %s at %g Hz, %s, in frame '%s', pose from %s; "
        "publishing %s",
        s.name.c_str(), beams.c_str(), s.rate, kSweepNames.name(s.sweep), s.frame_id.c_str(),
        s.pose_topic.empty() ? "TF" : ("topic " + s.pose_topic).c_str(),
        nh_.resolveName(s.topic).c_str());
  }
  report_timer_ = nh_.createTimer(ros::Duration(kReportPeriod), &RaycastNode::onReport, this);
  ROS_INFO("laser_raycast: started, %zu sensor%s over %zu bodies%s", sensors_.size(),
           sensors_.size() == 1 ? "" : "s", base->scene.bodies().size(),
           map_topics ? " (and the walls of the map topics' grids when they come)" : "");
  return true;
}

void RaycastNode::updateCapacity() {
  cast_thread_->setCapacity(castQueueCapacity(sensors_, params_.tf_timeout));
}

void RaycastNode::startTimer(int i) {
  // First a one-shot timer to the next multiple of the period, then the periodic timer from there:
  // scan times on the period's grid (tf_timing.h).
  timers_[i].stop();
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
  sensor.monitor().setActive(listened, stamp);
  if (listened) cast_thread_->schedule(i, sensor.sampleTimes(stamp));
}

void RaycastNode::onReport(const ros::TimerEvent&) {
  const ros::Time now = ros::Time::now();
  for (const auto& sensor : sensors_) sensor->monitor().reportRate(now, sensor->live().rate);
  diagnostics_->publish();
}

}  // namespace laser_raycast
