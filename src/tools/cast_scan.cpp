// cast_scan: simulated scans of URDF models and map worlds from a sensor pose, or from each pose of
// a path, printed as CSV. Needs no roscore: package:// URIs are resolved through ROS_PACKAGE_PATH.
// See synopsis(), flags() and the README; the path is cast_path.h's.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cast_path.h"
#include "command_line.h"
#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/measurement_model.h"
#include "laser_raycast/core/pattern_file.h"
#include "laser_raycast/core/returns.h"
#include "laser_raycast/core/scan_spec.h"
#include "laser_raycast/core/surface_reflectance.h"
#include "laser_raycast/loader/kinematics.h"
#include "laser_raycast/loader/map_file.h"
#include "laser_raycast/loader/ouster_metadata.h"
#include "laser_raycast/loader/package_resolver.h"
#include "laser_raycast/loader/scene_loader.h"
#include "laser_raycast/loader/velodyne_calibration.h"

namespace {

using laser_raycast::GeometrySource;
using laser_raycast::tools::ArgError;
using laser_raycast::tools::parseNumber;
using laser_raycast::tools::single;
namespace core = laser_raycast::core;
namespace po = boost::program_options;

using laser_raycast::tools::kExitBadArguments;
constexpr int kExitBadScene = 3;

struct Model {
  std::string path;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

struct Args {
  std::vector<Model> models;
  std::vector<Model> maps;  // map files (their path and pose), walls of map_height
  double map_height = laser_raycast::MapWallOptions::kDefaultHeight;  // m
  laser_raycast::tools::PathArgs path;  // the sensor poses: --sensor or --poses
  core::ScanSpec scan;  // the fan, ranges and method; REP 117 with the default -inf policy
  GeometrySource geometry = laser_raycast::LoaderOptions().geometry;
  laser_raycast::MeshImportBounds mesh_import;  // 0: from each file's size
  std::map<std::string, double> joints;
  int repeat = 0;
  int threads = core::CastConfig().threads;  // 0: every core
  bool rings = false;           // --elevations given: one fan per elevation, and the ring columns
  core::ReturnsConfig returns;  // divergent beams (core/returns.h); 1 sample: the ideal ray
  // Dual returns: a second row for a beam's last return, and the return column.
  bool dual() const {
    return returns.beam_samples > 1 && returns.return_mode == core::ReturnMode::kDual;
  }
  // --pattern-file: the beams of each scan from the file's next rows instead of a fan.
  std::string pattern_path;
  std::optional<core::PatternFile> pattern_file;
  int points_per_scan = 0;  // 0: the file's row count
  double point_rate = 0;    // Hz, > 0 with --pattern-file
  // --calibration: a Velodyne head's beams, one turn (the same every scan).
  std::string calibration_path;
  // --ouster-metadata: an Ouster head's beams, one turn (the same every scan).
  std::string ouster_path;
  std::optional<core::BeamList> calibrated;  // --calibration's or --ouster-metadata's
  // Beams off any grid: a pattern file's or a calibrated head's.
  bool offGrid() const { return pattern_file || calibrated; }
  // The radiometry (scan.output's intensity and detection range): each link's reflectivity by its
  // name (--reflectivity), the others' --default-reflectivity.
  std::map<std::string, double> reflectivity;
  double default_reflectivity = 1.0;
  bool radiometry() const { return scan.output.needsIncidence(); }
};

std::string formatNumber(double value) {
  if (std::isnan(value)) return "nan";  // printf may write "-nan"
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.9g", value);
  return buffer;
}

int parseCount(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || value < 0 || value > 1000000000L) {
    throw ArgError(flag + ": '" + text + "' is not a count (a non-negative integer)");
  }
  return static_cast<int>(value);
}

// "PATH" or "PATH@x,y,z,roll,pitch,yaw", of flag (--urdf or --map)
Model parseModel(const std::string& flag, const std::string& spec) {
  Model model;
  model.path = spec;
  const std::size_t at = spec.rfind('@');
  if (at != std::string::npos &&
      laser_raycast::tools::parsePose(spec.substr(at + 1), &model.pose)) {
    model.path = spec.substr(0, at);
  }
  if (model.path.empty()) throw ArgError(flag + ": empty path");
  return model;
}

// "E1,E2,...": radians, any order, at least one.
std::vector<double> parseElevations(const std::string& text) {
  std::vector<double> elevations;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    elevations.push_back(parseNumber("--elevations", text.substr(start, comma - start)));
    if (comma == std::string::npos) return elevations;
    start = comma + 1;
  }
}

// "NAME=VALUE"
void parseJoint(const std::string& spec, std::map<std::string, double>* joints) {
  const std::size_t eq = spec.find('=');
  if (eq == std::string::npos || eq == 0)
    throw ArgError("--joint: '" + spec + "' is not NAME=VALUE");
  (*joints)[spec.substr(0, eq)] = parseNumber("--joint " + spec.substr(0, eq), spec.substr(eq + 1));
}

GeometrySource parseGeometry(const std::string& name) {
  GeometrySource geometry;
  if (!laser_raycast::parseGeometrySource(name, &geometry)) {
    throw ArgError("--geometry: " + laser_raycast::kGeometrySourceNames.notOneOf(name));
  }
  return geometry;
}

