// cast_scan's command line: its flags, their checks, and its help (cast_scan_args.h).
#include "cast_scan_args.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <sstream>
#include <stdexcept>

#include "command_line.h"
#include "laser_raycast/loader/ouster_metadata.h"
#include "laser_raycast/loader/velodyne_calibration.h"

namespace laser_raycast {
namespace tools {
namespace cast_scan {

using laser_raycast::GeometrySource;
using laser_raycast::tools::ArgError;
using laser_raycast::tools::parseNumber;
using laser_raycast::tools::single;
namespace po = boost::program_options;

std::string formatNumber(double value) {
  if (std::isnan(value)) return "nan";  // printf may write "-nan"
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.9g", value);
  return buffer;
}

namespace {

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

}  // namespace

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
      ("threads a cast uses, and that build the meshes' BVHs (default " +
       std::to_string(Args().threads) + "; 0: every core); the ranges are the same for any number")
          .c_str());
  add("help,h", "print this help");
  return options;
}

namespace {

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

}  // namespace

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

namespace {

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

}  // namespace

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

}  // namespace cast_scan
}  // namespace tools
}  // namespace laser_raycast
