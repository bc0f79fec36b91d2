#include "node_diagnostics.h"

#include <diagnostic_msgs/DiagnosticStatus.h>

namespace laser_raycast {

using diagnostic_msgs::DiagnosticStatus;

NodeDiagnostics::NodeDiagnostics(const ros::NodeHandle& nh, const ros::NodeHandle& pnh,
                                 const std::vector<std::unique_ptr<Sensor>>& sensors,
                                 std::function<std::size_t()> link_frames,
                                 std::function<std::uint64_t()> link_lookups)
    : updater_(nh, pnh), windows_(sensors.size()), previous_(sensors.size()) {
  updater_.setHardwareID(ros::this_node::getName());
  // One look-up per link frame and scan time, however many sensors are due then.
  updater_.add("link poses",
               [link_frames = std::move(link_frames), link_lookups = std::move(link_lookups)](
                   diagnostic_updater::DiagnosticStatusWrapper& stat) {
                 stat.add("Link frames", link_frames());
                 stat.add("Link pose look-ups", link_lookups());
                 stat.summary(DiagnosticStatus::OK, "ok");
               });
  for (std::size_t i = 0; i < sensors.size(); ++i) {
    const Sensor* sensor = sensors[i].get();
    updater_.add(sensor->name() + " scan rate",
                 [this, sensor, i](diagnostic_updater::DiagnosticStatusWrapper& stat) {
                   rateStatus(*sensor, &windows_[i], stat);
                 });
    updater_.add(sensor->name() + " scans",
                 [this, sensor, i](diagnostic_updater::DiagnosticStatusWrapper& stat) {
                   SensorStats now;
                   scanStatus(*sensor, previous_[i], &now, stat);
                   previous_[i] = now;
                 });
  }
}

void NodeDiagnostics::publish() { updater_.force_update(); }

void NodeDiagnostics::rateStatus(const Sensor& sensor, RateWindow* window,
                                 diagnostic_updater::DiagnosticStatusWrapper& stat) {
  const SensorStats stats = sensor.monitor().stats();
  const double target = sensor.live().rate;
  const ros::Time now = ros::Time::now();
  window->samples.emplace_back(now, stats.published);
  while (window->samples.size() > 2 && (now - window->samples[1].first).toSec() >= kWindow) {
    window->samples.pop_front();
  }
  const double seconds = (now - window->samples.front().first).toSec();
  const std::uint64_t events = stats.published - window->samples.front().second;
  const double achieved = seconds > 0 ? events / seconds : 0.0;
  stat.add("Events in window", events);
  stat.add("Events since startup", stats.published);
  stat.add("Duration of window (s)", seconds);
  stat.add("Actual frequency (Hz)", achieved);
  stat.add("Target frequency (Hz)", target);
  if (!stats.active) {
    stat.summary(DiagnosticStatus::OK, "not cast: nobody subscribes");
    window->samples.clear();
  } else if (seconds <= 0) {
    stat.summary(DiagnosticStatus::OK, "measuring");
  } else if (events == 0) {
    stat.summary(DiagnosticStatus::ERROR, "no scans");
  } else if (achieved < (1 - kTolerance) * target) {
    stat.summary(DiagnosticStatus::WARN, "frequency too low");
  } else if (achieved > (1 + kTolerance) * target) {
    stat.summary(DiagnosticStatus::WARN, "frequency too high");
  } else {
    stat.summary(DiagnosticStatus::OK, "desired frequency met");
  }
}

void NodeDiagnostics::scanStatus(const Sensor& sensor, const SensorStats& previous,
                                 SensorStats* last,
                                 diagnostic_updater::DiagnosticStatusWrapper& stat) {
  const SensorStats s = sensor.monitor().stats();
  *last = s;
  stat.add("Scans published", s.published);
  stat.add("Cast time of the last scan (ms)", 1e3 * s.last_cast_seconds);
  stat.add("Beams hit in the last scan (share)", s.last_hit_share);
  stat.add("Scans skipped: no sensor transform", s.skipped.no_transform);
  stat.add("Scans skipped: pose topic stale or non-finite", s.skipped.stale_pose);
  stat.add("Scans skipped: waiting for the first transforms", s.skipped.waiting);
  stat.add("Scans skipped: cast thread behind", s.skipped.behind);
  stat.add("TF look-up failures", s.tf_failures);
  stat.add("Links left out for want of a transform", s.missing_links);
  // Skips after the start-up wait since the previous report.
  const auto lasting = [](const SensorStats& x) {
    return x.skipped.no_transform + x.skipped.stale_pose + x.skipped.behind;
  };
  const std::uint64_t new_skips = lasting(s) - lasting(previous);
  const std::uint64_t new_missing = s.missing_links - previous.missing_links;
  if (new_skips > 0) {
    stat.summaryf(DiagnosticStatus::WARN, "%lu scans skipped since the last report",
                  static_cast<unsigned long>(new_skips));
  } else if (new_missing > 0) {
    stat.summaryf(DiagnosticStatus::WARN, "links left out for want of a transform (%lu)",
                  static_cast<unsigned long>(new_missing));
  } else {
    stat.summary(DiagnosticStatus::OK, "ok");
  }
}

}  // namespace laser_raycast
