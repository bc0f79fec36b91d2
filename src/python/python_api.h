// What the Python module (module.cpp) binds: a scene loaded from URDF, a scan pattern, the
// measurement options, and a caster that casts a pattern from many sensor poses at once into numpy
// arrays. A thin layer over the loader and the core, as cast_scan is: the same scene, the same
// casts, the same REP 117 classification, so that its ranges are cast_scan's. The pattern is
// python_pattern.h's. Included by module.cpp only.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "laser_raycast/core/beam_list.h"
#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/measurement_model.h"
#include "laser_raycast/core/scan_spec.h"
#include "laser_raycast/core/sensor_model.h"
#include "laser_raycast/loader/kinematics.h"
#include "laser_raycast/loader/scene_loader.h"
#include "python_pattern.h"

namespace py = pybind11;

namespace laser_raycast {
namespace python {

using Poses = py::array_t<double, py::array::c_style | py::array::forcecast>;

inline std::string shapeOf(const py::array& a) {
  std::ostringstream out;
  out << "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) out << (i ? ", " : "") << a.shape(i);
  out << (a.ndim() == 1 ? ",)" : ")");
  return out.str();
}

// A (4, 4) or (N, 4, 4) array of homogeneous transforms as N poses: TypeError naming `what` for
// something that is not an array of numbers, ValueError for another shape. A (4, 4) array is one
// pose (N = 1) if `single` is given, which then says so.
inline std::vector<Eigen::Isometry3d> posesFrom(const py::handle& object, const std::string& what,
                                                bool* single = nullptr) {
  const Poses a = Poses::ensure(object);
  if (!a) {
    PyErr_Clear();
    throw py::type_error(what + " must be an array of numbers of shape (N, 4, 4), got " +
                         std::string(py::str(py::type::of(object).attr("__name__"))));
  }
  const bool one = a.ndim() == 2 && a.shape(0) == 4 && a.shape(1) == 4;
  if (!(one && single) && !(a.ndim() == 3 && a.shape(1) == 4 && a.shape(2) == 4)) {
    throw py::value_error(what + " must have shape (N, 4, 4)" + (single ? " or (4, 4)" : "") +
                          ", got " + shapeOf(a));
  }
  if (single) *single = one;
  const py::ssize_t n = one ? 1 : a.shape(0);
  std::vector<Eigen::Isometry3d> out(n, Eigen::Isometry3d::Identity());
  const double* data = a.data();
  for (py::ssize_t k = 0; k < n; ++k) {
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) m(r, c) = data[16 * k + 4 * r + c];
    // The last row is not read: a pose is its rotation and translation (the caster checks that
    // they are a finite rigid transform, and casts NaN beams from any other).
    out[k].linear() = m.topLeftCorner<3, 3>();
    out[k].translation() = m.topRightCorner<3, 1>();
  }
  return out;
}

// The scene and what the loader said about each model (for forward kinematics).
class Scene {
 public:
  static std::shared_ptr<Scene> fromUrdf(const std::string& source, const std::string& geometry,
                                         const std::string& tf_prefix) {
    auto scene = std::make_shared<Scene>();
    scene->addUrdf(source, geometry, tf_prefix);
    return scene;
  }

  // source: a path, a package:// URI, or the XML itself (text starting with '<').
  void addUrdf(const std::string& source, const std::string& geometry,
               const std::string& tf_prefix) {
    LoaderOptions options;
    if (!parseGeometrySource(geometry, &options.geometry)) {
      throw py::value_error("geometry: " + kGeometrySourceNames.notOneOf(geometry));
    }
    options.tf_prefix = tf_prefix;
    const std::size_t first = source.find_first_not_of(" \t\r\n");
    const bool xml = first != std::string::npos && source[first] == '<';
    LoadedModel model;
    {
      py::gil_scoped_release release;  // meshes may take seconds to read
      // A failed load leaves the scene as it was: the model is added to a copy.
      core::Scene next = scene_;
      model = xml ? loader_.addUrdfString(source, "", options, &next, "<URDF string>")
                  : loader_.addUrdfFile(source, options, &next);
      scene_ = std::move(next);
    }
    models_.push_back(std::move(model));
  }

  const core::Scene& scene() const { return scene_; }
  const std::vector<LoadedModel>& models() const { return models_; }

