#include "laser_raycast/core/scan_spec.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace laser_raycast {
namespace core {

void ScanSpec::validate() const {
  fan.validate();
  output.validate();
  std::ostringstream msg;
  if (elevations.empty()) {
    msg << "elevations must not be empty (a planar scanner is [0])";
    throw std::invalid_argument(msg.str());
  }
  for (std::size_t r = 0; r < elevations.size(); ++r) {
    // Written so that NaN fails.
    if (!(std::abs(elevations[r]) <= M_PI / 2)) {
      msg << "elevations[" << r << "] must be finite and in [-pi/2, pi/2] rad, got "
          << elevations[r];
      throw std::invalid_argument(msg.str());
    }
  }
  const std::vector<double> rings = ringElevations();
  const auto repeated = std::adjacent_find(rings.begin(), rings.end());
  if (repeated != rings.end()) {
    msg << "elevations must be distinct, got " << *repeated << " rad twice";
    throw std::invalid_argument(msg.str());
  }
  const double beams = static_cast<double>(fan.beamCount()) * elevations.size();
  if (!(beams <= FanSpec::kMaxBeams)) {
    msg << fan.beamCount() << " azimuths x " << elevations.size() << " elevations exceeds "
        << FanSpec::kMaxBeams << " beams";
    throw std::invalid_argument(msg.str());
  }
}

std::vector<double> ScanSpec::ringElevations() const {
  std::vector<double> rings = elevations;
  std::sort(rings.begin(), rings.end());
  return rings;
}

ScanPattern ScanSpec::pattern() const {
  validate();
  return ScanPattern(fan, ringElevations());
}

CastConfig ScanSpec::castConfig() const {
  CastConfig config;
  config.method = method;
  config.cull_backfaces = cull_backfaces;
  config.tmin = output.min_range_policy == MinRangePolicy::kPassThrough ? output.range_min : 0.0;
  config.tmax = output.range_max;
  config.compute_incidence = output.needsIncidence();
  return config;
}

}  // namespace core
}  // namespace laser_raycast