core::TriangleMethod parseMethod(const std::string& name) {
  core::TriangleMethod method;
  if (!core::parseTriangleMethod(name, &method)) {
    throw ArgError("--method: " + core::kTriangleMethodNames.notOneOf(name));
  }
  return method;
}

// A flag that may be given several times, each value kept by store.
po::typed_value<std::vector<std::string>>* repeated(const char* value_name,
                                                    std::function<void(const std::string&)> store) {
  return po::value<std::vector<std::string>>()
      ->composing()
      ->value_name(value_name)
      ->notifier([store](const std::vector<std::string>& values) {
        for (const std::string& value : values) store(value);
      });
}

// A finite number in `unit` into *out, or a count into *out.
po::typed_value<std::string>* number(const char* flag, const char* unit, double* out) {
  return single(unit, [flag, out](const std::string& v) { *out = parseNumber(flag, v); });
}
po::typed_value<std::string>* count(const char* flag, int* out) {
  return single("N", [flag, out](const std::string& v) { *out = parseCount(flag, v); });
}

// Beams off any grid: a pattern file's, a Velodyne calibration's or an Ouster metadata file's.
void addBeamFileFlags(po::options_description_easy_init& add, Args* args) {
  add("pattern-file", single("FILE", [args](const std::string& v) { args->pattern_path = v; }),
      "a scan pattern CSV 'Time/s,Azimuth/deg,Zenith/deg[,Line]' read as a loop: each scan takes "
      "its next --points-per-scan rows instead of a fan");
  add("calibration", single("FILE", [args](const std::string& v) { args->calibration_path = v; }),
      "a Velodyne calibration YAML (velodyne_pointcloud's): each laser's beam, origin and firing "
      "time over one turn (--scan-time with --sweep rotating, else 0.1 s) instead of a fan");
  add("ouster-metadata", single("FILE", [args](const std::string& v) { args->ouster_path = v; }),
      "an Ouster sensor metadata JSON (legacy or nested): each row's beam and origin, each column "
      "at its time over one turn (--scan-time with --sweep rotating, else the file's lidar mode's) "
      "instead of a fan");
  add("points-per-scan", count("--points-per-scan", &args->points_per_scan),
      "rows of --pattern-file a scan takes (default: all of them)");
  add("point-rate", number("--point-rate", "HZ", &args->point_rate),
      "points a second of --pattern-file: point k of a scan at k / HZ s (required with it)");
}

// Divergent beams and their returns (core/returns.h).
void addReturnFlags(po::options_description_easy_init& add, Args* args) {
  add("beam-divergence", number("--beam-divergence", "RAD", &args->returns.beam_divergence),
      "full angle of a beam's footprint (with --beam-samples > 1)");
  add("beam-samples", count("--beam-samples", &args->returns.beam_samples),
      "sub-rays a beam (default 1: the ideal ray)");
  add("return-mode",
      single("NAME",
             [args](const std::string& v) {
               if (!core::kReturnModeNames.parse(v, &args->returns.return_mode)) {
                 throw ArgError("--return-mode: " + core::kReturnModeNames.notOneOf(v));
               }
             }),
      ("one of " + core::kReturnModeNames.list() +
       " (default strongest); dual prints a beam's last return as a second row, with a return "
       "column (1 strongest, 2 last)")
          .c_str());
  add("min-return-separation",
      number("--min-return-separation", "M", &args->returns.min_return_separation),
      "sub-ray hits closer in range merge into one return (default 0 m)");
}

// Intensity and the radiometric range limit (core/measurement_model.h).
void addRadiometryFlags(po::options_description_easy_init& add, Args* args) {
  core::MeasurementConfig& output = args->scan.output;
  add("intensity", po::bool_switch(&output.intensity),
      "print an intensity column: the reflectivity at the hit times the cosine of the incidence");
  add("detection-range",
      single("R@REFLECTIVITY",
             [&output](const std::string& v) {
               const std::size_t at = v.find('@');
               if (at == std::string::npos) {
                 throw ArgError("--detection-range: '" + v + "' is not R@REFLECTIVITY");
               }
               output.detection_range = parseNumber("--detection-range", v.substr(0, at));
               output.detection_reflectivity = parseNumber("--detection-range", v.substr(at + 1));
               if (!(output.detection_range > 0 && output.detection_reflectivity > 0)) {
                 throw ArgError("--detection-range: '" + v +
                                "' needs R > 0 m and REFLECTIVITY > 0");
               }
             }),
      "a datasheet's 'range R at reflectivity': returns weaker than its target's are lost (inf)");
  add("reflectivity",
      repeated("LINK=VALUE",
               [args](const std::string& v) {
                 const std::size_t eq = v.find('=');
                 if (eq == std::string::npos || eq == 0) {
                   throw ArgError("--reflectivity: '" + v + "' is not LINK=VALUE");
                 }
                 const double value =
                     parseNumber("--reflectivity " + v.substr(0, eq), v.substr(eq + 1));
                 if (!(value >= 0)) {
                   throw ArgError("--reflectivity " + v.substr(0, eq) + ": must be >= 0, got " +
                                  formatNumber(value));
                 }
                 args->reflectivity[v.substr(0, eq)] = value;
               }),
      "a link's reflectivity, over its mesh's colours (repeat for several links)");
  add("default-reflectivity",
      number("--default-reflectivity", "VALUE", &args->default_reflectivity),
      "the reflectivity of links without one and without colours (default 1)");
}

