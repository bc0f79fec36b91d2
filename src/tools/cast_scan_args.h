// cast_scan's command line (cast_scan.cpp): what the flags say, read and checked by parseArgs;
// the flags, synopsis and notes that --help prints.
#pragma once

#include <boost/program_options.hpp>

#include <Eigen/Geometry>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "cast_path.h"
#include "laser_raycast/core/beam_list.h"
#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/pattern_file.h"
#include "laser_raycast/core/returns.h"
#include "laser_raycast/core/scan_spec.h"
#include "laser_raycast/loader/map_file.h"
#include "laser_raycast/loader/scene_loader.h"

namespace laser_raycast {
namespace tools {
namespace cast_scan {

namespace core = laser_raycast::core;

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
  laser_raycast::GeometrySource geometry = laser_raycast::LoaderOptions().geometry;
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

// A number as the CSV prints it: 9 significant digits, or inf, -inf, nan.
std::string formatNumber(double value);

// The flags, in the order the help lists them, their values read into *args.
boost::program_options::options_description flags(Args* args);
// The command line, checked (the pattern, calibration and Ouster files loaded): throws ArgError
// naming the flag. *help: --help was given (the rest is not read).
Args parseArgs(int argc, char** argv, bool* help);
// The usage lines and the notes that follow the flags in --help.
std::string synopsis();
std::string notes();

}  // namespace cast_scan
}  // namespace tools
}  // namespace laser_raycast