  // Every link's pose: each model's root at the identity and its joints at `joints` (0 if not
  // given), then the poses given in `links` instead, for each of `count` scans (a pose given once
  // holds for every scan); one set only if it is the same for every scan.
  std::vector<core::FramePoses> framePoses(
      std::size_t count, const std::map<std::string, double>& joints,
      const std::map<std::string, std::vector<Eigen::Isometry3d>>& links) const {
    for (const auto& [name, value] : joints) {
      if (!std::isfinite(value)) {
        throw py::value_error("joints['" + name + "'] must be finite");
      }
      if (!hasMovableJoint(name)) {
        throw py::value_error("joints: '" + name +
                              "' is not a movable joint of the scene's models");
      }
    }
    std::map<std::string, Eigen::Isometry3d> fixed;
    for (const LoadedModel& model : models_) {
      const auto poses = forwardKinematics(model, Eigen::Isometry3d::Identity(), joints);
      fixed.insert(poses.begin(), poses.end());
    }
    for (const auto& [name, poses] : links) {
      if (!fixed.count(name)) {
        throw py::value_error("link_poses: '" + name + "' is not a link of the scene's models");
      }
      if (poses.size() != 1 && poses.size() != count) {
        std::ostringstream msg;
        msg << "link_poses['" << name << "'] has " << poses.size() << " poses for " << count
            << " sensor poses (give one, or one per sensor pose)";
        throw py::value_error(msg.str());
      }
    }
    // One set for every scan unless some link has a pose per scan.
    bool per_scan = false;
    for (const auto& entry : links) per_scan = per_scan || entry.second.size() > 1;
    std::vector<core::FramePoses> out;
    out.reserve(per_scan ? count : 1);
    for (std::size_t k = 0; k < (per_scan ? count : 1); ++k) {
      std::map<std::string, Eigen::Isometry3d> at = fixed;
      for (const auto& [name, poses] : links) at[name] = poses[poses.size() == 1 ? 0 : k];
      out.push_back(framePosesFromLinks(scene_, at));
    }
    return out;
  }

  std::vector<std::string> linkNames() const {
    std::vector<std::string> out;
    for (const LoadedModel& model : models_) {
      for (const auto& entry : model.link_frames) out.push_back(entry.first);
    }
    return out;
  }

 private:
  bool hasMovableJoint(const std::string& name) const {
    for (const LoadedModel& model : models_) {
      for (const ModelJoint& joint : model.joints) {
        if (joint.name == name && joint.type != ModelJoint::Type::kFixed &&
            joint.type != ModelJoint::Type::kOther) {
          return true;
        }
      }
    }
    return false;
  }

  SceneLoader loader_{rosPackagePath};
  core::Scene scene_;
  std::vector<LoadedModel> models_;
};

// The measurement model's options (the node's parameters of the same names).
struct Measurement {
  core::MeasurementConfig config;  // its range limits are the cast's, set there
  std::map<std::string, double> reflectivity;
  double default_reflectivity = 1.0;

  // The reflectivity of each label of scene; ValueError for a name that is not one of them.
  std::vector<double> reflectivityByLabel(const core::Scene& scene) const {
    const auto& labels = scene.labels();
    std::vector<double> out(labels.size(), default_reflectivity);
    for (const auto& [name, value] : reflectivity) {
      const auto it = std::find(labels.begin(), labels.end(), name);
      if (it == labels.end()) {
        throw py::value_error("reflectivity: '" + name + "' is not a link with geometry");
      }
      out[it - labels.begin()] = value;
    }
    return out;
  }
};

struct Scans {
  py::array_t<double> ranges;
  py::array_t<std::int32_t> links;
  py::object points = py::none();
  py::object intensity = py::none();
};

class Caster {
 public:
  explicit Caster(int threads) : threads_(threads) {
    if (threads < 0)
      throw py::value_error("threads must be >= 0 (0: every core), got " + std::to_string(threads));
  }

  Scans cast(const Scene& scene, const py::object& sensor_poses, const Pattern& pattern,
             const std::optional<std::map<std::string, py::object>>& link_poses,
             const std::map<std::string, double>& joints, std::optional<double> range_min,
             std::optional<double> range_max, const std::string& min_range_policy,
             const std::optional<Measurement>& measurement, bool points) {
    const std::vector<Eigen::Isometry3d> sensors = posesFrom(sensor_poses, "sensor_poses");
    std::map<std::string, std::vector<Eigen::Isometry3d>> links;
    if (link_poses) {
      for (const auto& [name, poses] : *link_poses) {
        bool single = false;
        links[name] = posesFrom(poses, "link_poses['" + name + "']", &single);
      }
    }
    const std::vector<core::FramePoses> frames = scene.framePoses(sensors.size(), joints, links);
    const core::ScanSpec spec =
        specFor(pattern, range_min, range_max, min_range_policy, measurement);
    core::CastConfig config = spec.castConfig();
    config.threads = threads_;
    const std::vector<double> reflectivity =
        measurement ? measurement->reflectivityByLabel(scene.scene()) : std::vector<double>{};

    const py::ssize_t n = static_cast<py::ssize_t>(sensors.size());
    const py::ssize_t beams = pattern.size();
    Scans out;
    out.ranges = py::array_t<double>({n, beams});
    out.links = py::array_t<std::int32_t>({n, beams});
    py::array_t<double> xyz;
    py::array_t<float> intensity;
    if (points) xyz = py::array_t<double>({n, beams, py::ssize_t{3}});
    const bool with_intensity = measurement && measurement->config.intensity;
    if (with_intensity) intensity = py::array_t<float>({n, beams});
    Rows rows{out.ranges.mutable_data(), out.links.mutable_data(),
              points ? xyz.mutable_data() : nullptr,
              with_intensity ? intensity.mutable_data() : nullptr};
    {
      py::gil_scoped_release release;
      std::optional<core::MeasurementModel> model;
      if (measurement) model.emplace(spec.output);
      core::BeamList scratch;
      for (py::ssize_t k = 0; k < n; ++k) {
        caster_.forget();  // every pose cast anew, as cast_scan casts a path
        const core::FramePoses& at = frames[frames.size() == 1 ? 0 : k];
        if (pattern.offGrid()) {
          const core::BeamList& list = pattern.beamsOf(k, &scratch);
          // A calibrated head's turn, the same at every pose, shared with the caster.
          const core::ScanResult& result =
              pattern.turn ? caster_.castBeams(scene.scene(), at, sensors[k], pattern.turn, config)
                           : caster_.castBeams(scene.scene(), at, sensors[k], list, config);
          writeScan(scene.scene(), result, spec.output, list.directions, &list.origins,
                    reflectivity, model ? &*model : nullptr, rows.at(k * beams));
        } else {
          const core::ScanResult& result =
              caster_.cast(scene.scene(), at, sensors[k], pattern.pattern, config);
          writeScan(scene.scene(), result, spec.output, pattern.pattern.directions(), nullptr,
                    reflectivity, model ? &*model : nullptr, rows.at(k * beams));
        }
      }
    }
    if (points) out.points = xyz;
    if (with_intensity) out.intensity = intensity;
    return out;
  }