// The flags, in the order the help lists them. Values are read as text and converted by the
// notifiers into *args: the messages then say what is wrong with a value (program_options' own
// say only that it is invalid), and a number must be finite.
po::options_description flags(Args* args) {
  po::options_description options("Options");
  auto add = options.add_options();
  add("urdf",
      repeated("PATH[@POSE]",
               [args](const std::string& v) { args->models.push_back(parseModel("--urdf", v)); }),
      "a URDF file or package:// URI, placed at POSE x,y,z,roll,pitch,yaw (default: the "
      "identity); repeat for several models");
  add("map",
      repeated("PATH[@POSE]",
               [args](const std::string& v) { args->maps.push_back(parseModel("--map", v)); }),
      "a map_server map file (YAML) or package:// URI: walls over its occupied cells, its frame "
      "at POSE (default: the identity); repeat for several maps");
  add("map-height", number("--map-height", "M", &args->map_height),
      ("the walls' height, > 0 (default " + formatNumber(Args().map_height) + " m)").c_str());
  laser_raycast::tools::addPathFlags(add, &args->path);
  add("angle-min", number("--angle-min", "RAD", &args->scan.fan.angle_min), "the first beam");
  add("angle-max", number("--angle-max", "RAD", &args->scan.fan.angle_max), "the last beam");
  add("samples", count("--samples", &args->scan.fan.samples),
      "beams from --angle-min to --angle-max");
  add("angle-increment", number("--angle-increment", "RAD", &args->scan.fan.angle_increment),
      "the beam spacing, instead of --samples");
  add("range-min", number("--range-min", "M", &args->scan.output.range_min),
      "the shortest valid range");
  add("range-max", number("--range-max", "M", &args->scan.output.range_max),
      "the longest valid range");
  add("geometry",
      single("NAME", [args](const std::string& v) { args->geometry = parseGeometry(v); }),
      ("one of " + laser_raycast::kGeometrySourceNames.list()).c_str());
  add("method",
      single("NAME", [args](const std::string& v) { args->scan.method = parseMethod(v); }),
      "the triangle test");
  add("mesh-import-max-memory-mb",
      number("--mesh-import-max-memory-mb", "MB", &args->mesh_import.max_memory_mb),
      "address space for importing one mesh file (default 0: from the file's size)");
  add("mesh-import-timeout", number("--mesh-import-timeout", "S", &args->mesh_import.max_seconds),
      "time for importing one mesh file (default 0: from the file's size)");
  add("elevations",
      single("RAD,RAD,...",
             [args](const std::string& v) {
               args->scan.elevations = parseElevations(v);
               args->rings = true;
             }),
      "one fan of azimuths per elevation (rad, up positive, any order); ring r is the r-th lowest");
  addBeamFileFlags(add, args);
  add("joint",
      repeated("NAME=VALUE ...", [args](const std::string& v) { parseJoint(v, &args->joints); })
          ->multitoken(),
      "joint values (rad or m; 0 if not given): several after one --joint, or one each");
  addReturnFlags(add, args);
  addRadiometryFlags(add, args);
  add("repeat", count("--repeat", &args->repeat),
      "cast N more times after loading (the whole path) and print the median cast time of a "
      "scan to stderr, after the load's times and the meshes' memory per triangle");
  add("threads",
      single("N",
             [args](const std::string& v) {
               args->threads = laser_raycast::tools::parseThreads("--threads", v);
             }),
      ("threads a cast uses (default " + std::to_string(Args().threads) +
       "; 0: every core); the ranges are the same for any number")
          .c_str());
  add("help,h", "print this help");
  return options;
}

// A message of the core's validate() under the flag it is about: the core's messages start with
// the field's name, and the flag that sets a field is named after it (range_min: --range-min). One
// that starts with no flag's field goes under beams_from, the flag the beam count came from (""
// for the default): the core's "give exactly one of angle_increment and samples" for a 0, which
// FanSpec reads as unset, and the beam count of all rings together.
std::string underItsFlag(const std::string& message, const std::string& beams_from) {
  std::string flag = message.substr(0, message.find_first_of(" (["));
  std::replace(flag.begin(), flag.end(), '_', '-');
  Args unused;
  if (!flags(&unused).find_nothrow(flag, false)) flag = beams_from;
  return flag.empty() ? message : "--" + flag + ": " + message;
}

// The turn of a calibrated head cast at once (no --scan-time): 10 Hz, the models' default.
constexpr double kCalibratedScanTime = 0.1;  // s

