#include "job_caster.h"

#include <algorithm>

#include "param_reader.h"

namespace laser_raycast {

JobCaster::JobCaster(Context context)
    : context_(std::move(context)),
      link_poses_(*context_.scene, [this](const std::string& frame, const ros::Time& t,
                                          Eigen::Isometry3d* pose, std::string* error) {
        return context_.tf->lookup(context_.fixed_frame, frame, t, pose, error);
      },
      [this](const std::string& frame) {
        return context_.tf->isStatic(context_.fixed_frame, frame);
      }) {}

bool JobCaster::ready(const ScanJob& job, const ros::Time& now) {
  if (wait_.last != job.last() || wait_.chains.empty()) {
    wait_.last = job.last();
    wait_.chains.clear();
    for (const std::string& frame : context_.scene->frames()) {
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

void JobCaster::cast(const ScanJob& job) {
  for (const int s : job.sensors) castSensor(*(*context_.sensors)[s], job);
}

void JobCaster::done(const ScanJob& job, const std::optional<ros::Time>& oldest_queued) {
  // Times before the oldest stamp still queued (or this job's) are needed by no scan any more.
  link_poses_.forgetBefore(oldest_queued && *oldest_queued < job.stamp() ? *oldest_queued
                                                                         : job.stamp());
}

bool JobCaster::sensorPoses(Sensor& sensor, const ScanJob& job, bool quiet,
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

bool JobCaster::acceptMissing(Sensor& sensor, const ScanJob& job, bool quiet,
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
        links.missing.size(), context_.scene->frames().size(), context_.fixed_frame.c_str(),
        job.last().toSec(), context_.tf_timeout.toSec(),
        joinFirst(links.missing, kLinksInWarning).c_str(), links.first_error.c_str());
  }
  return true;
}

void JobCaster::castSensor(Sensor& sensor, const ScanJob& job) {
  const bool quiet = sensor.monitor().quiet(job.stamp());
  std::vector<Eigen::Isometry3d> poses;
  if (!sensorPoses(sensor, job, quiet, &poses)) return;
  // Looked up once per time for every sensor whose scan needs it.
  const LinkPosesAt links = link_poses_.at(job.times);
  sensor.monitor().lookupFailures(links.failures);
  if (!acceptMissing(sensor, job, quiet, links)) return;
  sensor.castAndPublish(*context_.scene, *context_.reflectivity, *context_.reflectivity_fixed,
                        job.times, links.frames, poses, links.missing.size());
}

}  // namespace laser_raycast
