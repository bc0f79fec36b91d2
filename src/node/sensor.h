// One simulated sensor of the node: its beams, caster and model, where its pose comes from (TF or
// a pose topic), the messages it makes (LaserScan for a planar pattern, PointCloud2 otherwise, and
// the per-beam labels) and where they go (sensor_output.h), its live parameters, and its monitor.
// The cast thread casts it; its timer, the subscriber check and live reconfiguration run on the
// node's callback thread.
#pragma once

#include <ros/ros.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/measurement_model.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/scene.h"
#include "laser_raycast/node/node_params.h"
#include "live_params.h"
#include "pose_topic.h"
#include "sensor_monitor.h"
#include "sensor_output.h"
#include "tf_source.h"

namespace laser_raycast {

class Sensor {
 public:
  // A rotating scan's poses are looked up at most this far apart across its sweep and
  // interpolated between (linear, slerp): exact for constant velocities, and finer than TF's
  // usual 50 to 100 Hz.
  static constexpr double kSweepSampleSpacing = 0.01;  // s

  // The parameters that can change while the node runs (cfg/Raycast.cfg).
  using Live = LiveParams;

  // threads: per cast (CastConfig::threads). output: where its messages go; pose_topic: where its
  // pose comes from if params.pose_topic is set (nullptr: from TF).
  Sensor(const SensorParams& params, const std::string& fixed_frame, double grace_period,
         int threads, std::unique_ptr<ScanOutput> output, std::unique_ptr<PoseTopic> pose_topic);

  const std::string& name() const { return name_; }
  // The TF chain its pose needs, as (target, source): fixed_frame <- frame_id, or, with a pose
  // topic, pose_frame <- frame_id.
  std::pair<std::string, std::string> tfChain() const;
  // Whether anyone listens to any of its topics (otherwise it is not cast).
  bool hasSubscribers() const { return output_->wanted(); }
  ros::Duration period() const;
  // The pose sample times of a scan stamped at `stamp`: the stamp alone for an instantaneous scan,
  // else across the sweep up to its last beam column's time.
  std::vector<ros::Time> sampleTimes(const ros::Time& stamp) const;

  Live live() const;
  // Validates `live` (applyLiveParams) and applies it from the next scan; "" or the problem
  // (naming the parameter), the previous values staying.
  std::string setLive(const Live& live);

  // The sensor pose in fixed_frame at t; false with the reason in *why and whether TF (rather than
  // the pose topic) lacked it in *from_tf. The TF look-ups it made that failed (its chain, and with
  // a pose topic the messages' frame) are added to *tf_failures.
  bool poseAt(const ros::Time& t, const TfSource& tf, Eigen::Isometry3d* pose, std::string* why,
              bool* from_tf, std::uint64_t* tf_failures);
  // Casts the scan whose pose samples are at `times`, from the frames and sensor poses at each,
  // and sends it to its output. missing_links: link transforms left out of it. reflectivity and
  // reflectivity_fixed are by label (scene_source.h).
  void castAndPublish(const core::Scene& scene, const std::vector<double>& reflectivity,
                      const std::vector<char>& reflectivity_fixed,
                      const std::vector<ros::Time>& times,
                      const std::vector<core::FramePoses>& frames,
                      const std::vector<Eigen::Isometry3d>& poses, std::size_t missing_links);

  SensorMonitor& monitor() { return monitor_; }
  const SensorMonitor& monitor() const { return monitor_; }

 private:
  // Applies a pending live change (cast thread, at the start of a scan).
  void applyLive();
  // A pattern file's next scan (beams_), at once or each point at its own time.
  const core::ScanResult* castPattern(const core::Scene& scene, const std::vector<ros::Time>& times,
                                      const std::vector<core::FramePoses>& frames,
                                      const std::vector<Eigen::Isometry3d>& poses);
  // Divergent beams in dual return mode: a 3D sensor's cloud has each beam's last return too.
  bool dual() const {
    return cast_params_.returns.beam_samples > 1 &&
           cast_params_.returns.return_mode == core::ReturnMode::kDual && !cast_params_.planar();
  }
  void publishScan(const ros::Time& stamp);
  void publishCloud(const ros::Time& stamp);
  void publishLabels(const core::Scene& scene, const std_msgs::Header& header);

  const std::string name_;
  const std::string fixed_frame_;
  mutable std::mutex mutex_;  // params_ (its live part) and pending_
  SensorParams params_;
  std::optional<Live> pending_;
  // The cast thread's own:
  SensorParams cast_params_;
  core::ScanPattern pattern_;
  core::CastConfig cast_config_;
  const int threads_;  // ~threads (node-wide), for every cast
  core::Caster caster_;
  core::MeasurementModel measurement_model_;
  core::MeasuredScan measured_;
  core::PulseReturns returns_;        // with divergent beams (beam_samples > 1)
  core::MeasuredScan measured_last_;  // return_mode dual: the beams' last returns
  // The last cloud published, its buffer written over by the next (a VLP-16's turn is 636 KB).
  sensor_msgs::PointCloud2 cloud_;
  core::SurfaceSamples surface_;  // the surfaces' reflectance and incidence, when intensity is on
  std::vector<double> column_times_;  // s after the stamp, per azimuth column (rotating)
  // The beams off any grid this scan casts: a pattern file's, and the row the next scan starts at
  // (the file a loop); or the head's turn, calibrated_ (a live rate change gives another).
  core::BeamList beams_;
  std::int64_t next_row_ = 0;
  std::shared_ptr<const core::BeamList> calibrated_;
  const core::BeamList& castList() const { return calibrated_ ? *calibrated_ : beams_; }

  std::unique_ptr<ScanOutput> output_;
  std::unique_ptr<PoseTopic> pose_topic_;
  SensorMonitor monitor_;
};

}  // namespace laser_raycast
