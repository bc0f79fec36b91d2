// cast_scan: one simulated scan of URDF models from a sensor pose, printed as CSV. Needs no
// roscore: package:// URIs are resolved through ROS_PACKAGE_PATH. See usage() and the README.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/scan_encoder.h"
#include "laser_raycast/core/scan_spec.h"
#include "laser_raycast/loader/kinematics.h"
#include "laser_raycast/loader/package_resolver.h"
#include "laser_raycast/loader/scene_loader.h"

namespace {

using laser_raycast::GeometrySource;
namespace core = laser_raycast::core;

constexpr int kExitBadArguments = 2;
constexpr int kExitBadScene = 3;

const char* const kUsage =
    "usage: cast_scan --urdf PATH[@x,y,z,roll,pitch,yaw] [--urdf ...] --sensor "
    "x,y,z,roll,pitch,yaw\n"
    "                 [--angle-min RAD] [--angle-max RAD] [--samples N | --angle-increment RAD]\n"
    "                 [--range-min M] [--range-max M] [--geometry visual|collision]\n"
    "                 [--method seed_plane|seed_uv|cramer|moller_trumbore|watertight]\n"
    "                 [--joint NAME=VALUE ...] [--repeat N]\n"
    "Prints CSV 'index,angle,range,link' (REP 117: inf, -inf, nan). Defaults: angles -pi..pi, 360 "
    "samples,\n"
    "ranges 0..30 m, geometry visual, method watertight. Poses in metres and radians (URDF rpy).\n"
    "Exit status: 0 ok, 2 bad arguments, 3 bad scene input.\n";

class ArgError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Model {
  std::string path;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
};

struct Args {
  std::vector<Model> models;
  bool has_sensor = false;
  Eigen::Isometry3d sensor = Eigen::Isometry3d::Identity();
  core::ScanSpec scan;  // the fan, ranges and method; REP 117 with the default -inf policy
  GeometrySource geometry = GeometrySource::kVisual;
  std::map<std::string, double> joints;
  int repeat = 0;
};

double parseNumber(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(value)) {
    throw ArgError(flag + ": '" + text + "' is not a finite number");
  }
  return value;
}

int parseCount(const std::string& flag, const std::string& text) {
  char* end = nullptr;
  const long value = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || value < 0 || value > 1000000000L) {
    throw ArgError(flag + ": '" + text + "' is not a count (a non-negative integer)");
  }
  return static_cast<int>(value);
}

// "x,y,z,roll,pitch,yaw"
bool parsePose(const std::string& text, Eigen::Isometry3d* pose) {
  double v[6];
  std::size_t start = 0;
  for (int k = 0; k < 6; ++k) {
    const std::size_t comma = text.find(',', start);
    if ((k < 5) != (comma != std::string::npos)) return false;
    const std::string item = text.substr(start, k < 5 ? comma - start : std::string::npos);
    char* end = nullptr;
    v[k] = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(v[k])) return false;
    start = comma + 1;
  }
  *pose = laser_raycast::poseFromXyzRpy(v[0], v[1], v[2], v[3], v[4], v[5]);
  return true;
}

Args parseArgs(int argc, char** argv) {
  Args args;
  bool has_samples = false, has_increment = false;
  std::vector<std::string> words(argv + 1, argv + argc);
  for (std::size_t i = 0; i < words.size(); ++i) {
    std::string flag = words[i];
    std::string value;
    bool inline_value = false;
    if (flag.compare(0, 2, "--") == 0 && flag.find('=') != std::string::npos) {
      value = flag.substr(flag.find('=') + 1);
      flag = flag.substr(0, flag.find('='));
      inline_value = true;
    }
    auto next = [&]() -> std::string {
      if (inline_value) return value;
      if (i + 1 >= words.size()) throw ArgError(flag + " needs a value");
      return words[++i];
    };
    if (flag == "--urdf") {
      const std::string spec = next();
      Model model;
      model.path = spec;
      const std::size_t at = spec.rfind('@');
      if (at != std::string::npos && parsePose(spec.substr(at + 1), &model.pose)) {
        model.path = spec.substr(0, at);
      }
      if (model.path.empty()) throw ArgError("--urdf: empty path");
      args.models.push_back(model);
    } else if (flag == "--sensor") {
      const std::string spec = next();
      if (!parsePose(spec, &args.sensor)) {
        throw ArgError("--sensor: '" + spec + "' is not x,y,z,roll,pitch,yaw (6 finite numbers)");
      }
      args.has_sensor = true;
    } else if (flag == "--angle-min") {
      args.scan.fan.angle_min = parseNumber(flag, next());
    } else if (flag == "--angle-max") {
      args.scan.fan.angle_max = parseNumber(flag, next());
    } else if (flag == "--samples") {
      args.scan.fan.samples = parseCount(flag, next());
      has_samples = true;
    } else if (flag == "--angle-increment") {
      args.scan.fan.angle_increment = parseNumber(flag, next());
      has_increment = true;
    } else if (flag == "--range-min") {
      args.scan.output.range_min = parseNumber(flag, next());
    } else if (flag == "--range-max") {
      args.scan.output.range_max = parseNumber(flag, next());
    } else if (flag == "--geometry") {
      const std::string name = next();
      if (!laser_raycast::parseGeometrySource(name, &args.geometry)) {
        throw ArgError("--geometry: " + laser_raycast::kGeometrySourceNames.notOneOf(name));
      }
    } else if (flag == "--method") {
      const std::string name = next();
      if (!core::parseTriangleMethod(name, &args.scan.method)) {
        throw ArgError("--method: " + core::kTriangleMethodNames.notOneOf(name));
      }
    } else if (flag == "--joint") {
      // One NAME=VALUE per --joint, or several after one --joint.
      std::vector<std::string> specs{next()};
      while (!inline_value && i + 1 < words.size() && words[i + 1].compare(0, 2, "--") != 0 &&
             words[i + 1].find('=') != std::string::npos) {
        specs.push_back(words[++i]);
      }
      for (const std::string& spec : specs) {
        const std::size_t eq = spec.find('=');
        if (eq == std::string::npos || eq == 0) {
          throw ArgError("--joint: '" + spec + "' is not NAME=VALUE");
        }
        args.joints[spec.substr(0, eq)] =
            parseNumber("--joint " + spec.substr(0, eq), spec.substr(eq + 1));
      }
    } else if (flag == "--repeat") {
      args.repeat = parseCount(flag, next());
    } else {
      throw ArgError("unknown argument '" + words[i] + "'");
    }
  }
  if (args.models.empty()) throw ArgError("give at least one --urdf");
  if (!args.has_sensor) throw ArgError("--sensor is required");
  if (has_samples && has_increment) throw ArgError("give --samples or --angle-increment, not both");
  if (!has_samples && !has_increment) args.scan.fan.samples = 360;
  if (!(args.scan.output.range_min >= 0)) throw ArgError("--range-min must be >= 0");
  if (!(args.scan.output.range_max > args.scan.output.range_min))
    throw ArgError("--range-max must be greater than --range-min");
  try {
    args.scan.validate();
  } catch (const std::invalid_argument& e) {
    throw ArgError(e.what());
  }
  return args;
}

