#include "sensor.h"

#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>

#include <chrono>
#include <iomanip>
#include <sstream>

#include "laser_raycast/ScanLabels.h"
#include "laser_raycast/core/pose_samples.h"
#include "laser_raycast/node/point_cloud.h"
#include "tf_timing.h"

namespace laser_raycast {

Sensor::Sensor(const SensorParams& params, const std::string& fixed_frame, double grace_period,
               int threads, std::unique_ptr<ScanOutput> output,
               std::unique_ptr<PoseTopic> pose_topic)
    : name_(params.name),
      fixed_frame_(fixed_frame),
      params_(params),
      cast_params_(params),
      pattern_(params.scan.pattern()),
      cast_config_(params.scan.castConfig()),
      threads_(threads),
      measurement_model_(params.scan.output),
      output_(std::move(output)),
      pose_topic_(std::move(pose_topic)),
      monitor_(params.name, output_->topic(), grace_period) {
  cast_config_.threads = threads_;
  if (params.sweep == Sweep::kRotating) {
    column_times_ = rotatingColumnTimes(pattern_.azimuthCount(), params.timeIncrement());
  }
}

std::pair<std::string, std::string> Sensor::tfChain() const {
  if (!pose_topic_) return {fixed_frame_, params_.frame_id};
  return {params_.pose_frame.empty() ? params_.frame_id : params_.pose_frame, params_.frame_id};
}

ros::Duration Sensor::period() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return ros::Duration(1.0 / params_.rate);
}

std::vector<ros::Time> Sensor::sampleTimes(const ros::Time& stamp) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return laser_raycast::sampleTimes(stamp, ros::Duration(params_.sweepDuration()),
                                    ros::Duration(kSweepSampleSpacing));
}

Sensor::Live Sensor::live() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return liveParams(params_);
}

std::string Sensor::setLive(const Live& live) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string error = applyLiveParams(live, &params_);
  if (error.empty()) pending_ = live;
  return error;
}

void Sensor::applyLive() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!pending_) return;
  cast_params_ = params_;
  cast_config_ = cast_params_.scan.castConfig();
  cast_config_.threads = threads_;
  measurement_model_.setConfig(cast_params_.scan.output);
  if (cast_params_.sweep == Sweep::kRotating) {
    column_times_ = rotatingColumnTimes(pattern_.azimuthCount(), cast_params_.timeIncrement());
  }
  pending_.reset();
}

bool Sensor::poseAt(const ros::Time& t, const TfSource& tf, Eigen::Isometry3d* pose,
                    std::string* why, bool* from_tf, std::uint64_t* tf_failures) {
  // Without a pose topic the sensor is a TF frame like any other; with one, the topic gives the
  // pose of pose_frame, and TF (usually a static mount) the sensor relative to it.
  Eigen::Isometry3d world_from_pose_frame = Eigen::Isometry3d::Identity();
  *from_tf = false;
  if (pose_topic_ && !pose_topic_->poseAt(t, tf, &world_from_pose_frame, why, tf_failures)) {
    return false;
  }
  *from_tf = true;
  const auto [target, source] = tfChain();
  Eigen::Isometry3d target_from_sensor;
  std::string error;
  if (!tf.lookup(target, source, t, &target_from_sensor, &error)) {
    ++*tf_failures;
    std::ostringstream s;
    s << "no transform from '" << source << "' to '" << target << "' at t = " << std::fixed
      << std::setprecision(3) << t.toSec() << " (" << error << ")";
    *why = s.str();
    return false;
  }
  *pose = world_from_pose_frame * target_from_sensor;
  return true;
}

