// Presets of real sensors: the beam pattern, range limits and scan rate of a named lidar, taken
// from its datasheet and user manual (src/core/measurement/sensor_model.cpp says where each value
// comes from; docs/sensors.md lists them). A preset fills a ScanSpec; explicit settings then
// override single fields of it.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "laser_raycast/core/enum_names.h"
#include "laser_raycast/core/returns.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/scan_spec.h"
#include "laser_raycast/core/velodyne_beams.h"

namespace laser_raycast {
namespace core {

enum class SensorModelId {
  kVlp16,    // Velodyne VLP-16 (Puck): 16 rings, 360 deg
  kHdl32e,   // Velodyne HDL-32E: 32 rings, 360 deg
  kOs1_64,   // Ouster OS1-64, first generation, uniform beam spacing: 64 rings, 360 deg
  kUtm30lx,  // Hokuyo UTM-30LX: planar, 270 deg
  kTim571,   // SICK TiM571: planar, 270 deg
  kLds01,    // ROBOTIS LDS-01 (Hitachi-LG HLS-LFCD2), the TurtleBot3's: planar, 360 deg
};
// The names the sensor_model parameter takes: the makers' spellings.
inline const EnumNames<SensorModelId, 6> kSensorModelNames{{{
    {SensorModelId::kVlp16, "VLP-16"},
    {SensorModelId::kHdl32e, "HDL-32E"},
    {SensorModelId::kOs1_64, "OS1-64"},
    {SensorModelId::kUtm30lx, "UTM-30LX"},
    {SensorModelId::kTim571, "TiM571"},
    {SensorModelId::kLds01, "LDS-01"},
}}};
inline const char* toString(SensorModelId id) { return kSensorModelNames.name(id); }

struct SensorModel {
  SensorModelId id;
  // rad, ascending (ring r is the r-th lowest); {0} for a planar scanner.
  std::vector<double> elevations;
  // Azimuths as angle_min, angle_max and angle_increment (samples 0). A full turn runs from -pi
  // to pi - angle_increment, so that no azimuth is cast twice.
  FanSpec fan;
  double range_min = 0;  // m
  double range_max = 0;  // m
  double rate = 0;       // Hz: scans (head turns) per second
  // What the datasheet gives of the sensor's returns, where it gives it all: the detection pair
  // (range R at reflectivity rho of a Lambertian target), the beam's divergence and the return it
  // reports. The preset's "-realistic" variant applies them.
  struct Realism {
    double detection_range;         // m
    double detection_reflectivity;  // (0, 1]
    double beam_divergence;         // rad, full angle
    int beam_samples;               // sub-rays over the footprint (ReturnsConfig)
    ReturnMode return_mode;
    double min_return_separation;  // m: the datasheet's range resolution
  };
  std::optional<Realism> realism;
  bool realistic = false;  // this is the "-realistic" variant (realism is set)
  // The lasers as the sensor fires them, where the user manual publishes them (the Velodyne
  // presets: each laser's elevation by laser id and its firing time, velodyne_beams.h): the
  // preset's beams are then the head's turn (beams()), each laser at the azimuth its firing time
  // gives, and elevations x fan is the same lasers as a grid (every ring at the same azimuths, a
  // column at once), what a preset gives when its fan or elevations are set explicitly.
  std::optional<VelodyneHead> head;
  // Or an Ouster metadata file of this package (a package:// URI) whose head (OusterHead::scan)
  // the preset's beams are in the same way, for the loader to read ("" for none).
  std::string head_file;

  // "VLP-16", or "OS1-64-realistic" for the variant.
  std::string name() const;

  // Sets spec->fan, spec->elevations, spec->output.range_min and range_max, and *rate, and for
  // the realistic variant spec->output.detection_range and detection_reflectivity; leaves
  // everything else in spec (min-range policy, noise, intensity, method) as it was. Explicit
  // settings are applied afterwards by the caller; one that sets samples must clear
  // fan.angle_increment (and vice versa), since a FanSpec takes exactly one of them.
  void apply(ScanSpec* spec, double* rate) const;
  // For the realistic variant, sets the beam divergence, sub-rays, return mode and separation;
  // otherwise leaves returns as it was.
  void applyReturns(ReturnsConfig* returns) const;
  // The head's beams over one turn taking scan_time s (VelodyneHead::scan); head must be set.
  BeamList beams(double scan_time) const { return head->scan(scan_time); }
};

// The preset of that sensor.
SensorModel sensorModel(SensorModelId id);
// The suffix of a preset's realistic variant.
inline constexpr const char* kRealisticSuffix = "-realistic";
// The preset named `name` (exactly one of kSensorModelNames), or its realistic variant (the name
// and kRealisticSuffix, for a preset with realism); nullopt for anything else. The error message
// for an unknown name: sensorModelProblem(name).
std::optional<SensorModel> findSensorModel(const std::string& name);
// Why `name` names no preset: the names there are, or that the preset has no realistic variant and
// why.
std::string sensorModelProblem(const std::string& name);

}  // namespace core
}  // namespace laser_raycast