// --pattern-file and its flags, or --calibration, or --ouster-metadata; loads the file. Throws
// ArgError.
void checkPatternFlags(const po::variables_map& values, Args* args) {
  const std::vector<std::pair<const char*, const std::string*>> files = {
      {"--pattern-file", &args->pattern_path},
      {"--calibration", &args->calibration_path},
      {"--ouster-metadata", &args->ouster_path}};
  const char* given = nullptr;
  for (const auto& [flag, path] : files) {
    if (path->empty()) continue;
    if (given) throw ArgError(std::string("give ") + given + " or " + flag + ", not both");
    given = flag;
  }
  if (given && args->returns.beam_samples > 1) {
    throw ArgError(std::string("--beam-samples > 1: not with ") + given +
                   " (divergent beams are cast for a fan or rings)");
  }
  if (given) {
    for (const char* flag :
         {"elevations", "samples", "angle-increment", "angle-min", "angle-max"}) {
      if (values.count(flag)) throw ArgError(std::string("--") + flag + ": not with " + given);
    }
  }
  const bool rotating = args->path.sweep == laser_raycast::tools::Sweep::kRotating;
  if (!args->calibration_path.empty()) {
    try {
      const core::VelodyneHead head =
          laser_raycast::loadVelodyneCalibration(args->calibration_path);
      args->calibrated = head.scan(rotating ? args->path.scan_time : kCalibratedScanTime);
    } catch (const std::invalid_argument& e) {
      throw ArgError(std::string("--calibration: ") + e.what());
    }
  }
  if (!args->ouster_path.empty()) {
    try {
      const core::OusterHead head = laser_raycast::loadOusterMetadata(args->ouster_path);
      args->calibrated = head.scan(rotating ? args->path.scan_time : 1 / head.fps);
    } catch (const std::invalid_argument& e) {
      throw ArgError(std::string("--ouster-metadata: ") + e.what());
    }
  }
  if (args->pattern_path.empty()) {
    for (const char* flag : {"points-per-scan", "point-rate"}) {
      if (values.count(flag))
        throw ArgError(std::string("--") + flag + ": only with --pattern-file");
    }
    return;
  }
  if (!(args->point_rate > 0)) throw ArgError("--pattern-file: give --point-rate HZ (> 0)");
  try {
    args->pattern_file = core::PatternFile::load(args->pattern_path);
  } catch (const std::invalid_argument& e) {
    throw ArgError(std::string("--pattern-file: ") + e.what());
  }
  if (args->points_per_scan == 0) args->points_per_scan = args->pattern_file->size();
  if (args->points_per_scan > core::FanSpec::kMaxBeams) {
    throw ArgError("--points-per-scan: more than " + std::to_string(core::FanSpec::kMaxBeams));
  }
}

// Throws ArgError.
Args parseArgs(int argc, char** argv, bool* help) {
  Args args;
  po::variables_map values;
  *help = !laser_raycast::tools::parseCommandLine(argc, argv, flags(&args), &values);
  if (*help) return args;
  const bool has_samples = values.count("samples"), has_increment = values.count("angle-increment");
  if (args.models.empty() && args.maps.empty()) throw ArgError("give at least one --urdf or --map");
  if (values.count("map-height") && args.maps.empty()) throw ArgError("--map-height needs --map");
  // Written so that NaN fails (parseNumber refuses it already).
  if (!(args.map_height > 0)) {
    throw ArgError("--map-height: must be > 0 m, got " + formatNumber(args.map_height));
  }
  laser_raycast::tools::checkPathFlags(values, args.path);
  if (has_samples && has_increment) throw ArgError("give --samples or --angle-increment, not both");
  if (!has_samples && !has_increment) args.scan.fan.samples = core::FanSpec::kDefaultSamples;
  // The angles, the beam count, the range limits and the elevations: checked once, by the core.
  const char* beams_from = has_samples ? "samples" : has_increment ? "angle-increment" : "";
  try {
    args.scan.validate();
  } catch (const std::invalid_argument& e) {
    throw ArgError(underItsFlag(e.what(), beams_from));
  }
  try {
    args.mesh_import.validate("--mesh-import-max-memory-mb:", "--mesh-import-timeout:");
  } catch (const std::invalid_argument& e) {
    throw ArgError(e.what());
  }
  try {
    args.returns.validate();
  } catch (const std::invalid_argument& e) {
    throw ArgError(underItsFlag(e.what(), ""));
  }
  laser_raycast::tools::checkSweepTimes(args.path, args.scan.fan);
  checkPatternFlags(values, &args);
  if (!(args.default_reflectivity >= 0)) {
    throw ArgError("--default-reflectivity: must be >= 0, got " +
                   formatNumber(args.default_reflectivity));
  }
  for (const char* flag : {"reflectivity", "default-reflectivity"}) {
    if (values.count(flag) && !args.radiometry()) {
      throw ArgError(std::string("--") + flag + ": give --intensity or --detection-range too");
    }
  }
  return args;
}

// "a|b|c": the names of a table, as the synopsis lists the choices of a flag.
template <typename E, std::size_t N>
std::string choices(const core::EnumNames<E, N>& names) {
  std::string out;
  for (const auto& entry : names.entries())
    out += (out.empty() ? "" : "|") + std::string(entry.second);
  return out;
}

// An angle of the help text: pi, -pi, or the number.
std::string formatAngle(double rad) {
  return rad == M_PI ? "pi" : rad == -M_PI ? "-pi" : formatNumber(rad);
}

