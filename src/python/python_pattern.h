// What the Python module binds as Pattern (module.cpp): the beams of a scan, from a fan, a preset
// or a head's or pattern's file, read by the same readers as the node and cast_scan. Included by
// python_api.h only.
#pragma once

#include <pybind11/pybind11.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "laser_raycast/core/beam_list.h"
#include "laser_raycast/core/ouster_beams.h"
#include "laser_raycast/core/pattern_file.h"
#include "laser_raycast/core/scan_spec.h"
#include "laser_raycast/core/sensor_model.h"
#include "laser_raycast/loader/ouster_metadata.h"
#include "laser_raycast/loader/package_resolver.h"
#include "laser_raycast/loader/velodyne_calibration.h"

namespace py = pybind11;

namespace laser_raycast {
namespace python {

// The beams of a scan, and a preset's range limits if it came from one: a grid (a fan of azimuths
// at each elevation), or beams off any grid, each its own direction and origin (a calibrated
// head's turn, the same every scan; or a pattern file read as a loop, scan k of a cast taking its
// rows from k * points_per_scan on, as cast_scan --poses takes them).
struct Pattern {
  // A turn of a calibrated head cast at once unless scan_time says otherwise: 10 Hz, as cast_scan.
  static constexpr double kCalibratedScanTime = 0.1;  // s

  core::FanSpec fan;
  std::vector<double> elevations{0.0};
  std::optional<core::SensorModel> preset;
  core::ScanPattern pattern{core::FanSpec{-M_PI, M_PI, 0, 2}};
  std::shared_ptr<const core::BeamList> turn;     // a calibrated head's beams, or null
  std::shared_ptr<const core::PatternFile> file;  // a pattern file, or null
  int points_per_scan = 0;                        // with file: rows a scan takes
  double point_rate = 0;                          // with file: Hz
  std::string source;                             // the file off-grid beams came from

  bool offGrid() const { return turn || file; }
  int size() const {
    return turn ? turn->size() : file ? points_per_scan : static_cast<int>(pattern.size());
  }
  // Scan k's beams, off any grid (*scratch holds a pattern file's).
  const core::BeamList& beamsOf(std::int64_t k, core::BeamList* scratch) const {
    if (turn) return *turn;
    *scratch = file->scan(k * points_per_scan, points_per_scan, point_rate);
    return *scratch;
  }

  static Pattern make(double angle_min, double angle_max, std::optional<int> samples,
                      std::optional<double> angle_increment, std::vector<double> elevations) {
    Pattern p;
    p.fan.angle_min = angle_min;
    p.fan.angle_max = angle_max;
    if (samples.has_value() == angle_increment.has_value()) {
      throw py::value_error("give exactly one of samples and angle_increment");
    }
    p.fan.samples = samples.value_or(0);
    p.fan.angle_increment = angle_increment.value_or(0);
    p.elevations = std::move(elevations);
    p.build();
    return p;
  }

  static Pattern fromPreset(const std::string& name) {
    const std::optional<core::SensorModel> model = core::findSensorModel(name);
    if (!model) throw py::value_error("name: " + core::sensorModelProblem(name));
    if (model->realistic) {
      throw py::value_error("name: '" + name + "' is a realistic variant (detection pair, beam " +
                            "divergence and returns: the node's and simulate_bag's); its pattern " +
                            "is " + toString(model->id) + "'s: Pattern.preset(\"" +
                            toString(model->id) + "\")");
    }
    Pattern p;
    p.fan = model->fan;
    p.elevations = model->elevations;
    p.preset = model;
    p.build();
    // The beams as the sensor fires them, one turn at the preset's rate (as the node's preset).
    if (model->head) {
      p.turn = std::make_shared<const core::BeamList>(model->beams(1 / model->rate));
    } else if (!model->head_file.empty()) {
      try {
        const core::OusterHead head =
            loadOusterMetadata(resolvePackageUri(model->head_file, rosPackagePath));
        p.turn = std::make_shared<const core::BeamList>(head.scan(1 / model->rate));
      } catch (const std::exception& e) {
        throw py::value_error("name: '" + name + "': its beams' file " + model->head_file +
                              " (part of the package): " + e.what());
      }
    }
    if (p.turn) {
      p.source = name + " preset";
      p.offGridSpec();
    }
    return p;
  }

  // A Velodyne calibration YAML (as cast_scan --calibration reads it): one turn of scan_time s.
  static Pattern fromCalibration(const std::string& path, double scan_time) {
    checkScanTime(scan_time);
    return offGridTurn(path, [&] { return loadVelodyneCalibration(path).scan(scan_time); });
  }

  // An Ouster metadata JSON (as cast_scan --ouster-metadata reads it): one turn of scan_time s,
  // the file's lidar mode's if not given.
  static Pattern fromOusterMetadata(const std::string& path, std::optional<double> scan_time) {
    if (scan_time) checkScanTime(*scan_time);
    return offGridTurn(path, [&] {
      const core::OusterHead head = loadOusterMetadata(path);
      return head.scan(scan_time.value_or(1 / head.fps));
    });
  }

  // A scan pattern CSV (as cast_scan --pattern-file reads it): points_per_scan rows a scan (all
  // of them if not given), point k of a scan at k / point_rate s.
  static Pattern fromPatternFile(const std::string& path, double point_rate,
                                 std::optional<int> points_per_scan) {
    if (!(std::isfinite(point_rate) && point_rate > 0)) {
      throw py::value_error("point_rate must be > 0 Hz, got " + std::to_string(point_rate));
    }
    Pattern p;
    try {
      p.file = std::make_shared<const core::PatternFile>(core::PatternFile::load(path));
    } catch (const std::invalid_argument& e) {
      throw py::value_error(std::string("path: ") + e.what());
    }
    const int count = points_per_scan.value_or(p.file->size());
    if (count < 1 || count > core::FanSpec::kMaxBeams) {
      throw py::value_error("points_per_scan must be in [1, " +
                            std::to_string(core::FanSpec::kMaxBeams) + "], got " +
                            std::to_string(count));
    }
    p.points_per_scan = count;
    p.point_rate = point_rate;
    p.source = path;
    p.offGridSpec();
    return p;
  }

  // Validates as the node and cast_scan do (ScanSpec), with the rings in ascending order.
  void build() {
    core::ScanSpec spec;
    spec.fan = fan;
    spec.elevations = elevations;
    try {
      pattern = spec.pattern();
    } catch (const std::invalid_argument& e) {
      throw py::value_error(e.what());
    }
    elevations = spec.ringElevations();
  }

 private:
  static void checkScanTime(double scan_time) {
    if (!(std::isfinite(scan_time) && scan_time > 0 && scan_time <= 1)) {
      throw py::value_error("scan_time must be in (0, 1] s, got " + std::to_string(scan_time));
    }
  }
  template <typename Read>
  static Pattern offGridTurn(const std::string& path, Read&& read) {
    Pattern p;
    try {
      core::BeamList beams = read();
      beams.validate();
      p.turn = std::make_shared<const core::BeamList>(std::move(beams));
    } catch (const std::invalid_argument& e) {
      throw py::value_error(std::string("path: ") + e.what());
    }
    p.source = path;
    p.offGridSpec();
    return p;
  }
  // Off a grid the fan is not cast; the scan's settings are checked with cast_scan's default.
  void offGridSpec() {
    fan = core::FanSpec{};
    fan.samples = core::FanSpec::kDefaultSamples;
    elevations = {0.0};
  }
};

}  // namespace python
}  // namespace laser_raycast