std::string formatNumber(double value) {
  if (std::isnan(value)) return "nan";  // printf may write "-nan"
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.9g", value);
  return buffer;
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      return 0;
    }
  }
  Args args;
  try {
    args = parseArgs(argc, argv);
  } catch (const ArgError& e) {
    std::cerr << "cast_scan: " << e.what() << "\n" << kUsage;
    return kExitBadArguments;
  }

  // Load every model; with several, give each a private prefix so that equal link names stay apart
  // (the prefix is not printed).
  laser_raycast::SceneLoader loader(laser_raycast::rosPackagePath);
  core::Scene scene;
  std::vector<laser_raycast::LoadedModel> loaded;
  const bool prefixed = args.models.size() > 1;
  for (std::size_t m = 0; m < args.models.size(); ++m) {
    laser_raycast::LoaderOptions options;
    options.geometry = args.geometry;
    if (prefixed) options.tf_prefix = "m" + std::to_string(m) + "/";
    try {
      loaded.push_back(loader.addUrdfFile(args.models[m].path, options, &scene));
    } catch (const laser_raycast::SceneLoadError& e) {
      std::cerr << "cast_scan: " << e.what() << "\n";
      return kExitBadScene;
    }
  }

  // Joint values: every name must be a movable joint of some model.
  for (const auto& [name, value] : args.joints) {
    bool found = false;
    for (const auto& model : loaded) {
      for (const auto& joint : model.joints) {
        if (joint.name != name) continue;
        found = true;
        using Type = laser_raycast::ModelJoint::Type;
        if (joint.type != Type::kRevolute && joint.type != Type::kContinuous &&
            joint.type != Type::kPrismatic) {
          std::cerr << "cast_scan: --joint " << name << "=" << value
                    << ": the joint is not revolute, continuous or prismatic\n";
          return kExitBadArguments;
        }
      }
    }
    if (!found) {
      std::cerr << "cast_scan: --joint " << name << ": no model has a joint of that name\n";
      return kExitBadArguments;
    }
  }
  std::map<std::string, Eigen::Isometry3d> link_poses;
  for (std::size_t m = 0; m < loaded.size(); ++m) {
    const auto poses =
        laser_raycast::forwardKinematics(loaded[m], args.models[m].pose, args.joints);
    link_poses.insert(poses.begin(), poses.end());
  }
  const core::FramePoses frame_poses = laser_raycast::framePosesFromLinks(scene, link_poses);

  const core::ScanPattern pattern = args.scan.pattern();
  const core::CastConfig config = args.scan.castConfig();
  core::Caster caster;
  const core::ScanResult& result = caster.cast(scene, frame_poses, args.sensor, pattern, config);

  if (args.repeat > 0) {
    std::vector<long long> ns;
    ns.reserve(args.repeat);
    for (int k = 0; k < args.repeat; ++k) {
      caster.forget();  // time the cast itself, not the reuse of an unchanged scan
      const auto t0 = std::chrono::steady_clock::now();
      caster.cast(scene, frame_poses, args.sensor, pattern, config);
      const auto t1 = std::chrono::steady_clock::now();
      ns.push_back(std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count());
    }
    std::nth_element(ns.begin(), ns.begin() + ns.size() / 2, ns.end());
    std::cerr << "cast_ns_per_scan_median=" << ns[ns.size() / 2] << "\n";
  }

  std::string out = "index,angle,range,link\n";
  for (int i = 0; i < pattern.size(); ++i) {
    out += std::to_string(i) + "," + formatNumber(pattern.azimuth(i)) + "," +
           formatNumber(core::classifyRange(result.range[i], args.scan.output)) + ",";
    if (result.body[i] >= 0) {
      const std::string& label = scene.labels()[scene.bodies()[result.body[i]].label];
      out += prefixed ? label.substr(label.find('/') + 1) : label;
    }
    out += "\n";
  }
  std::fwrite(out.data(), 1, out.size(), stdout);
  return 0;
}
