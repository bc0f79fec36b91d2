#include "laser_raycast/core/velodyne_beams.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "laser_raycast/core/scan_pattern.h"

namespace laser_raycast {
namespace core {

void VelodyneHead::validate() const {
  auto bad = [](const std::string& what) {
    throw std::invalid_argument("velodyne calibration: " + what);
  };
  if (lasers.empty()) bad("no lasers");
  std::vector<char> seen(lasers.size(), 0);
  for (std::size_t i = 0; i < lasers.size(); ++i) {
    const VelodyneLaser& l = lasers[i];
    const std::string which = "laser_id " + std::to_string(l.id);
    if (l.id < 0 || l.id >= static_cast<int>(lasers.size()) || seen[l.id]) {
      bad(which + ": ids must be 0 .. " + std::to_string(lasers.size() - 1) + ", each once");
    }
    seen[l.id] = 1;
    if (!std::isfinite(l.elevation) || std::abs(l.elevation) > M_PI / 2) {
      std::ostringstream msg;
      msg << which << ": vert_correction " << l.elevation << " rad is outside [-pi/2, pi/2]";
      bad(msg.str());
    }
    if (!std::isfinite(l.rot_correction) || !std::isfinite(l.vert_offset) ||
        !std::isfinite(l.horiz_offset)) {
      bad(which + ": a correction is not finite");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (lasers[j].elevation == l.elevation) {
        bad(which + " and laser_id " + std::to_string(lasers[j].id) +
            " have the same vert_correction (their rings would be ambiguous)");
      }
    }
  }
  if (!(timing.laser_period > 0) ||
      !(timing.sequence_period >= timing.laser_period * static_cast<double>(lasers.size()))) {
    bad("a firing sequence of " + std::to_string(lasers.size()) +
        " lasers does not fit its period");
  }
}

std::vector<int> VelodyneHead::rings() const {
  std::vector<int> order(lasers.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return lasers[a].elevation < lasers[b].elevation; });
  std::vector<int> ring(lasers.size());
  for (std::size_t r = 0; r < order.size(); ++r) ring[lasers[order[r]].id] = static_cast<int>(r);
  return ring;
}

BeamList VelodyneHead::scan(double scan_time, double start_azimuth) const {
  validate();
  const std::vector<int> ring = rings();
  std::vector<const VelodyneLaser*> by_id(lasers.size());
  for (const VelodyneLaser& l : lasers) by_id[l.id] = &l;
  if (!(std::isfinite(scan_time) && scan_time > 0)) {
    throw std::invalid_argument("velodyne head: a turn must take a finite time > 0 s");
  }
  // Refused before any is made: a slow turn of a dense head fires more beams than a list holds.
  const double fired = std::floor(scan_time / timing.sequence_period) * lasers.size();
  if (fired > FanSpec::kMaxBeams) {
    std::ostringstream msg;
    msg << "velodyne head: a turn of " << scan_time << " s fires " << static_cast<long long>(fired)
        << " beams, more than " << FanSpec::kMaxBeams;
    throw std::invalid_argument(msg.str());
  }
  const long sequences = std::max(1L, static_cast<long>(scan_time / timing.sequence_period));
  BeamList beams;
  const std::size_t n = static_cast<std::size_t>(sequences) * lasers.size();
  beams.directions.reserve(n);
  beams.origins.reserve(n);
  beams.times.reserve(n);
  beams.lines.reserve(n);
  for (long s = 0; s < sequences; ++s) {
    for (std::size_t i = 0; i < by_id.size(); ++i) {
      const VelodyneLaser& l = *by_id[i];
      const double t = s * timing.sequence_period + static_cast<double>(i) * timing.laser_period;
      // The head turns clockwise seen from above: its azimuth decreases with time.
      const double azimuth = start_azimuth - 2 * M_PI * t / scan_time + l.rot_correction;
      const double ce = std::cos(l.elevation), se = std::sin(l.elevation);
      const double ca = std::cos(azimuth), sa = std::sin(azimuth);
      beams.directions.emplace_back(ce * ca, ce * sa, se);
      // The driver's point at distance 0: the horizontal offset across the beam (to its left),
      // the vertical offset along the up direction perpendicular to it.
      beams.origins.emplace_back(-l.horiz_offset * sa - l.vert_offset * se * ca,
                                 l.horiz_offset * ca - l.vert_offset * se * sa, l.vert_offset * ce);
      beams.times.push_back(t);
      beams.lines.push_back(ring[l.id]);
    }
  }
  return beams;
}

namespace {

VelodyneHead nominal(const std::vector<double>& degrees, const VelodyneTiming& timing) {
  VelodyneHead head;
  head.timing = timing;
  for (std::size_t i = 0; i < degrees.size(); ++i) {
    VelodyneLaser l;
    l.id = static_cast<int>(i);
    l.elevation = degrees[i] * M_PI / 180;
    head.lasers.push_back(l);
  }
  return head;
}

}  // namespace

VelodyneHead nominalVlp16() {
  return nominal({-15, 1, -13, 3, -11, 5, -9, 7, -7, 9, -5, 11, -3, 13, -1, 15}, kVlp16Timing);
}

VelodyneHead nominalHdl32e() {
  return nominal(
      {-30.67, -9.33,  -29.33, -8.00,  -28.00, -6.67,  -26.67, -5.33,  -25.33, -4.00,  -24.00,
       -2.67,  -22.67, -1.33,  -21.33, 0.00,   -20.00, 1.33,   -18.67, 2.67,   -17.33, 4.00,
       -16.00, 5.33,   -14.67, 6.67,   -13.33, 8.00,   -12.00, 9.33,   -10.67, 10.67},
      kHdl32eTiming);
}

}  // namespace core
}  // namespace laser_raycast