// The usage lines: each flag's choices from its name table.
std::string synopsis() {
  using laser_raycast::tools::Sweep;
  const auto& sweeps = laser_raycast::tools::kSweepNames;
  const char* const indent = "                 ";
  std::ostringstream out;
  out << "usage: cast_scan [--urdf PATH[@x,y,z,roll,pitch,yaw] ...]\n"
      << indent << "[--map PATH[@x,y,z,roll,pitch,yaw] ...] [--map-height M]\n"
      << indent << "(--sensor x,y,z,roll,pitch,yaw | --poses FILE)\n"
      << indent << "[--sweep " << sweeps.name(Sweep::kInstant) << " | --sweep "
      << sweeps.name(Sweep::kRotating) << " --scan-time S [--twist vx,vy,vz,wx,wy,wz]]\n"
      << indent << "[--angle-min RAD] [--angle-max RAD] [--samples N | --angle-increment RAD]\n"
      << indent << "[--range-min M] [--range-max M] [--geometry "
      << choices(laser_raycast::kGeometrySourceNames) << "]\n"
      << indent << "[--method " << choices(core::kTriangleMethodNames) << "]\n"
      << indent << "[--elevations RAD,RAD,...] [--joint NAME=VALUE ...] [--repeat N]\n"
      << indent << "[--pattern-file FILE --point-rate HZ [--points-per-scan N]]\n"
      << indent << "[--calibration FILE | --ouster-metadata FILE]\n"
      << indent << "[--beam-divergence RAD --beam-samples N [--min-return-separation M]\n"
      << indent << " [--return-mode " << choices(core::kReturnModeNames) << "]]\n"
      << indent << "[--intensity] [--detection-range R@REFLECTIVITY]\n"
      << indent << "[--reflectivity LINK=VALUE ...] [--default-reflectivity VALUE]\n"
      << indent << "[--threads N] [--mesh-import-max-memory-mb MB] [--mesh-import-timeout S]\n";
  return out.str();
}

// The output, the defaults (Args': a ScanSpec's, and core::FanSpec::kDefaultSamples) and the exit
// statuses.
std::string notes() {
  const Args defaults;
  const core::ScanSpec& scan = defaults.scan;
  std::ostringstream out;
  out << "Prints CSV 'index,angle,range,link' (REP 117: inf, -inf, nan); with --elevations\n"
      << "'index,ring,elevation,angle,range,link' (ring 0 the lowest). With --poses, a scan\n"
      << "from each pose of FILE in turn, its rows led by 'pose' (0: the file's first pose line).\n"
      << "With --sweep rotating, each row ends with 'time', s after the scan's first beam.\n"
      << "With --pattern-file, --calibration or --ouster-metadata,\n"
      << "'index,line,azimuth,elevation,time,range,link' (rad; time k / HZ s, or the laser's\n"
      << "firing time, or the column's; with --sweep rotating each beam is cast from the pose at\n"
      << "its time; line: the file's Line, the laser's ring, or the Ouster row).\n"
      << "With --return-mode dual, a second row for a beam's last return and a 'return'\n"
      << "column; with --intensity, an 'intensity' column last. A return that --detection-range\n"
      << "loses prints range inf and no link.\n"
      << "Defaults: angles " << formatAngle(scan.fan.angle_min) << ".."
      << formatAngle(scan.fan.angle_max) << ", " << core::FanSpec::kDefaultSamples
      << " samples, ranges " << formatNumber(scan.output.range_min) << ".."
      << formatNumber(scan.output.range_max) << " m, geometry "
      << laser_raycast::toString(defaults.geometry) << ", method " << core::toString(scan.method)
      << ",\n"
      << defaults.threads << (defaults.threads == 1 ? " thread" : " threads") << ".\n"
      << "Poses in metres and radians (URDF rpy). --urdf and --map together take at least one;\n"
      << "a map's walls are " << formatNumber(defaults.map_height)
      << " m high unless --map-height says otherwise, its hits labelled 'map'.\n"
      << "Exit status: 0 ok, 2 bad arguments, 3 bad scene input.\n";
  return out.str();
}

// The models, loaded and placed, with their joints at the given values.
struct LoadedScene {
  core::Scene scene;
  core::FramePoses poses;
  bool prefixed = false;  // each model's link names carry a private prefix (not printed)
  // Over every model and map, for --repeat's statistics.
  double load_seconds = 0, bvh_build_seconds = 0;
  std::size_t mesh_triangles_built = 0, mesh_bytes_built = 0;
  std::size_t map_occupied_cells = 0, map_boxes = 0;
};

// Every joint value must name a movable joint of some model. Throws ArgError.
void checkJoints(const std::map<std::string, double>& joints,
                 const std::vector<laser_raycast::LoadedModel>& models) {
  using Type = laser_raycast::ModelJoint::Type;
  for (const auto& [name, value] : joints) {
    bool found = false;
    for (const auto& model : models) {
      for (const auto& joint : model.joints) {
        if (joint.name != name) continue;
        found = true;
        if (joint.type != Type::kRevolute && joint.type != Type::kContinuous &&
            joint.type != Type::kPrismatic) {
          throw ArgError("--joint " + name + "=" + formatNumber(value) +
                         ": the joint is not revolute, continuous or prismatic");
        }
      }
    }
    if (!found) throw ArgError("--joint " + name + ": no model has a joint of that name");
  }
}

// Adds the walls of every --map, each on a frame "map" (with the private prefix of the model after
// the URDFs when there are several models), placed at its pose in *link_poses. Throws
// SceneLoadError.
void loadMaps(const Args& args, LoadedScene* out,
              std::map<std::string, Eigen::Isometry3d>* link_poses) {
  for (std::size_t m = 0; m < args.maps.size(); ++m) {
    laser_raycast::MapWallOptions options;
    options.height = args.map_height;
    if (out->prefixed) options.frame = "m" + std::to_string(args.models.size() + m) + "/map";
    const laser_raycast::LoadedMap loaded = laser_raycast::addMapFile(
        args.maps[m].path, laser_raycast::rosPackagePath, options, &out->scene);
    for (const std::string& warning : loaded.warnings) {
      std::cerr << "cast_scan: warning: " << warning << "\n";
    }
    (*link_poses)[options.frame] = args.maps[m].pose;
    out->load_seconds += loaded.read_seconds + loaded.build_seconds;
    out->map_occupied_cells += loaded.occupied_cells;
    out->map_boxes += loaded.boxes;
  }
}

