#include "laser_raycast/core/beam_list.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

#include "laser_raycast/core/scan_pattern.h"

namespace laser_raycast {
namespace core {

void BeamList::validate() const {
  const std::size_t n = directions.size();
  auto bad = [](const std::string& what) { throw std::invalid_argument("beam list: " + what); };
  if (n > static_cast<std::size_t>(FanSpec::kMaxBeams)) {
    bad(std::to_string(n) + " beams, more than " + std::to_string(FanSpec::kMaxBeams));
  }
  if (!origins.empty() && origins.size() != n) bad("origins do not match the directions");
  if (!times.empty() && times.size() != n) bad("times do not match the directions");
  if (!lines.empty() && lines.size() != n) bad("lines do not match the directions");
  for (std::size_t i = 0; i < n; ++i) {
    if (!directions[i].allFinite() || std::abs(directions[i].norm() - 1) > 1e-9) {
      bad("direction of beam " + std::to_string(i) + " is not a finite unit vector");
    }
    if (!origins.empty() && !origins[i].allFinite()) {
      bad("origin of beam " + std::to_string(i) + " is not finite");
    }
    if (!times.empty() && !(std::isfinite(times[i]) && times[i] >= 0)) {
      std::ostringstream msg;
      msg << "time of beam " << i << " is " << times[i] << ", expected finite and >= 0";
      bad(msg.str());
    }
  }
}

void BeamList::append(const BeamList& other, int i) {
  directions.push_back(other.directions[i]);
  if (!other.origins.empty()) {
    origins.resize(directions.size() - 1, Eigen::Vector3d::Zero());
    origins.push_back(other.origins[i]);
  }
  if (!other.times.empty()) {
    times.resize(directions.size() - 1, 0.0);
    times.push_back(other.times[i]);
  }
  if (!other.lines.empty()) {
    lines.resize(directions.size() - 1, 0);
    lines.push_back(other.lines[i]);
  }
}

Eigen::Vector3d beamDirection(double azimuth, double elevation) {
  const double ce = std::cos(elevation), se = std::sin(elevation);
  return Eigen::Vector3d(ce * std::cos(azimuth), ce * std::sin(azimuth), se);
}

}  // namespace core
}  // namespace laser_raycast
