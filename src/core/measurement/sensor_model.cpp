#include "laser_raycast/core/sensor_model.h"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace laser_raycast {
namespace core {
namespace {

constexpr double degrees(double d) { return d * M_PI / 180.0; }

// count elevations evenly spaced from lowest to highest (degrees), ascending.
std::vector<double> uniformRings(double lowest_deg, double highest_deg, int count) {
  std::vector<double> rings(count);
  for (int r = 0; r < count; ++r) {
    rings[r] = degrees(lowest_deg + (highest_deg - lowest_deg) * r / (count - 1));
  }
  return rings;
}

// A full turn of n azimuths, each cast once: -pi to pi - 2 pi / n.
FanSpec fullTurn(int n) {
  FanSpec fan;
  fan.angle_increment = 2 * M_PI / n;
  fan.angle_min = -M_PI;
  fan.angle_max = M_PI - fan.angle_increment;
  return fan;
}

// A fan from first_deg to last_deg inclusive, spaced by increment_deg.
FanSpec sector(double first_deg, double last_deg, double increment_deg) {
  FanSpec fan;
  fan.angle_min = degrees(first_deg);
  fan.angle_max = degrees(last_deg);
  fan.angle_increment = degrees(increment_deg);
  return fan;
}

// A preset of that id and those elevations, its other fields to be filled by its maker below.
SensorModel blank(SensorModelId id, std::vector<double> elevations = {}) {
  return SensorModel{id, std::move(elevations), {}, 0, 0, 0, std::nullopt, false, std::nullopt, ""};
}

SensorModel vlp16() {
  SensorModel m = blank(SensorModelId::kVlp16);
  // Per the Velodyne VLP-16 user manual and datasheet: 16 channels, vertical field of view +15 to
  // -15 deg at 2.0 deg vertical resolution (the lasers' elevation table: -15, -13, ..., 13, 15).
  m.elevations = uniformRings(-15.0, 15.0, 16);
  // Per the VLP-16 user manual's rotation speed vs resolution table: 0.2 deg at 600 rpm. 600 rpm
  // (10 Hz) is a setting (5-20 Hz), the default of the sensor and of velodyne_driver's rpm. (One
  // firing sequence takes 55.296 us, so a real turn at 600 rpm holds about 1808 of them.)
  m.fan = fullTurn(1800);
  m.rate = 10.0;
  // Per the datasheet: range up to 100 m. The datasheet gives no minimum range; 0.4 m is the
  // min_range default of velodyne_pointcloud's launch files (a driver setting, not a sensor spec).
  m.range_max = 100.0;
  m.range_min = 0.4;
  // Per the user manual: the lasers by id (-15, 1, -13, 3, ... deg) fired 2.304 us apart, a
  // sequence every 55.296 us: the same 16 elevations as above, each at its own azimuth and time.
  m.head = nominalVlp16();
  return m;
}

SensorModel hdl32e() {
  SensorModel m = blank(SensorModelId::kHdl32e);
  // Per the Velodyne HDL-32E user manual and datasheet: 32 lasers, vertical field of view +10.67
  // to -30.67 deg at 1.33 deg vertical resolution. The published table is spaced by exactly 4/3
  // deg with 0 deg as the 24th laser from the bottom: -92/3 (-30.67) to 32/3 (10.67) deg.
  m.elevations = uniformRings(-92.0 / 3.0, 32.0 / 3.0, 32);
  // Per the user manual: the 32 lasers fire in a cycle of 46.08 us; at 600 rpm (10 Hz, a setting:
  // 5-20 Hz, the sensor's default) a turn holds 0.1 s / 46.08 us = 2170 cycles, 0.166 deg apart.
  m.fan = fullTurn(2170);
  m.rate = 10.0;
  // Per the datasheet: range up to 100 m. No minimum range is specified; 0.4 m is velodyne_
  // pointcloud's min_range launch default, as for the VLP-16.
  m.range_max = 100.0;
  m.range_min = 0.4;
  // Per the user manual: the lasers by id (-30.67, -9.33, -29.33, ... deg) fired 1.152 us apart,
  // a cycle every 46.08 us: the elevations above, rounded as the manual's table gives them.
  m.head = nominalHdl32e();
  return m;
}

SensorModel os1_64() {
  SensorModel m = blank(SensorModelId::kOs1_64);
  // Per the Ouster OS1 datasheet (first generation, 64 channels): vertical field of view +16.6 to
  // -16.6 deg (33.2 deg), beams spaced uniformly (0.527 deg). Later OS1 revisions (45 deg, and
  // gradient or below-horizon spacing) are other sensors; give their elevations explicitly.
  // Ouster's client code lists the design angles as +-16.611 deg, within 0.011 deg of these.
  m.elevations = uniformRings(-16.6, 16.6, 64);
  // Per the datasheet: horizontal resolution 512, 1024 or 2048 and rotation 10 or 20 Hz,
  // configurable; 1024 at 10 Hz is the sensor's default lidar mode ("1024x10").
  m.fan = fullTurn(1024);
  m.rate = 10.0;
  // Per the datasheet: range 0.8 m to 120 m (80% reflective Lambertian target).
  m.range_min = 0.8;
  m.range_max = 120.0;
  // Per the same datasheet (its optical performance and laser sections): 0.8 m to 40 m on a 10%
  // reflective Lambertian target (100 klx sunlight, false positive rate 1/10,000; the 80% pair,
  // 120 m, asks a little less: rho / R^2 of 5.6e-5 against 6.3e-5); beam divergence 0.13 deg
  // (FWHM, 64 and 16 channels); range resolution 1.2 cm; 1 return, the strongest. Seven sub-rays:
  // the footprint's centre and a ring of six (ReturnsConfig).
  m.realism = SensorModel::Realism{40.0, 0.1, degrees(0.13), 7, ReturnMode::kStrongest, 0.012};
  // The beams as ouster-sdk places them: the nominal metadata file written from the datasheet by
  // scripts/make_ouster_metadata (the rows above, the detector's four azimuth offsets, the beam
  // origins and the lidar-to-sensor transform the sensors report; its docstring gives each
  // value's source).
  m.head_file = "package://laser_raycast/config/ouster/os1_64_nominal.json";
  return m;
}

SensorModel utm30lx() {
  SensorModel m = blank(SensorModelId::kUtm30lx, {0.0});
  // Per the Hokuyo UTM-30LX specification and its SCIP 2.0 protocol: 270 deg scan, 1440 steps a
  // turn (0.25 deg), steps 0..1080 with the front at step 540: -135 to +135 deg, 1081 beams.
  m.fan = sector(-135.0, 135.0, 0.25);
  // Per the specification: scan time 25 ms (40 Hz), fixed.
  m.rate = 40.0;
  // Per the specification: guaranteed detection range 0.1 to 30 m (white paper); it may report
  // up to 60 m (its maximum), which explicit range_max can select.
  m.range_min = 0.1;
  m.range_max = 30.0;
  return m;
}

SensorModel tim571() {
  SensorModel m = blank(SensorModelId::kTim571, {0.0});
  // Per the SICK TiM571 product data sheet: aperture angle 270 deg, angular resolution 0.33 deg
  // (a third of a degree: 811 beams from -135 to +135 deg, as the sick_tim driver publishes).
  m.fan = sector(-135.0, 135.0, 1.0 / 3.0);
  // Per the data sheet: scanning frequency 15 Hz, fixed.
  m.rate = 15.0;
  // Per the data sheet: operating range 0.05 m to 25 m.
  m.range_min = 0.05;
  m.range_max = 25.0;
  return m;
}

SensorModel lds01() {
  SensorModel m = blank(SensorModelId::kLds01, {0.0});
  // Per the ROBOTIS LDS-01 (HLS-LFCD2) specification: angular range 360 deg, angular resolution
  // 1 deg. Its driver (hls_lfcd_lds_driver) publishes 360 beams from 0 to 359 deg.
  m.fan = sector(0.0, 359.0, 1.0);
  // Per the specification: scan rate 300 rpm +-10% (5 Hz).
  m.rate = 5.0;
  // Per the specification: distance range 120 mm to 3,500 mm.
  m.range_min = 0.12;
  m.range_max = 3.5;
  return m;
}

}  // namespace

std::string SensorModel::name() const {
  return std::string(toString(id)) + (realistic ? kRealisticSuffix : "");
}

void SensorModel::apply(ScanSpec* spec, double* rate_out) const {
  spec->fan = fan;
  spec->elevations = elevations;
  spec->output.range_min = range_min;
  spec->output.range_max = range_max;
  if (realistic) {
    spec->output.detection_range = realism->detection_range;
    spec->output.detection_reflectivity = realism->detection_reflectivity;
  }
  *rate_out = rate;
}

void SensorModel::applyReturns(ReturnsConfig* returns) const {
  if (!realistic) return;
  returns->beam_divergence = realism->beam_divergence;
  returns->beam_samples = realism->beam_samples;
  returns->return_mode = realism->return_mode;
  returns->min_return_separation = realism->min_return_separation;
}

SensorModel sensorModel(SensorModelId id) {
  switch (id) {
    case SensorModelId::kVlp16:
      return vlp16();
    case SensorModelId::kHdl32e:
      return hdl32e();
    case SensorModelId::kOs1_64:
      return os1_64();
    case SensorModelId::kUtm30lx:
      return utm30lx();
    case SensorModelId::kTim571:
      return tim571();
    case SensorModelId::kLds01:
      return lds01();
  }
  // A value cast from a bad integer.
  throw std::invalid_argument("sensorModel: no sensor model has id " +
                              std::to_string(static_cast<int>(id)));
}

namespace {

// The base name of a realistic variant's name ("" if name is none).
std::string variantBase(const std::string& name) {
  const std::string suffix = kRealisticSuffix;
  if (name.size() <= suffix.size() ||
      name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0) {
    return "";
  }
  return name.substr(0, name.size() - suffix.size());
}

}  // namespace

std::optional<SensorModel> findSensorModel(const std::string& name) {
  SensorModelId id;
  if (kSensorModelNames.parse(name, &id)) return sensorModel(id);
  if (!kSensorModelNames.parse(variantBase(name), &id)) return std::nullopt;
  SensorModel model = sensorModel(id);
  if (!model.realism) return std::nullopt;
  model.realistic = true;
  return model;
}

std::string sensorModelProblem(const std::string& name) {
  SensorModelId id;
  if (kSensorModelNames.parse(variantBase(name), &id) && !sensorModel(id).realism) {
    return "'" + name + "': " + toString(id) +
           " has no realistic variant (the datasheet this package cites gives no reflectivity for "
           "its range, or no divergence: set detection_range, detection_reflectivity and "
           "beam_divergence yourself)";
  }
  std::string variants;
  for (const auto& [preset, preset_name] : kSensorModelNames.entries()) {
    if (sensorModel(preset).realism) {
      variants += std::string(variants.empty() ? "" : ", ") + preset_name + kRealisticSuffix;
    }
  }
  return kSensorModelNames.notOneOf(name) + " (or a realistic variant: " + variants + ")";
}

}  // namespace core
}  // namespace laser_raycast
