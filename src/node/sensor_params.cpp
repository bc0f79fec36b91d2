#include "sensor_params.h"

#include <ros/names.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "laser_raycast/core/sensor_model.h"
#include "laser_raycast/loader/ouster_metadata.h"
#include "laser_raycast/loader/package_resolver.h"
#include "laser_raycast/loader/velodyne_calibration.h"

namespace laser_raycast {
namespace {

// The beam count comes from exactly one of angle_increment and samples; with neither, from the
// fallback fan (a preset's, or an entry's defaults) or else core::FanSpec::kDefaultSamples. The
// core checks the angles and the beam count. Returns the name of the parameter the beam count came
// from.
const char* readFan(ParamReader* r, core::FanSpec* fan) {
  fan->angle_min = r->number("angle_min", fan->angle_min, "rad");
  fan->angle_max = r->number("angle_max", fan->angle_max, "rad");
  const bool has_increment = r->has("angle_increment"), has_samples = r->has("samples");
  if (has_increment && has_samples) {
    r->fail("samples", "set " + r->prefix() + "angle_increment or " + r->prefix() +
                           "samples, not both (got angle_increment " +
                           describeValue(*r->get("angle_increment")) + " and samples " +
                           describeValue(*r->get("samples")) + ")");
  }
  if (has_increment) {
    fan->angle_increment = r->number("angle_increment", 0.0, "rad");
    fan->samples = 0;
    r->note(r->prefix() + "samples unset (beams from " + r->prefix() + "angle_increment)");
  } else if (has_samples || fan->angle_increment == 0) {
    const int fallback = fan->samples > 0 ? fan->samples : core::FanSpec::kDefaultSamples;
    fan->samples = r->integer("samples", fallback, "beams");
    fan->angle_increment = 0;
    r->note(r->prefix() + "angle_increment unset (beams from " + r->prefix() + "samples)");
  } else {
    // The fallback's spacing: a preset's (or, in an entry, the private namespace's).
    fan->angle_increment = r->number("angle_increment", fan->angle_increment, "rad");
    r->note(r->prefix() + "samples unset (beams from " + r->prefix() + "angle_increment)");
  }
  return has_increment || fan->angle_increment != 0 ? "angle_increment" : "samples";
}

// A message of the core's validate() goes out under the parameter it is about: the core's
// messages start with the field's name (with an index for one element of a list), and the
// fields are named as the parameters are ("parameter ~samples: samples must be in [2, 10000000],
// got 1"). One that starts with no parameter's name goes out under beams_from, the parameter the
// beam count came from: the core's "give exactly one of angle_increment and samples" for a 0,
// which FanSpec reads as unset, and the beam count of all rings together.
void failWithCoreMessage(ParamReader* r, const std::string& message, const char* beams_from) {
  const std::string field = message.substr(0, message.find_first_of(" ("));
  const std::string name = field.substr(0, field.find('['));
  const std::vector<std::string>& known = r->known();
  const bool is_parameter = std::find(known.begin(), known.end(), name) != known.end();
  r->fail(is_parameter ? field : beams_from, message);
}

// ~elevations: one fan per elevation (rad, any order); [0] is a planar scanner. Empty, non-finite,
// out-of-range or repeated values are the core's to refuse (ScanSpec::validate, below).
void readElevations(ParamReader* r, core::ScanSpec* scan) {
  scan->elevations = r->numberList("elevations", scan->elevations, "rad");
}

// ~sensor_model: a preset's pattern, range limits and rate (and a realistic variant's detection
// pair, divergence and returns), before the explicit parameters.
void readSensorModel(ParamReader* r, SensorParams* s) {
  s->sensor_model = r->text("sensor_model", s->sensor_model);
  if (s->sensor_model.empty()) return;
  const std::optional<core::SensorModel> model = core::findSensorModel(s->sensor_model);
  if (!model) {
    r->fail("sensor_model", core::sensorModelProblem(s->sensor_model));
    return;
  }
  model->apply(&s->scan, &s->rate);
  model->applyReturns(&s->returns);
}

// What the sensor reports: range limits, min-range policy, noise, intensity; and how it casts.
void readOutput(ParamReader* r, core::ScanSpec* scan) {
  core::MeasurementConfig& out = scan->output;
  out.range_min = r->number("range_min", out.range_min, "m");
  out.range_max = r->number("range_max", out.range_max, "m");
  out.min_range_policy =
      r->choice("min_range_policy", out.min_range_policy, core::kMinRangePolicyNames);
  out.noise_stddev = r->number("noise_stddev", out.noise_stddev, "m");
  const int seed = r->integer("noise_seed", static_cast<int>(out.noise_seed), "");
  if (seed < 0) r->fail("noise_seed", "must be >= 0, got " + std::to_string(seed));
  out.noise_seed = static_cast<std::uint64_t>(std::max(seed, 0));
  out.intensity = r->choice("intensity", out.intensity, kIntensityNames);
  out.surface_reflectance = r->boolean("surface_reflectance", out.surface_reflectance);
  out.reflectance_from_color = r->number("reflectance_from_color", out.reflectance_from_color, "");
  out.detection_range = r->number("detection_range", out.detection_range, "m");
  out.detection_reflectivity =
      r->number("detection_reflectivity", out.detection_reflectivity, "");
  out.range_bias = r->number("range_bias", out.range_bias, "m");
  out.range_resolution = r->number("range_resolution", out.range_resolution, "m");
  out.dropout_probability = r->number("dropout_probability", out.dropout_probability, "");
  scan->method = r->choice("method", scan->method, core::kTriangleMethodNames);
  scan->cull_backfaces = r->boolean("cull_backfaces", scan->cull_backfaces);
}

// Beam divergence and returns (core/returns.h).
void readReturns(ParamReader* r, core::ReturnsConfig* returns) {
  returns->beam_divergence = r->number("beam_divergence", returns->beam_divergence, "rad");
  returns->beam_samples = r->integer("beam_samples", returns->beam_samples, "");
  returns->return_mode = r->choice("return_mode", returns->return_mode, core::kReturnModeNames);
  returns->min_return_separation =
      r->number("min_return_separation", returns->min_return_separation, "m");
}

void readRate(ParamReader* r, SensorParams* s) {
  s->rate = r->number("rate", s->rate, "Hz");
  if (!(std::isfinite(s->rate) && s->rate > 0 && s->rate <= SensorParams::kMaxRate)) {
    r->fail("rate", "must be in (0, " + formatNumber(SensorParams::kMaxRate) + "] Hz, got " +
                        formatNumber(s->rate));
  }
}

// When the beams are taken, and how a 3D scan is published.
void readSweep(ParamReader* r, SensorParams* s, std::vector<std::string>* warnings) {
  s->sweep = r->choice("sweep", s->sweep, kSweepNames);
  if (r->has("scan_time")) {
    s->scan_time = r->number("scan_time", 0.0, "s");
    // One head turns once per scan: a turn longer than the period would overlap the next scan.
    const double period = 1.0 / s->rate;
    if (!(std::isfinite(s->scan_time) && s->scan_time > 0 && s->scan_time <= period)) {
      r->fail("scan_time", "must be in (0, 1 / " + r->prefix() + "rate] = (0, " +
                               formatNumber(period) + "] s, got " + formatNumber(s->scan_time));
    }
    if (s->sweep == Sweep::kInstant) {
      warnings->push_back(r->prefix() + "scan_time has no effect with " + r->prefix() +
                          "sweep 'instant'");
    }
  } else if (s->scan_time > 0) {
    r->note(r->prefix() + "scan_time = " + formatNumber(s->scan_time) + " s");
  } else {
    r->note(r->prefix() + "scan_time unset (1 / " + r->prefix() + "rate)");
  }
  s->organized = r->boolean("organized", s->organized);
  s->point_layout = r->choice("point_layout", s->point_layout, kPointLayoutNames);
}

// Where the sensor pose comes from: TF, or a topic giving the pose of pose_frame.
void readPoseSource(ParamReader* r, SensorParams* s) {
  s->pose_topic = r->text("pose_topic", s->pose_topic);
  if (!s->pose_topic.empty()) checkTopic(r, "pose_topic", s->pose_topic);
  s->pose_frame = r->text("pose_frame", s->pose_frame);
  checkFrame(r, "pose_frame", s->pose_frame, true);
  if (!s->pose_frame.empty() && s->pose_topic.empty()) {
    r->fail("pose_frame", "is set to '" + s->pose_frame + "' but " + r->prefix() +
                              "pose_topic is not (pose_frame names the frame whose pose the "
                              "topic gives)");
  }
  // .inf (YAML) never times out, for a pose source that publishes only when the pose changes.
  s->pose_timeout = r->number("pose_timeout", s->pose_timeout, "s");
  if (!(s->pose_timeout > 0)) {
    r->fail("pose_timeout",
            "must be > 0 s (.inf: never stale), got " + formatNumber(s->pose_timeout));
  }
}

// Makes head the sensor's beams: one turn of scanTime() now, and head_turn for a turn of another
// length (a live rate change). Throws what the head's scan throws.
template <class Head>
void fireHead(const Head& head, SensorParams* s) {
  s->head_turn = [head](double scan_time) { return head.scan(scan_time); };
  s->calibrated = std::make_shared<const core::BeamList>(s->head_turn(s->scanTime()));
}

// ~calibration_file: a calibrated Velodyne head's beams instead of the fan.
void readCalibration(ParamReader* r, SensorParams* s) {
  s->calibration_file = r->text("calibration_file", s->calibration_file);
  if (s->calibration_file.empty()) {
    s->calibrated.reset();
    s->head_turn = nullptr;
    return;
  }
  if (!s->pattern_file.empty()) {
    r->fail("calibration_file", "is set and so is " + r->prefix() + "pattern_file: give one");
    return;
  }
  try {
    fireHead(loadVelodyneCalibration(s->calibration_file), s);
  } catch (const std::invalid_argument& e) {
    r->fail("calibration_file", e.what());
  }
}

// ~ouster_metadata: an Ouster head's beams instead of the fan. Its columns' times follow the
// sensor's scan_time, not the metadata's lidar_mode (a warning says when they differ).
void readOusterMetadata(ParamReader* r, SensorParams* s, std::vector<std::string>* warnings) {
  s->ouster_metadata = r->text("ouster_metadata", s->ouster_metadata);
  if (s->ouster_metadata.empty()) return;
  const char* other = !s->pattern_file.empty()       ? "pattern_file"
                      : !s->calibration_file.empty() ? "calibration_file"
                                                     : nullptr;
  if (other) {
    r->fail("ouster_metadata", "is set and so is " + r->prefix() + other + ": give one");
    return;
  }
  try {
    const core::OusterHead head = loadOusterMetadata(s->ouster_metadata);
    fireHead(head, s);
    if (std::abs(head.fps * s->scanTime() - 1) > 1e-6) {
      warnings->push_back(r->prefix() + "ouster_metadata: the file's lidar mode turns at " +
                          formatNumber(head.fps) + " Hz, the sensor once in " +
                          formatNumber(s->scanTime()) + " s (" + r->prefix() +
                          "scan_time or 1 / " + r->prefix() +
                          "rate); its columns follow the sensor's");
    }
  } catch (const std::invalid_argument& e) {
    r->fail("ouster_metadata", e.what());
  }
}

// A preset's beams as the sensor fires them (core::SensorModel::head, or head_file's Ouster head),
// one turn of scanTime(), unless a file gives the beams or the fan, the elevations or divergent
// beams are set (a note says so: the preset is then the grid of its elevations, every ring at the
// same azimuths, a column at once).
void readPresetHead(ParamReader* r, SensorParams* s) {
  s->preset_head = false;
  if (s->sensor_model.empty() || s->calibrated || s->pattern) return;
  const std::optional<core::SensorModel> model = core::findSensorModel(s->sensor_model);
  if (!model || !(model->head || !model->head_file.empty())) return;
  const char* grid_by = nullptr;
  for (const char* name : {"elevations", "samples", "angle_increment", "angle_min", "angle_max"}) {
    if (!grid_by && r->has(name)) grid_by = name;
  }
  const std::string as_grid = s->sensor_model +
                              "'s lasers as a grid (every ring at the same azimuths, a column at " +
                              "once)";
  if (grid_by) {
    r->note(r->prefix() + grid_by + " is set: " + as_grid);
    return;
  }
  if (s->returns.beam_samples > 1) {
    // Divergent beams are cast for grids only (set here, or by a realistic variant).
    r->note(r->prefix() + "beam_samples is " + std::to_string(s->returns.beam_samples) + ": " +
            as_grid);
    return;
  }
  if (model->head) {
    try {
      fireHead(*model->head, s);
    } catch (const std::invalid_argument& e) {
      // A turn too slow for a list (a VLP-16's over 34.56 s: 10M beams).
      r->fail("sensor_model", "'" + s->sensor_model + "' over one turn of " +
                                  formatNumber(s->scanTime()) + " s: " + e.what());
      return;
    }
  } else {
    try {
      fireHead(loadOusterMetadata(resolvePackageUri(model->head_file, rosPackagePath)), s);
    } catch (const std::exception& e) {
      // The package's own file: missing or unreadable only in a broken installation.
      r->fail("sensor_model", "'" + s->sensor_model + "': its beams' file " + model->head_file +
                                  " (part of this package): " + e.what());
      return;
    }
  }
  s->preset_head = true;
}

// ~pattern_file, ~points_per_scan, ~point_rate: beams from a scan pattern file instead of the fan.
void readPatternFile(ParamReader* r, SensorParams* s) {
  s->pattern_file = r->text("pattern_file", s->pattern_file);
  s->points_per_scan = r->integer("points_per_scan", s->points_per_scan, "points");
  s->point_rate = r->number("point_rate", s->point_rate, "Hz");
  if (s->pattern_file.empty()) {
    s->pattern.reset();
    for (const char* name : {"points_per_scan", "point_rate"}) {
      if (r->has(name))
        r->fail(name, std::string("is set but ") + r->prefix() + "pattern_file is not");
    }
    return;
  }
  if (!(std::isfinite(s->point_rate) && s->point_rate > 0)) {
    r->fail("point_rate", "must be > 0 Hz with a pattern_file, got " + formatNumber(s->point_rate));
  }
  if (s->points_per_scan < 0 || s->points_per_scan > core::FanSpec::kMaxBeams) {
    r->fail("points_per_scan", "must be in [0, " + std::to_string(core::FanSpec::kMaxBeams) +
                                   "] (0: the file's rows), got " +
                                   std::to_string(s->points_per_scan));
  }
  if (!s->pattern || r->has("pattern_file")) {
    try {
      s->pattern =
          std::make_shared<const core::PatternFile>(core::PatternFile::load(s->pattern_file));
    } catch (const std::invalid_argument& e) {
      r->fail("pattern_file", e.what());
      return;
    }
  }
  if (s->points_per_scan == 0) s->points_per_scan = s->pattern->size();
}

}  // namespace

void checkFrame(ParamReader* r, const std::string& name, const std::string& frame, bool optional) {
  if (frame.empty() && !optional) r->fail(name, "must not be empty");
  if (!frame.empty() && frame[0] == '/') {
    r->fail(name, "'" + frame + "': tf2 frame ids must not start with '/'");
  }
}

bool checkTopic(ParamReader* r, const std::string& name, const std::string& topic) {
  std::string why;
  if (!ros::names::validate(topic, why)) {
    r->fail(name, "'" + topic + "' is not a valid topic name: " + why);
    return false;
  }
  if (topic[0] == '~') {
    r->fail(name, "'" + topic + "': private topic names ('~') are not supported; give a name " +
                      "relative to the node's namespace or a global one");
    return false;
  }
  return true;
}

void readSensor(ParamReader* r, SensorParams* s, bool entry, std::vector<std::string>* warnings) {
  if (entry) {
    s->name = r->text("name", "");
    s->topic = r->text("topic", "");
    if (!r->has("frame_id")) {
      r->failWith("parameter " + r->prefix() + "frame_id: not set (each entry of ~sensors names " +
                  "its sensor frame)");
    }
  }
  readSensorModel(r, s);
  s->frame_id = r->text("frame_id", s->frame_id);
  checkFrame(r, "frame_id", s->frame_id, false);
  const char* beams_from = readFan(r, &s->scan.fan);
  readElevations(r, &s->scan);
  readOutput(r, &s->scan);
  readReturns(r, &s->returns);
  readRate(r, s);
  readSweep(r, s, warnings);
  readPoseSource(r, s);
  readPatternFile(r, s);
  readCalibration(r, s);
  readOusterMetadata(r, s, warnings);
  readPresetHead(r, s);
  if (s->returns.beam_samples > 1 && (s->pattern || s->calibrated)) {
    const char* file = s->pattern                      ? "pattern_file"
                       : !s->calibration_file.empty() ? "calibration_file"
                                                      : "ouster_metadata";
    r->fail("beam_samples", "is " + std::to_string(s->returns.beam_samples) + " but " +
                                r->prefix() + file +
                                " is set: divergent beams are cast for a fan or rings only");
  }
  // The angles and beam count, elevations, ranges, noise and realism: checked once, by the core.
  if (r->error().empty()) {
    try {
      s->scan.validate();
    } catch (const std::invalid_argument& e) {
      failWithCoreMessage(r, e.what(), beams_from);
    }
    try {
      s->returns.validate();
    } catch (const std::invalid_argument& e) {
      r->failWith(r->prefix() + e.what());
    }
  }
  // The layout's integer fields must hold every ring number and point time of the scan.
  if (r->error().empty() && !s->planar()) {
    // A pattern file's lines (at most 256) and its points' times, even when cast at once.
    const int rings = s->pattern      ? 256
                      : s->calibrated ? s->calibrated->lines.empty() ? 1 : 256
                                      : static_cast<int>(s->scan.elevations.size());
    const double last_time = s->pattern      ? (s->points_per_scan - 1) / s->point_rate
                             : s->calibrated ? s->calibrated->times.back()
                                             : s->sweepDuration();
    const std::string limit = pointLayoutLimit(s->point_layout, rings, last_time);
    if (!limit.empty()) r->fail("point_layout", limit);
  }
  const auto no_effect = [&](const char* name) {
    warnings->push_back(r->prefix() + name + " has no effect for a planar pattern (published as " +
                        "a LaserScan)");
  };
  if (s->planar() && s->organized) no_effect("organized");
  if (s->planar() && s->point_layout != PointLayout::kVelodyne) no_effect("point_layout");
}

double SensorParams::timeIncrement() const {
  if (sweep != Sweep::kRotating) return 0.0;
  return scan.fan.increment() * scanTime() / (2 * M_PI);
}

double SensorParams::sweepDuration() const {
  if (pattern) return sweep == Sweep::kRotating ? (points_per_scan - 1) / point_rate : 0.0;
  if (calibrated) return sweep == Sweep::kRotating ? calibrated->times.back() : 0.0;
  return sweep == Sweep::kRotating ? (scan.fan.beamCount() - 1) * timeIncrement() : 0.0;
}

}  // namespace laser_raycast