 private:
  // Where one scan's beams go in the result arrays (null: not asked for).
  struct Rows {
    double* range;
    std::int32_t* link;
    double* xyz;
    float* intensity;
    Rows at(py::ssize_t offset) const {
      return Rows{range + offset, link + offset, xyz ? xyz + 3 * offset : nullptr,
                  intensity ? intensity + offset : nullptr};
    }
  };

  // The scan the node and cast_scan would make of these settings, validated as they validate it.
  static core::ScanSpec specFor(const Pattern& pattern, std::optional<double> range_min,
                                std::optional<double> range_max,
                                const std::string& min_range_policy,
                                const std::optional<Measurement>& measurement) {
    core::ScanSpec spec;
    spec.fan = pattern.fan;
    spec.elevations = pattern.elevations;
    if (measurement) spec.output = measurement->config;
    spec.output.range_min = range_min.value_or(pattern.preset ? pattern.preset->range_min : 0.0);
    spec.output.range_max = range_max.value_or(pattern.preset ? pattern.preset->range_max : 30.0);
    if (!core::kMinRangePolicyNames.parse(min_range_policy, &spec.output.min_range_policy)) {
      throw py::value_error("min_range_policy: " +
                            core::kMinRangePolicyNames.notOneOf(min_range_policy));
    }
    try {
      spec.validate();
    } catch (const std::invalid_argument& e) {
      throw py::value_error(e.what());
    }
    return spec;
  }

  // One scan's beams into its rows: measured by model (as the node publishes them) or, without
  // one, the exact ranges classified as cast_scan prints them.
  // The points leave from origins (beam by beam; null or empty: the sensor's origin) along dirs.
  void writeScan(const core::Scene& scene, const core::ScanResult& result,
                 const core::MeasurementConfig& output, const std::vector<Eigen::Vector3d>& dirs,
                 const std::vector<Eigen::Vector3d>* origins,
                 const std::vector<double>& reflectivity, core::MeasurementModel* model,
                 const Rows& rows) {
    const std::size_t beams = result.range.size();
    if (model) {
      model->measure(scene, result, reflectivity, &measured_);
      for (std::size_t b = 0; b < beams; ++b) {
        rows.range[b] = measured_.ranges[b];
        rows.link[b] = measured_.labels[b];
        if (rows.intensity) rows.intensity[b] = measured_.intensities[b];
      }
    } else {
      // A hit within the limits is itself (classifyRange's first rule, checked here so that
      // most beams skip the call); classifyRange decides every other.
      const double lo = output.range_min, hi = output.range_max;
      for (std::size_t b = 0; b < beams; ++b) {
        const double r = result.range[b];
        rows.range[b] = r >= lo && r <= hi ? r : core::classifyRange(r, output);
        const int body = result.body[b];
        rows.link[b] = body >= 0 ? scene.bodies()[body].label : -1;
      }
    }
    if (!rows.xyz) return;
    const bool offset = origins && !origins->empty();
    for (std::size_t b = 0; b < beams; ++b) {
      const double r = rows.range[b];
      const bool valid = std::isfinite(r);
      for (int a = 0; a < 3; ++a) {
        const double along = r * dirs[b][a];
        rows.xyz[b * 3 + a] = !valid   ? std::numeric_limits<double>::quiet_NaN()
                              : offset ? (*origins)[b][a] + along
                                       : along;
      }
    }
  }

  int threads_;
  core::Caster caster_;
  core::MeasuredScan measured_;
};

inline py::array_t<double> matrixArray(const Eigen::MatrixXd& m) {
  py::array_t<double> out({static_cast<py::ssize_t>(m.rows()), static_cast<py::ssize_t>(m.cols())});
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) out.mutable_at(r, c) = m(r, c);
  return out;
}

}  // namespace python
}  // namespace laser_raycast
