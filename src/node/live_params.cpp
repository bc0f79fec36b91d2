#include "live_params.h"

#include <cmath>
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
  params->scan.output = live.output;
  params->rate = live.rate;
  return "";
}

}  // namespace laser_raycast
