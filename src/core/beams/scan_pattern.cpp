#include "laser_raycast/core/scan_pattern.h"

#include <iomanip>
#include <sstream>
#include <stdexcept>

namespace laser_raycast {
namespace core {
namespace {

[[noreturn]] void fail(const std::ostringstream& msg) { throw std::invalid_argument(msg.str()); }

}  // namespace

void FanSpec::validate() const {
  std::ostringstream msg;
  if (!std::isfinite(angle_min)) {
    msg << "angle_min must be finite, got " << angle_min;
    fail(msg);
  }
  if (!std::isfinite(angle_max)) {
    msg << "angle_max must be finite, got " << angle_max;
    fail(msg);
  }
  if (!(angle_max > angle_min)) {
    msg << "angle_max (" << angle_max << " rad) must be greater than angle_min (" << angle_min
        << " rad)";
    fail(msg);
  }
  const bool has_increment = angle_increment != 0, has_samples = samples != 0;
  if (has_increment == has_samples) {
    msg << "give exactly one of angle_increment and samples (got angle_increment "
        << angle_increment << " rad, samples " << samples << ")";
    fail(msg);
  }
  if (has_increment) {
    if (!(std::isfinite(angle_increment) && angle_increment > 0)) {
      msg << "angle_increment must be finite and > 0, got " << angle_increment;
      fail(msg);
    }
    const double n = std::round((angle_max - angle_min) / angle_increment) + 1;
    if (!(n <= kMaxBeams)) {
      msg << "angle_increment " << angle_increment << " rad gives " << std::fixed
          << std::setprecision(0) << n << std::defaultfloat << std::setprecision(6)
          << " beams over [" << angle_min << ", " << angle_max << "] rad; at most " << kMaxBeams
          << " are allowed";
      fail(msg);
    }
  } else if (samples < 2 || samples > kMaxBeams) {
    msg << "samples must be in [2, " << kMaxBeams << "], got " << samples;
    fail(msg);
  }
}

int FanSpec::beamCount() const {
  if (samples != 0) return samples;
  return static_cast<int>(std::round((angle_max - angle_min) / angle_increment)) + 1;
}

double FanSpec::increment() const {
  if (samples != 0) return (angle_max - angle_min) / (samples - 1);
  return angle_increment;
}

ScanPattern::ScanPattern(const FanSpec& fan) : ScanPattern(fan, std::vector<double>{0.0}) {}

ScanPattern::ScanPattern(const FanSpec& fan, std::vector<double> elevations)
    : elevations_(std::move(elevations)) {
  fan.validate();
  if (elevations_.empty()) throw std::invalid_argument("elevations must not be empty");
  for (std::size_t r = 0; r < elevations_.size(); ++r) {
    if (!(std::abs(elevations_[r]) <= M_PI / 2)) {
      std::ostringstream msg;
      msg << "elevation " << r << " must be in [-pi/2, pi/2] rad, got " << elevations_[r];
      fail(msg);
    }
  }
  angle_min_ = fan.angle_min;
  angle_increment_ = fan.increment();
  azimuth_count_ = fan.beamCount();
  if (static_cast<double>(azimuth_count_) * elevations_.size() > FanSpec::kMaxBeams) {
    std::ostringstream msg;
    msg << azimuth_count_ << " azimuths x " << elevations_.size() << " rings exceeds "
        << FanSpec::kMaxBeams << " beams";
    fail(msg);
  }
  directions_.reserve(static_cast<std::size_t>(azimuth_count_) * elevations_.size());
  for (const double elevation : elevations_) {
    const double ce = std::cos(elevation), se = std::sin(elevation);
    for (int i = 0; i < azimuth_count_; ++i) {
      const double a = azimuth(i);
      directions_.emplace_back(ce * std::cos(a), ce * std::sin(a), se);
    }
  }
}

}  // namespace core
}  // namespace laser_raycast
