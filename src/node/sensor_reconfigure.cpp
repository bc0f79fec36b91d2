#include "sensor_reconfigure.h"

#include <utility>

namespace laser_raycast {

SensorReconfigure::SensorReconfigure(const ros::NodeHandle& nh, Sensor* sensor,
                                     std::function<void()> on_rate)
    : sensor_(sensor), on_rate_(std::move(on_rate)), server_(mutex_, nh) {
  // The server starts from the .cfg's defaults; the sensor's values (its parameters, a preset) win.
  server_.updateConfig(toConfig(sensor_->live()));
  server_.setCallback(
      [this](RaycastConfig& config, std::uint32_t level) { onConfig(config, level); });
}

RaycastConfig SensorReconfigure::toConfig(const Sensor::Live& live) {
  RaycastConfig c;
  c.rate = live.rate;
  c.range_min = live.output.range_min;
  c.range_max = live.output.range_max;
  c.min_range_policy = core::toString(live.output.min_range_policy);
  c.intensity = kIntensityNames.name(live.output.intensity);
  c.noise_stddev = live.output.noise_stddev;
  c.noise_seed = static_cast<int>(live.output.noise_seed);
  c.range_bias = live.output.range_bias;
  c.range_resolution = live.output.range_resolution;
  c.dropout_probability = live.output.dropout_probability;
  return c;
}

void SensorReconfigure::onConfig(RaycastConfig& config, std::uint32_t) {
  const Sensor::Live before = sensor_->live();
  Sensor::Live next = before;
  next.rate = config.rate;
  core::MeasurementConfig& out = next.output;
  out.range_min = config.range_min;
  out.range_max = config.range_max;
  out.noise_stddev = config.noise_stddev;
  out.noise_seed = static_cast<std::uint64_t>(std::max(config.noise_seed, 0));
  out.range_bias = config.range_bias;
  out.range_resolution = config.range_resolution;
  out.dropout_probability = config.dropout_probability;
  std::string error;
  if (!core::kMinRangePolicyNames.parse(config.min_range_policy, &out.min_range_policy)) {
    error = "min_range_policy " + core::kMinRangePolicyNames.notOneOf(config.min_range_policy);
  } else if (!kIntensityNames.parse(config.intensity, &out.intensity)) {
    error = "intensity " + kIntensityNames.notOneOf(config.intensity);
  } else {
    error = sensor_->setLive(next);
  }
  if (!started_) {  // setCallback's first call hands back the values just set
    started_ = true;
    return;
  }
  if (!error.empty()) {
    ROS_ERROR("sensor '%s': reconfiguration refused, the previous values stay: %s",
              sensor_->name().c_str(), error.c_str());
    config = toConfig(before);
    return;
  }
  ROS_INFO(
      "sensor '%s': reconfigured (from the next scan): rate %g Hz, range [%g, %g] m, "
      "min_range_policy %s, intensity %s, noise %g m (seed %lu), bias %g m, resolution %g m, "
      "dropout %g",
      sensor_->name().c_str(), next.rate, out.range_min, out.range_max,
      config.min_range_policy.c_str(), config.intensity.c_str(), out.noise_stddev,
      static_cast<unsigned long>(out.noise_seed), out.range_bias, out.range_resolution,
      out.dropout_probability);
  if (next.rate != before.rate && on_rate_) on_rate_();
}

}  // namespace laser_raycast
