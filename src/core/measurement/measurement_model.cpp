#include "laser_raycast/core/measurement_model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace laser_raycast {
namespace core {

void MeasurementConfig::validate() const {
  std::ostringstream msg;
  if (!(std::isfinite(range_min) && range_min >= 0)) {
    msg << "range_min must be finite and >= 0, got " << range_min;
  } else if (!(std::isfinite(range_max) && range_max > range_min)) {
    msg << "range_max (" << range_max << " m) must be finite and greater than range_min ("
        << range_min << " m)";
  } else if (!(range_max <= std::numeric_limits<float>::max())) {
    // Ranges are published as float: beyond this a valid reading would round to +Inf (no return).
    msg << "range_max (" << range_max << " m) must be representable as a float (at most "
        << std::numeric_limits<float>::max() << " m)";
  } else if (!(std::isfinite(noise_stddev) && noise_stddev >= 0)) {
    msg << "noise_stddev must be finite and >= 0, got " << noise_stddev;
  } else if (!std::isfinite(range_bias)) {
    msg << "range_bias must be finite, got " << range_bias;
  } else if (!(std::isfinite(range_resolution) && range_resolution >= 0)) {
    msg << "range_resolution must be finite and >= 0, got " << range_resolution;
  } else if (!(dropout_probability >= 0 && dropout_probability <= 1)) {
    msg << "dropout_probability must be in [0, 1], got " << dropout_probability;
  } else if (!(std::isfinite(detection_range) && detection_range >= 0)) {
    msg << "detection_range must be finite and >= 0 m, got " << detection_range;
  } else if (!(std::isfinite(detection_reflectivity) && detection_reflectivity > 0)) {
    msg << "detection_reflectivity must be finite and > 0, got " << detection_reflectivity;
  } else if (!(std::isfinite(reflectance_from_color) && reflectance_from_color >= 0)) {
    msg << "reflectance_from_color must be finite and >= 0, got " << reflectance_from_color;
  } else {
    return;
  }
  throw std::invalid_argument(msg.str());
}

double classifyRange(double range, const MeasurementConfig& config) {
  if (std::isnan(range)) return range;
  if (!(range <= config.range_max)) return std::numeric_limits<double>::infinity();
  if (range < config.range_min) {
    switch (config.min_range_policy) {
      case MinRangePolicy::kNegInf:
        return -std::numeric_limits<double>::infinity();
      case MinRangePolicy::kNan:
        return std::numeric_limits<double>::quiet_NaN();
      case MinRangePolicy::kPassThrough:
        // The cast started at range_min, so this only happens if the caller cast from 0.
        return std::numeric_limits<double>::infinity();
    }
  }
  return range;
}

double quantizeRange(double range, const MeasurementConfig& config) {
  const double step = config.range_resolution;
  if (!(step > 0)) return range;
  return std::clamp(std::round(range / step) * step, config.range_min, config.range_max);
}

bool detected(double rho, double cos_incidence, double r, const MeasurementConfig& config) {
  if (config.detection_range == 0) return true;
  // rho cos / r^2 >= rho_d / R^2, multiplied out (no division by a zero range).
  const double R = config.detection_range;
  return rho * cos_incidence * R * R >= config.detection_reflectivity * r * r;
}

MeasurementModel::MeasurementModel(const MeasurementConfig& config) : config_(config), noise_(0.0, 1.0) {
  config_.validate();
  seed(config_.noise_seed);
}

void MeasurementModel::setConfig(const MeasurementConfig& config) {
  config.validate();
  const bool reseed = config.noise_seed != config_.noise_seed;
  config_ = config;
  if (reseed) seed(config_.noise_seed);
}

void MeasurementModel::seed(std::uint64_t seed) {
  rng_.seed(seed);
  dropout_rng_.seed(seed ^ kDropoutSeedMix);
  noise_.reset();  // drop a normal value cached from the old sequence
}

bool MeasurementModel::degrade(double* range) {
  double r = *range + config_.range_bias;
  if (config_.noise_stddev > 0) r += config_.noise_stddev * noise_(rng_);
  r = std::clamp(r, config_.range_min, config_.range_max);
  *range = quantizeRange(r, config_);
  if (config_.dropout_probability > 0) {
    // u in [0, 1) from the top 53 bits: exact and the same with every standard library.
    const double u = static_cast<double>(dropout_rng_() >> 11) * 0x1p-53;
    if (u < config_.dropout_probability) return false;
  }
  return true;
}

void MeasurementModel::measure(const Scene& scene, const ScanResult& result,
                         const std::vector<double>& reflectivity, MeasuredScan* out,
                         const SurfaceSamples* surface) {
  const std::size_t n = result.range.size();
  out->ranges.resize(n);
  out->labels.resize(n);
  const bool radiometry = config_.needsIncidence();
  if (radiometry) {
    if (result.cos_incidence.size() != n) {
      throw std::invalid_argument(
          "intensity and the detection range need the cast's cos_incidence (compute_incidence)");
    }
    if (surface && (surface->reflectance.size() != n || surface->cos_incidence.size() != n)) {
      throw std::invalid_argument("the surface samples are not of this scan");
    }
  }
  if (config_.intensity) {
    out->intensities.assign(n, 0.0f);
  } else {
    out->intensities.clear();
  }
  constexpr double kNoReturn = std::numeric_limits<double>::infinity();
  if (!radiometry && config_.isIdeal()) {
    // Nothing to degrade or detect (the defaults): a valid range is kept as it is, which is what
    // degrade() returns for it (classifyRange keeps only ranges in [range_min, range_max]).
    for (std::size_t i = 0; i < n; ++i) {
      const int body = result.body[i];
      out->labels[i] = body >= 0 ? scene.bodies()[body].label : -1;
      out->ranges[i] = static_cast<float>(classifyRange(result.range[i], config_));
    }
    return;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const int body = result.body[i];
    const int label = body >= 0 ? scene.bodies()[body].label : -1;
    out->labels[i] = label;
    double r = classifyRange(result.range[i], config_);
    bool valid = std::isfinite(r);
    // The hit's reflectance and incidence: the surface's where it gives them, else the label's.
    double rho = 0, cos_incidence = 0;
    if (radiometry && label >= 0) {
      rho = label < static_cast<int>(reflectivity.size()) ? reflectivity[label] : 1.0;
      cos_incidence = result.cos_incidence[i];
      if (surface) {
        if (!std::isnan(surface->reflectance[i])) rho = surface->reflectance[i];
        cos_incidence = surface->cos_incidence[i];
      }
    }
    if (valid && !detected(rho, cos_incidence, result.range[i], config_)) {
      valid = false;  // too weak: no return, and no random draws
      r = kNoReturn;
      out->labels[i] = -1;
    } else if (valid && !degrade(&r)) {
      valid = false;
      r = kNoReturn;  // lost: no return
      out->labels[i] = -1;
    }
    out->ranges[i] = static_cast<float>(r);  // the one rounding to float
    if (config_.intensity && valid && label >= 0) {
      out->intensities[i] = static_cast<float>(rho * cos_incidence);
    }
  }
}

}  // namespace core
}  // namespace laser_raycast
