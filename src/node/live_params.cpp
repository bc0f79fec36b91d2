#include "live_params.h"

#include <cmath>
#include <memory>
#include <stdexcept>

#include "param_reader.h"

namespace laser_raycast {

LiveParams liveParams(const SensorParams& params) {
  return LiveParams{params.scan.output, params.rate};
}

std::string applyLiveParams(const LiveParams& live, SensorParams* params) {
  if (!(std::isfinite(live.rate) && live.rate > 0 && live.rate <= SensorParams::kMaxRate)) {
    return "rate must be in (0, " + formatNumber(SensorParams::kMaxRate) + "] Hz, got " +
           formatNumber(live.rate);
  }
  // scan_time 0 follows the rate (1 / rate); a set one must fit in the new period.
  if (params->sweep == Sweep::kRotating && params->scan_time > 1.0 / live.rate) {
    return "rate " + formatNumber(live.rate) + " Hz is too fast for scan_time " +
           formatNumber(params->scan_time) +
           " s (a head turns once a scan; scan_time needs a restart)";
  }
  // scan_time 0 follows the rate: a slower rate lengthens a rotating sweep, whose point times the
  // layout's fields must still hold.
  SensorParams next = *params;
  next.rate = live.rate;
  if (!next.planar()) {
    const std::string limit = pointLayoutLimit(
        next.point_layout, static_cast<int>(next.scan.elevations.size()), next.sweepDuration());
    if (!limit.empty()) {
      return "rate " + formatNumber(live.rate) + " Hz is too slow for point_layout " + limit;
    }
  }
  try {
    live.output.validate();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  // A head's beams (a preset's lasers, a calibration file's) are one turn of scanTime(): a turn
  // that follows the rate is fired again at the new one.
  if (next.calibrated && next.head_turn && next.scanTime() != params->scanTime()) {
    try {
      next.calibrated = std::make_shared<const core::BeamList>(next.head_turn(next.scanTime()));
    } catch (const std::invalid_argument& e) {
      return "rate " + formatNumber(live.rate) + " Hz: " + params->calibratedFrom() +
             " over one turn of " + formatNumber(next.scanTime()) + " s: " + e.what();
    }
  }
  params->scan.output = live.output;
  params->rate = live.rate;
  params->calibrated = next.calibrated;
  return "";
}

}  // namespace laser_raycast