// Loads every model and map; with several, gives each a private prefix so that equal link names
// stay apart. Throws SceneLoadError (bad scene input) or ArgError (a bad joint).
LoadedScene loadScene(const Args& args) {
  laser_raycast::SceneLoader loader(laser_raycast::rosPackagePath);
  LoadedScene out;
  std::vector<laser_raycast::LoadedModel> loaded;
  out.prefixed = args.models.size() + args.maps.size() > 1;
  for (std::size_t m = 0; m < args.models.size(); ++m) {
    laser_raycast::LoaderOptions options;
    options.geometry = args.geometry;
    options.mesh_import = args.mesh_import;
    if (out.prefixed) options.tf_prefix = "m" + std::to_string(m) + "/";
    loaded.push_back(loader.addUrdfFile(args.models[m].path, options, &out.scene));
    out.load_seconds += loaded.back().load_seconds;
    out.bvh_build_seconds += loaded.back().bvh_build_seconds;
    out.mesh_triangles_built += loaded.back().mesh_triangles_built;
    out.mesh_bytes_built += loaded.back().mesh_bytes_built;
  }
  checkJoints(args.joints, loaded);
  std::map<std::string, Eigen::Isometry3d> link_poses;
  for (std::size_t m = 0; m < loaded.size(); ++m) {
    const auto poses =
        laser_raycast::forwardKinematics(loaded[m], args.models[m].pose, args.joints);
    link_poses.insert(poses.begin(), poses.end());
  }
  loadMaps(args, &out, &link_poses);
  out.poses = laser_raycast::framePosesFromLinks(out.scene, link_poses);
  return out;
}

// The scans' pattern and settings, and the one caster that casts them all, as the node's sensor
// keeps one from scan to scan: a scan is reused only if nothing moved relative to the sensor.
struct Casting {
  core::ScanPattern pattern;
  core::CastConfig config;
  core::Caster caster;
  double time_increment;       // s between two azimuth columns: > 0 for a rotating sweep
  core::PulseReturns returns;  // with --beam-samples > 1
  core::BeamList beams;        // --pattern-file: this scan's beams
  // The radiometry: by label, each one's reflectivity and whether --reflectivity set it; the scan
  // measured (the second return's too, in dual mode).
  std::vector<double> reflectivity;
  std::vector<char> reflectivity_fixed;
  core::SurfaceSamples surface;
  core::MeasuredScan measured, measured_second;
};

// The label of the body hit ("" for none), without a model's private prefix.
std::string bodyLabel(const LoadedScene& loaded, int body) {
  if (body < 0) return "";
  const std::string& label = loaded.scene.labels()[loaded.scene.bodies()[body].label];
  return loaded.prefixed ? label.substr(label.find('/') + 1) : label;
}

// Each label's reflectivity: --reflectivity's for its link (named without a model's private
// prefix), else --default-reflectivity. Throws ArgError for a link no model has.
void labelReflectivity(const Args& args, const LoadedScene& loaded, Casting* casting) {
  std::map<std::string, bool> used;
  for (const std::string& label : loaded.scene.labels()) {
    const std::string link = loaded.prefixed ? label.substr(label.find('/') + 1) : label;
    const auto it = args.reflectivity.find(link);
    casting->reflectivity.push_back(it != args.reflectivity.end() ? it->second
                                                                  : args.default_reflectivity);
    casting->reflectivity_fixed.push_back(it != args.reflectivity.end());
    if (it != args.reflectivity.end()) used[link] = true;
  }
  for (const auto& entry : args.reflectivity) {
    if (!used.count(entry.first)) {
      throw ArgError("--reflectivity " + entry.first + ": no model has a link of that name");
    }
  }
}

// The intensities and the detection range of the scan just cast from sensor (result), as the
// node measures them: the surface's reflectance and incidence at each hit where it gives them
// (a sweep's from its first pose), else the link's reflectivity and the cast's incidence. No
// noise: cast_scan's ranges stay the caster's.
void measure(const Args& args, const LoadedScene& loaded, const Eigen::Isometry3d& sensor,
             const core::ScanResult& result, Casting* casting) {
  if (!args.radiometry()) return;
  const core::MeasurementConfig& output = args.scan.output;
  core::MeasurementModel model(output);
  if (args.returns.beam_samples > 1) {
    model.measure(loaded.scene, casting->returns.first, casting->reflectivity, &casting->measured,
                  &casting->returns.first_surface);
    model.measure(loaded.scene, casting->returns.second, casting->reflectivity,
                  &casting->measured_second, &casting->returns.second_surface);
    return;
  }
  if (args.offGrid()) {
    core::sampleSurfaces(loaded.scene, loaded.poses, sensor, casting->beams, result,
                         output.reflectance_from_color, casting->reflectivity_fixed,
                         &casting->surface);
  } else {
    core::sampleSurfaces(loaded.scene, loaded.poses, sensor, casting->pattern, result,
                         output.reflectance_from_color, casting->reflectivity_fixed,
                         &casting->surface);
  }
  model.measure(loaded.scene, result, casting->reflectivity, &casting->measured, &casting->surface);
}

