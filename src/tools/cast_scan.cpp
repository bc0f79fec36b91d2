// cast_scan: simulated scans of URDF models and map worlds from a sensor pose, or from each pose of
// a path, printed as CSV. Needs no roscore: package:// URIs are resolved through ROS_PACKAGE_PATH.
// See the README; the command line is cast_scan_args.h's, the path cast_path.h's.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "cast_path.h"
#include "cast_scan_args.h"
#include "command_line.h"
#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/measurement_model.h"
#include "laser_raycast/core/returns.h"
#include "laser_raycast/core/scan_spec.h"
#include "laser_raycast/core/surface_reflectance.h"
#include "laser_raycast/loader/kinematics.h"
#include "laser_raycast/loader/map_file.h"
#include "laser_raycast/loader/package_resolver.h"
#include "laser_raycast/loader/scene_loader.h"

namespace {

using laser_raycast::tools::ArgError;
using laser_raycast::tools::cast_scan::Args;
using laser_raycast::tools::cast_scan::formatNumber;
namespace core = laser_raycast::core;

using laser_raycast::tools::kExitBadArguments;
constexpr int kExitBadScene = 3;

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
    options.bvh.threads = args.threads;  // --threads builds the meshes' BVHs too
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
  Casting(core::ScanPattern pattern_in, const core::CastConfig& config_in, double increment)
      : pattern(std::move(pattern_in)), config(config_in), time_increment(increment) {}

  core::ScanPattern pattern;
  core::CastConfig config;
  core::Caster caster;
  double time_increment;       // s between two azimuth columns: > 0 for a rotating sweep
  core::PulseReturns returns;  // with --beam-samples > 1
  core::BeamList beams;        // --pattern-file: this scan's beams
  // --calibration's or --ouster-metadata's beams, the same every scan (shared with the caster,
  // which knows them again without comparing them).
  std::shared_ptr<const core::BeamList> calibrated;
  const core::BeamList& list() const { return calibrated ? *calibrated : beams; }
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
    core::sampleSurfaces(loaded.scene, loaded.poses, sensor, casting->list(), result,
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
        laser_raycast::tools::sweepSamplesAt(args.path, sensor, loaded.poses, casting->list().times);
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
    if (casting->calibrated) {
      result = rotating ? &caster.castBeamsSweep(loaded.scene, samples, casting->calibrated, config)
                        : &caster.castBeams(loaded.scene, loaded.poses, sensor,
                                            casting->calibrated, config);
    } else {
      result = rotating
                   ? &caster.castBeamsSweep(loaded.scene, samples, casting->beams, config)
                   : &caster.castBeams(loaded.scene, loaded.poses, sensor, casting->beams, config);
    }
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
    const core::BeamList& beams = casting.list();
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
  namespace cli = laser_raycast::tools::cast_scan;
  const auto exit_now = laser_raycast::tools::readCommandLine(
      "cast_scan", cli::synopsis(), cli::notes(), cli::parseArgs, cli::flags, argc, argv, &args);
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
  Casting casting(args.scan.pattern(), args.scan.castConfig(),
                  laser_raycast::tools::timeIncrement(args.path, args.scan.fan.increment()));
  casting.config.threads = args.threads;
  if (args.calibrated && !args.pattern_file) {
    casting.calibrated = std::make_shared<const core::BeamList>(*args.calibrated);
  }
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
