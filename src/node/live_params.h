// The parameters of a sensor that can change while the node runs (cfg/Raycast.cfg), and whether a
// change is accepted. Pure (no ROS communication), so unit tests check the refusals;
// Sensor::setLive applies what this accepts from its next scan.
#pragma once

#include <string>

#include "laser_raycast/core/measurement_model.h"
#include "laser_raycast/node/node_params.h"

namespace laser_raycast {

struct LiveParams {
  core::MeasurementConfig output;  // range limits, min-range policy, noise, intensity, realism
  double rate = 10.0;              // Hz
};

// The live part of `params`.
LiveParams liveParams(const SensorParams& params);

// Applies `live` to *params and returns "", or returns the problem (naming the parameter and the
// value) and leaves *params as it was: a rate outside (0, kMaxRate], a rate too fast for a
// rotating sensor's scan_time (one turn per scan; scan_time itself needs a restart), one so slow
// that a sweep following it outlasts the times point_layout can hold, or output settings
// core::MeasurementConfig::validate refuses (e.g. range_min >= range_max). A head's beams
// (SensorParams::calibrated, head_turn) whose turn follows the rate are fired again over the new
// turn.
std::string applyLiveParams(const LiveParams& live, SensorParams* params);

}  // namespace laser_raycast
