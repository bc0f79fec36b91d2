#include "sensor_params.h"

#include <ros/names.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace laser_raycast {
namespace {

// The beam count comes from exactly one of angle_increment and samples (neither:
// kDefaultSamples); the core checks the angles and the beam count.
void readFan(ParamReader* r, core::FanSpec* fan) {
  fan->angle_min = r->number("angle_min", fan->angle_min, "rad");
  fan->angle_max = r->number("angle_max", fan->angle_max, "rad");
  const bool has_increment = r->has("angle_increment"), has_samples = r->has("samples");
  if (has_increment) {
    fan->angle_increment = r->number("angle_increment", 0.0, "rad");
    if (!(std::isfinite(fan->angle_increment) && fan->angle_increment > 0)) {
      r->fail("angle_increment",
              "must be finite and > 0 rad, got " + formatNumber(fan->angle_increment));
    }
  } else {
    r->note(r->prefix() + "angle_increment unset (beams from " + r->prefix() + "samples)");
  }
  if (has_samples || !has_increment) {
    fan->samples = r->integer("samples", SensorParams::kDefaultSamples, "beams");
    if (fan->samples < 2) r->fail("samples", "must be >= 2, got " + std::to_string(fan->samples));
  } else {
    r->note(r->prefix() + "samples unset (beams from " + r->prefix() + "angle_increment)");
  }
  if (has_increment && has_samples) {
    r->fail("samples", "set " + r->prefix() + "angle_increment or " + r->prefix() +
                           "samples, not both (got angle_increment " +
                           formatNumber(fan->angle_increment) + " and samples " +
                           std::to_string(fan->samples) + ")");
  }
}

// What the sensor reports: range limits, min-range policy, noise, intensity; and how it casts.
void readOutput(ParamReader* r, core::ScanSpec* scan) {
  core::EncoderConfig& out = scan->output;
  out.range_min = r->number("range_min", out.range_min, "m");
  out.range_max = r->number("range_max", out.range_max, "m");
  out.min_range_policy =
      r->choice("min_range_policy", out.min_range_policy, core::kMinRangePolicyNames);
  out.noise_stddev = r->number("noise_stddev", out.noise_stddev, "m");
  const int seed = r->integer("noise_seed", static_cast<int>(out.noise_seed), "");
  if (seed < 0) r->fail("noise_seed", "must be >= 0, got " + std::to_string(seed));
  out.noise_seed = static_cast<std::uint64_t>(std::max(seed, 0));
  out.intensity = r->choice("intensity", out.intensity, kIntensityNames);
  scan->method = r->choice("method", scan->method, core::kTriangleMethodNames);
  scan->cull_backfaces = r->boolean("cull_backfaces", scan->cull_backfaces);
}

void readRate(ParamReader* r, SensorParams* s) {
  s->rate = r->number("rate", s->rate, "Hz");
  if (!(std::isfinite(s->rate) && s->rate > 0 && s->rate <= SensorParams::kMaxRate)) {
    r->fail("rate", "must be in (0, " + formatNumber(SensorParams::kMaxRate) + "] Hz, got " +
                        formatNumber(s->rate));
  }
}

// Where the sensor pose comes from: TF, or a topic giving the pose of pose_frame.
void readPoseSource(ParamReader* r, SensorParams* s) {
  s->pose_topic = r->text("pose_topic", s->pose_topic);
  std::string why;
  if (!s->pose_topic.empty() && !ros::names::validate(s->pose_topic, why)) {
    r->fail("pose_topic", "'" + s->pose_topic + "' is not a valid topic name: " + why);
  }
  s->pose_frame = r->text("pose_frame", s->pose_frame);
  checkFrame(r, "pose_frame", s->pose_frame, true);
  if (!s->pose_frame.empty() && s->pose_topic.empty()) {
    r->fail("pose_frame", "is set to '" + s->pose_frame + "' but " + r->prefix() +
                              "pose_topic is not (pose_frame names the frame whose pose the "
                              "topic gives)");
  }
  // .inf (YAML) never times out, for a pose source that publishes only when the pose changes.
  s->pose_timeout = r->number("pose_timeout", s->pose_timeout, "s");
  if (!(s->pose_timeout > 0)) {
    r->fail("pose_timeout",
            "must be > 0 s (.inf: never stale), got " + formatNumber(s->pose_timeout));
  }
}

}  // namespace

void checkFrame(ParamReader* r, const std::string& name, const std::string& frame, bool optional) {
  if (frame.empty() && !optional) r->fail(name, "must not be empty");
  if (!frame.empty() && frame[0] == '/') {
    r->fail(name, "'" + frame + "': tf2 frame ids must not start with '/'");
  }
}

void readSensor(ParamReader* r, SensorParams* s) {
  s->frame_id = r->text("frame_id", s->frame_id);
  checkFrame(r, "frame_id", s->frame_id, false);
  readFan(r, &s->scan.fan);
  readOutput(r, &s->scan);
  readRate(r, s);
  readPoseSource(r, s);
}

std::vector<std::string> sensorParamNames() {
  const XmlRpc::XmlRpcValue none;
  ParamReader r(none, "~");
  SensorParams s;
  readSensor(&r, &s);
  return r.known();
}

}  // namespace laser_raycast
