// The node's diagnostics (diagnostic_updater, on /diagnostics): per sensor, the scan rate against
// the configured one (frequency status), and its scans: cast time, share of beams hit, TF look-up
// failures, scans skipped and why; for the node, the link poses looked up in TF.
#pragma once

#include <diagnostic_updater/diagnostic_updater.h>
#include <ros/ros.h>

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <vector>

#include "sensor.h"

namespace laser_raycast {

class NodeDiagnostics {
 public:
  // The sensors must outlive this. link_frames: the scene's (now: a map topic's grid can add one);
  // link_lookups: the TF look-ups of link poses so far (CastThread::linkLookups).
  NodeDiagnostics(const ros::NodeHandle& nh, const ros::NodeHandle& pnh,
                  const std::vector<std::unique_ptr<Sensor>>& sensors,
                  std::function<std::size_t()> link_frames,
                  std::function<std::uint64_t()> link_lookups);
  // Publishes the status of every sensor now (called every second).
  void publish();

 private:
  // A sensor's scans published at recent times, for the achieved rate.
  struct RateWindow {
    std::deque<std::pair<ros::Time, std::uint64_t>> samples;
  };

  void rateStatus(const Sensor& sensor, RateWindow* window,
                  diagnostic_updater::DiagnosticStatusWrapper& stat);
  static void scanStatus(const Sensor& sensor, const SensorStats& previous, SensorStats* last,
                         diagnostic_updater::DiagnosticStatusWrapper& stat);

  // The achieved rate is averaged over this long, and is OK within this share of the configured
  // one (diagnostic_updater's FrequencyStatus defaults: 5 s, 10%).
  static constexpr double kWindow = 5.0;  // s
  static constexpr double kTolerance = 0.1;

  diagnostic_updater::Updater updater_;
  std::vector<RateWindow> windows_;
  std::vector<SensorStats> previous_;  // at the previous publication, for "since then" counts
};

}  // namespace laser_raycast