// Beam i's range and link as the CSV prints them: REP 117's range, and the label hit; a return
// that the detection range loses (a hit in range with no measured return) prints inf and no link.
std::string rangeAndLink(const Args& args, const LoadedScene& loaded, const core::ScanResult& beams,
                         const core::MeasuredScan& measured, int i) {
  const double range = core::classifyRange(beams.range[i], args.scan.output);
  if (args.radiometry() && std::isfinite(range) && measured.labels[i] < 0) return "inf,";
  return formatNumber(range) + "," + bodyLabel(loaded, beams.body[i]);
}

// A pattern file's beams of the path's scan number `pose` into casting->beams: its rows from
// pose * points_per_scan on.
void patternScan(const Args& args, std::size_t pose, Casting* casting) {
  if (args.calibrated) casting->beams = *args.calibrated;
  if (!args.pattern_file) return;
  casting->beams = args.pattern_file->scan(static_cast<std::int64_t>(pose) * args.points_per_scan,
                                           args.points_per_scan, args.point_rate);
}

// The scan from sensor, at once or as a rotating sweep starting there (a pattern file's beams,
// casting->beams, or the fan); *ns, if given, the time of the cast alone (not of the sweep's
// samples).
const core::ScanResult& castFrom(const Args& args, const LoadedScene& loaded,
                                 const Eigen::Isometry3d& sensor, Casting* casting, long long* ns) {
  const bool rotating = args.path.sweep == laser_raycast::tools::Sweep::kRotating;
  core::Caster& caster = casting->caster;
  const core::CastConfig& config = casting->config;
  core::PoseSamples samples;
  if (rotating && args.offGrid()) {
    samples =
        laser_raycast::tools::sweepSamplesAt(args.path, sensor, loaded.poses, casting->beams.times);
  } else if (rotating) {
    samples = laser_raycast::tools::sweepSamples(args.path, sensor, loaded.poses, casting->pattern);
  }
  const auto t0 = std::chrono::steady_clock::now();
  if (args.returns.beam_samples > 1) {
    // Divergent beams, from the scan's first pose (a sweep's motion is not applied to them).
    core::castReturns(&casting->caster, loaded.scene, loaded.poses, sensor, args.scan.fan,
                      args.scan.ringElevations(), casting->config, args.returns,
                      casting->reflectivity, casting->reflectivity_fixed,
                      args.scan.output.reflectance_from_color, args.scan.output.surface_reflectance,
                      &casting->returns);
    const auto t1 = std::chrono::steady_clock::now();
    if (ns) *ns = std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count();
    return casting->returns.first;
  }
  const core::ScanResult* result;
  if (args.offGrid()) {
    result = rotating
                 ? &caster.castBeamsSweep(loaded.scene, samples, casting->beams, config)
                 : &caster.castBeams(loaded.scene, loaded.poses, sensor, casting->beams, config);
  } else {
    result = rotating ? &caster.castSweep(loaded.scene, samples, casting->pattern, config,
                                          casting->time_increment)
                      : &caster.cast(loaded.scene, loaded.poses, sensor, casting->pattern, config);
  }
  const auto t1 = std::chrono::steady_clock::now();
  if (ns) *ns = std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count();
  return *result;
}

// Casts every scan of the path `repeat` more times and prints the median time of a scan over all
// of them to stderr. Each cast is computed anew (forget(): not the previous scan's result), as the
// node casts scan after scan: a planar fan's kept slices of its plane (kept_slice.h) serve the
// casts after the first two.
void reportMedianCastTime(const Args& args, const LoadedScene& loaded, Casting* casting) {
  std::vector<long long> ns(args.repeat * args.path.sensors.size());
  auto next = ns.begin();
  for (int k = 0; k < args.repeat; ++k) {
    for (std::size_t p = 0; p < args.path.sensors.size(); ++p) {
      const Eigen::Isometry3d& sensor = args.path.sensors[p];
      patternScan(args, p, casting);
      casting->caster.forget();  // time the cast itself, not the reuse of an unchanged scan
      castFrom(args, loaded, sensor, casting, &*next++);
    }
  }
  std::nth_element(ns.begin(), ns.begin() + ns.size() / 2, ns.end());
  std::cerr << "cast_ns_per_scan_median=" << ns[ns.size() / 2] << "\n";
}

// What loading cost: time reading files (map files and covering their cells with boxes included)
// and building BVHs, the meshes' memory per triangle (of each mesh read, once however often it is
// instanced), and the maps' occupied cells and boxes, to stderr.
void reportLoad(const LoadedScene& loaded) {
  std::cerr << "load_seconds=" << formatNumber(loaded.load_seconds) << "\n"
            << "bvh_build_seconds=" << formatNumber(loaded.bvh_build_seconds) << "\n"
            << "mesh_triangles=" << loaded.mesh_triangles_built << "\n"
            << "mesh_bytes=" << loaded.mesh_bytes_built << "\n";
  if (loaded.mesh_triangles_built > 0) {
    std::cerr << "mesh_bytes_per_triangle="
              << formatNumber(static_cast<double>(loaded.mesh_bytes_built) /
                              loaded.mesh_triangles_built)
              << "\n";
  }
  if (loaded.map_occupied_cells > 0) {
    std::cerr << "map_occupied_cells=" << loaded.map_occupied_cells << "\n"
              << "map_boxes=" << loaded.map_boxes << "\n";
  }
}