void Sensor::castAndPublish(const core::Scene& scene, const std::vector<double>& reflectivity,
                            const std::vector<char>& reflectivity_fixed,
                            const std::vector<ros::Time>& times,
                            const std::vector<core::FramePoses>& frames,
                            const std::vector<Eigen::Isometry3d>& poses,
                            std::size_t missing_links) {
  applyLive();
  const auto start = std::chrono::steady_clock::now();
  const core::ScanResult* result;
  if (cast_params_.offGrid()) {
    result = castPattern(scene, times, frames, poses);
  } else if (times.size() == 1) {
    result = &caster_.cast(scene, frames.front(), poses.front(), pattern_, cast_config_);
  } else {
    // A rotating scan: each beam column from the poses at its own time (s after the stamp).
    core::PoseSamples samples;
    for (const ros::Time& t : times) samples.times.push_back((t - times.front()).toSec());
    samples.world_from_sensor = poses;
    samples.frames = frames;
    result =
        &caster_.castSweep(scene, samples, pattern_, cast_config_, cast_params_.timeIncrement());
  }
  const double cast_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const core::MeasurementConfig& output = cast_params_.scan.output;
  if (cast_params_.returns.beam_samples > 1) {
    // Divergent beams: the mode's return (dual: the strongest, and for a cloud the last too),
    // cast from the scan's first pose (a sweep's motion is not applied to them).
    core::castReturns(&caster_, scene, frames.front(), poses.front(), cast_params_.scan.fan,
                      cast_params_.scan.ringElevations(), cast_config_, cast_params_.returns,
                      reflectivity, reflectivity_fixed, output.reflectance_from_color,
                      output.surface_reflectance, &returns_);
    measurement_model_.measure(scene, returns_.first, reflectivity, &measured_,
                               &returns_.first_surface);
    if (dual()) {
      measurement_model_.measure(scene, returns_.second, reflectivity, &measured_last_,
                                 &returns_.second_surface);
    }
  } else if (output.needsIncidence() && output.surface_reflectance) {
    // A sweep's surfaces are sampled from its first pose (sampleSurfaces); beams off the grid
    // from their own origins and directions.
    if (cast_params_.offGrid()) {
      core::sampleSurfaces(scene, frames.front(), poses.front(), castList(), *result,
                           output.reflectance_from_color, reflectivity_fixed, &surface_);
    } else {
      core::sampleSurfaces(scene, frames.front(), poses.front(), pattern_, *result,
                           output.reflectance_from_color, reflectivity_fixed, &surface_);
    }
    measurement_model_.measure(scene, *result, reflectivity, &measured_, &surface_);
  } else {
    measurement_model_.measure(scene, *result, reflectivity, &measured_);
  }
  if (cast_params_.planar()) {
    publishScan(times.front());
  } else {
    publishCloud(times.front());
  }
  std_msgs::Header header;
  header.stamp = times.front();
  header.frame_id = cast_params_.frame_id;
  publishLabels(scene, header);

  const core::MeasurementConfig& out = cast_params_.scan.output;
  std::size_t hits = 0;
  for (const float r : measured_.ranges) hits += r >= out.range_min && r <= out.range_max;
  monitor_.published(times.front(), missing_links, cast_seconds,
                     measured_.ranges.empty() ? 0.0 : double(hits) / measured_.ranges.size());
}

const core::ScanResult* Sensor::castPattern(const core::Scene& scene,
                                            const std::vector<ros::Time>& times,
                                            const std::vector<core::FramePoses>& frames,
                                            const std::vector<Eigen::Isometry3d>& poses) {
  if (cast_params_.pattern) {
    const core::PatternFile& file = *cast_params_.pattern;
    beams_ = file.scan(next_row_, cast_params_.points_per_scan, cast_params_.point_rate);
    next_row_ = (next_row_ + cast_params_.points_per_scan) % file.size();
    calibrated_.reset();
  } else {
    // The same list every scan, until a live rate change makes another: shared with the caster,
    // which knows it again without comparing its beams.
    calibrated_ = cast_params_.calibrated;
  }
  // An instant scan casts every point from the stamp's poses; the points keep their times.
  if (cast_params_.sweep != Sweep::kRotating) {
    if (calibrated_) {
      return &caster_.castBeams(scene, frames.front(), poses.front(), calibrated_, cast_config_);
    }
    return &caster_.castBeams(scene, frames.front(), poses.front(), beams_, cast_config_);
  }
  // Each point from the poses at its own time (s after the stamp).
  core::PoseSamples samples;
  for (const ros::Time& t : times) samples.times.push_back((t - times.front()).toSec());
  samples.world_from_sensor = poses;
  samples.frames = frames;
  if (calibrated_) return &caster_.castBeamsSweep(scene, samples, calibrated_, cast_config_);
  return &caster_.castBeamsSweep(scene, samples, beams_, cast_config_);
}

void Sensor::publishScan(const ros::Time& stamp) {
  sensor_msgs::LaserScan scan;
  scan.header.stamp = stamp;  // the first beam's time (every beam's, when instantaneous)
  scan.header.frame_id = cast_params_.frame_id;
  scan.angle_min = static_cast<float>(pattern_.angleMin());
  scan.angle_max = static_cast<float>(pattern_.angleMax());
  scan.angle_increment = static_cast<float>(pattern_.angleIncrement());
  scan.time_increment = static_cast<float>(cast_params_.timeIncrement());
  scan.scan_time = static_cast<float>(cast_params_.scanTime());
  scan.range_min = static_cast<float>(cast_params_.scan.output.range_min);
  scan.range_max = static_cast<float>(cast_params_.scan.output.range_max);
  scan.ranges = measured_.ranges;
  scan.intensities = measured_.intensities;
  output_->send(scan);
}

void Sensor::publishCloud(const ros::Time& stamp) {
  std_msgs::Header header;
  header.stamp = stamp;  // the first beam column's time; each point has its own in `time`
  header.frame_id = cast_params_.frame_id;
  CloudOptions options;
  options.organized = cast_params_.organized;
  options.layout = cast_params_.point_layout;
  if (cast_params_.offGrid()) {
    buildBeamCloud(castList(), measured_, header, options, &cloud_);
  } else {
    buildPointCloud(pattern_, measured_, column_times_, header, options, &cloud_,
                    dual() ? &measured_last_ : nullptr);
  }
  output_->send(cloud_);
}

void Sensor::publishLabels(const core::Scene& scene, const std_msgs::Header& header) {
  // The labels are computed with every scan; the message is built only for a subscriber.
  if (!output_->labelsWanted()) return;
  laser_raycast::ScanLabels labels;
  labels.header = header;
  labels.link_names = scene.labels();
  labels.labels.assign(measured_.labels.begin(), measured_.labels.end());
  output_->send(labels);
}

}  // namespace laser_raycast
