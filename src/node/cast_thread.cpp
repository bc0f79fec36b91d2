#include "cast_thread.h"

#include <algorithm>
#include <chrono>

#include "param_reader.h"

namespace laser_raycast {

CastThread::CastThread(Context context) : context_(std::move(context)) {
  takeScene();
  thread_ = std::thread([this] { run(); });
}

void CastThread::takeScene() {
  std::shared_ptr<const CastScene> scene = context_.scene->current();
  if (scene == scene_ && link_poses_) return;
  if (link_poses_) earlier_lookups_ += link_poses_->lookups();
  // The poses looked up so far are of the old scene's frames; the new one's are looked up anew.
  link_poses_ = std::make_unique<LinkPoses>(
      scene->scene, [this](const std::string& frame, const ros::Time& t, Eigen::Isometry3d* pose,
                           std::string* error) {
        return context_.tf->lookup(context_.fixed_frame, frame, t, pose, error);
      });
  scene_ = std::move(scene);
  wait_.chains.clear();
}

CastThread::~CastThread() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void CastThread::setCapacity(std::size_t capacity) {
  std::lock_guard<std::mutex> lock(mutex_);
  queue_.setCapacity(capacity);
}

void CastThread::schedule(int sensor, const std::vector<ros::Time>& times) {
  std::optional<ScanJob> dropped;
  std::size_t queued;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    dropped = queue_.push(times, sensor);
    queued = queue_.size();
  }
  wake_.notify_all();
  if (!dropped) return;
  for (const int s : dropped->sensors) {
    (*context_.sensors)[s]->monitor().skipped(
        SensorMonitor::Skip::kBehind, dropped->stamp(),
        "the cast thread is " + std::to_string(queued) +
            " scans behind (casting takes longer than the scan period)");
  }
}

void CastThread::run() {
  const auto poll = std::chrono::duration<double>(kPollPeriod);
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_) {
    if (queue_.empty()) {
      wake_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      continue;
    }
    const ScanJob front = queue_.front();
    lock.unlock();
    takeScene();
    const bool go = ready(front);
    lock.lock();
    if (!go) {
      wake_.wait_for(lock, poll, [this] { return stop_; });
      continue;
    }
    // Sensors may have joined the job meanwhile, or an earlier job come in front of it.
    if (queue_.empty() || queue_.front().times != front.times) continue;
    const ScanJob job = queue_.pop();
    lock.unlock();
    process(job);
    lock.lock();
    // Times before the oldest stamp still queued (or this job's) are needed by no scan any more.
    const std::optional<ros::Time> oldest = queue_.oldestStamp();
    link_poses_->forgetBefore(oldest && *oldest < job.stamp() ? *oldest : job.stamp());
  }
}

bool CastThread::ready(const ScanJob& job) {
  const ros::Time now = ros::Time::now();
  if (now.isZero()) return false;  // simulated time has not started
  if (wait_.last != job.last() || wait_.chains.empty()) {
    wait_.last = job.last();
    wait_.chains.clear();
    for (const std::string& frame : scene_->scene.frames()) {
      wait_.chains.emplace_back(context_.fixed_frame, frame);
    }
    wait_.state.assign(wait_.chains.size(), FrameAvailability::kWaiting);
  }
  // The sensors' chains, for sensors that joined the job since.
  for (const int s : job.sensors) {
    const auto chain = (*context_.sensors)[s]->tfChain();
    if (std::find(wait_.chains.begin(), wait_.chains.end(), chain) == wait_.chains.end()) {
      wait_.chains.push_back(chain);
      wait_.state.push_back(FrameAvailability::kWaiting);
    }
  }
  for (std::size_t i = 0; i < wait_.chains.size(); ++i) {
    if (wait_.state[i] != FrameAvailability::kWaiting) continue;
    const auto& [target, source] = wait_.chains[i];
    wait_.state[i] =
        context_.tf->availability(target, source, job.last(), now, context_.tf_timeout);
    if (wait_.state[i] == FrameAvailability::kWaiting) return false;
  }
  return true;
}

void CastThread::process(const ScanJob& job) {
  for (const int s : job.sensors) castSensor(*(*context_.sensors)[s], job);
}

bool CastThread::sensorPoses(Sensor& sensor, const ScanJob& job, bool quiet,
                             std::vector<Eigen::Isometry3d>* poses) {
  poses->resize(job.times.size());
  for (std::size_t j = 0; j < job.times.size(); ++j) {
    std::string why;
    bool from_tf;
    std::uint64_t failures = 0;
    const bool ok =
        sensor.poseAt(job.times[j], *context_.tf, &(*poses)[j], &why, &from_tf, &failures);
    sensor.monitor().lookupFailures(failures);
    if (!ok) {
      using Skip = SensorMonitor::Skip;
      sensor.monitor().skipped(quiet     ? Skip::kWaiting
                               : from_tf ? Skip::kNoTransform
                                         : Skip::kStalePose,
                               job.stamp(), why);
      return false;
    }
  }
  return true;
}

bool CastThread::acceptMissing(Sensor& sensor, const ScanJob& job, bool quiet,
                               const LinkPosesAt& links) {
  if (links.missing.empty()) return true;
  if (quiet) {
    sensor.monitor().skipped(SensorMonitor::Skip::kWaiting, job.stamp(),
                             std::to_string(links.missing.size()) +
                                 " link frames have no transform yet (" +
                                 joinFirst(links.missing, kLinksInWarning) + ")");
    return false;
  }
  const ros::WallTime now = ros::WallTime::now();
  if (last_link_warning_.isZero() || (now - last_link_warning_).toSec() >= kWarnPeriod) {
    last_link_warning_ = now;
    ROS_WARN(
        "%zu of %zu link frames have no transform to '%s' at t = %.3f; their geometry is "
        "left out of this scan (a transform older than ~tf_timeout %.3f s is not waited "
        "for): %s (%s)",
        links.missing.size(), scene_->scene.frames().size(), context_.fixed_frame.c_str(),
        job.last().toSec(), context_.tf_timeout.toSec(),
        joinFirst(links.missing, kLinksInWarning).c_str(), links.first_error.c_str());
  }
  return true;
}

void CastThread::castSensor(Sensor& sensor, const ScanJob& job) {
  const bool quiet = sensor.monitor().quiet(job.stamp());
  std::vector<Eigen::Isometry3d> poses;
  if (!sensorPoses(sensor, job, quiet, &poses)) return;
  // Looked up once per time for every sensor whose scan needs it.
  const LinkPosesAt links = link_poses_->at(job.times);
  link_lookups_ = earlier_lookups_ + link_poses_->lookups();
  sensor.monitor().lookupFailures(links.failures);
  if (!acceptMissing(sensor, job, quiet, links)) return;
  sensor.castAndPublish(scene_->scene, scene_->reflectivity, job.times, links.frames, poses,
                        links.missing.size());
}

}  // namespace laser_raycast