// The CSV's header: with --poses, the pose's number first; with a rotating sweep, the beam's time
// last.
std::string csvHeader(const Args& args, const Casting& casting) {
  const std::string intensity = args.scan.output.intensity ? ",intensity\n" : "\n";
  if (args.offGrid()) {
    return std::string(args.path.pose_column ? "pose," : "") +
           "index,line,azimuth,elevation,time,range,link" + intensity;
  }
  return std::string(args.path.pose_column ? "pose," : "") +
         (args.rings ? "index,ring,elevation,angle,range,link" : "index,angle,range,link") +
         (casting.time_increment > 0 ? ",time" : "") + (args.dual() ? ",return" : "") + intensity;
}

// The intensity column's field of beam i (with a leading comma), or "" without --intensity.
std::string intensityField(const Args& args, const core::MeasuredScan& measured, int i) {
  return args.scan.output.intensity ? "," + formatNumber(measured.intensities[i]) : "";
}

// One CSV row per beam of the scan from the path's pose number `pose`, in beam order
// (ring-major).
std::string csvRows(const Args& args, const LoadedScene& loaded, const Casting& casting,
                    const core::ScanResult& result, std::size_t pose) {
  std::string out;
  if (args.offGrid()) {
    const core::BeamList& beams = casting.beams;
    for (int i = 0; i < beams.size(); ++i) {
      const Eigen::Vector3d& d = beams.directions[i];
      if (args.path.pose_column) out += std::to_string(pose) + ",";
      out += std::to_string(i) + "," + std::to_string(beams.line(i)) + "," +
             formatNumber(std::atan2(d.y(), d.x())) + "," +
             formatNumber(std::atan2(d.z(), std::hypot(d.x(), d.y()))) + "," +
             formatNumber(beams.time(i)) + "," +
             rangeAndLink(args, loaded, result, casting.measured, i) +
             intensityField(args, casting.measured, i) + "\n";
    }
    return out;
  }
  const core::ScanPattern& pattern = casting.pattern;
  const int azimuths = pattern.azimuthCount();
  for (int row = 0; row < (args.dual() ? 2 : 1) * pattern.size(); ++row) {
    // Dual: each beam's strongest return, then its last where that is another.
    const int i = args.dual() ? row / 2 : row;
    const bool second = args.dual() && row % 2 == 1;
    const core::ScanResult& beams = second ? casting.returns.second : result;
    const core::MeasuredScan& measured = second ? casting.measured_second : casting.measured;
    if (second && beams.body[i] < 0) continue;
    const int ring = i / azimuths;
    if (args.path.pose_column) out += std::to_string(pose) + ",";
    out += std::to_string(i) + ",";
    if (args.rings) {
      out += std::to_string(ring) + "," + formatNumber(pattern.elevations()[ring]) + ",";
    }
    out += formatNumber(pattern.azimuth(i % azimuths)) + "," +
           rangeAndLink(args, loaded, beams, measured, i);
    if (casting.time_increment > 0) {
      out += "," + formatNumber(i % azimuths * casting.time_increment);  // castSweep's column time
    }
    if (args.dual()) out += second ? ",2" : ",1";
    out += intensityField(args, measured, i) + "\n";
  }
  return out;
}

void print(const std::string& text) { std::fwrite(text.data(), 1, text.size(), stdout); }

}  // namespace

int main(int argc, char** argv) {
  Args args;
  const auto exit_now = laser_raycast::tools::readCommandLine("cast_scan", synopsis(), notes(),
                                                              parseArgs, flags, argc, argv, &args);
  if (exit_now) return *exit_now;
  LoadedScene loaded;
  try {
    loaded = loadScene(args);
  } catch (const laser_raycast::SceneLoadError& e) {
    std::cerr << "cast_scan: " << e.what() << "\n";
    return kExitBadScene;
  } catch (const ArgError& e) {
    std::cerr << "cast_scan: " << e.what() << "\n";
    return kExitBadArguments;
  }
  Casting casting{args.scan.pattern(),
                  args.scan.castConfig(),
                  core::Caster(),
                  laser_raycast::tools::timeIncrement(args.path, args.scan.fan.increment()),
                  {},
                  {}};
  casting.config.threads = args.threads;
  try {
    labelReflectivity(args, loaded, &casting);
  } catch (const ArgError& e) {
    std::cerr << "cast_scan: " << e.what() << "\n";
    return kExitBadArguments;
  }
  // The path in order, each scan printed before the next is cast (the result is the caster's).
  print(csvHeader(args, casting));
  for (std::size_t p = 0; p < args.path.sensors.size(); ++p) {
    patternScan(args, p, &casting);
    const core::ScanResult& result =
        castFrom(args, loaded, args.path.sensors[p], &casting, nullptr);
    measure(args, loaded, args.path.sensors[p], result, &casting);
    print(csvRows(args, loaded, casting, result, p));
  }
  if (args.repeat > 0) {
    reportLoad(loaded);
    reportMedianCastTime(args, loaded, &casting);
  }
  return 0;
}
