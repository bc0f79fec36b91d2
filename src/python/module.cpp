// The Python module laser_raycast._laser_raycast (pybind11): scenes from URDF, scan patterns, and
// a caster that casts a pattern from many sensor poses at once into numpy arrays. The package
// laser_raycast (python/laser_raycast/__init__.py) re-exports it; docs/python.md describes it.
//
// It is a thin layer over the loader and the core, as cast_scan is: the same scene, the same
// casts, the same REP 117 classification, so that its ranges are cast_scan's.
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

#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/measurement_model.h"
#include "laser_raycast/core/scan_spec.h"
#include "laser_raycast/core/sensor_model.h"
#include "laser_raycast/loader/kinematics.h"
#include "laser_raycast/loader/scene_loader.h"

namespace py = pybind11;

namespace laser_raycast {
namespace python {
namespace {

using Poses = py::array_t<double, py::array::c_style | py::array::forcecast>;

std::string shapeOf(const py::array& a) {
  std::ostringstream out;
  out << "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) out << (i ? ", " : "") << a.shape(i);
  out << (a.ndim() == 1 ? ",)" : ")");
  return out.str();
}

// A (4, 4) or (N, 4, 4) array of homogeneous transforms as N poses: TypeError naming `what` for
// something that is not an array of numbers, ValueError for another shape. A (4, 4) array is one
// pose (N = 1) if `single` is given, which then says so.
std::vector<Eigen::Isometry3d> posesFrom(const py::handle& object, const std::string& what,
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

// The beams of a scan, and a preset's range limits if it came from one.
struct Pattern {
  core::FanSpec fan;
  std::vector<double> elevations{0.0};
  std::optional<core::SensorModel> preset;
  core::ScanPattern pattern{core::FanSpec{-M_PI, M_PI, 0, 2}};

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
    if (!model) throw py::value_error("name: " + core::kSensorModelNames.notOneOf(name));
    Pattern p;
    p.fan = model->fan;
    p.elevations = model->elevations;
    p.preset = model;
    p.build();
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
};

// The measurement model's options (the node's parameters of the same names).
struct Measurement {
  core::MeasurementConfig config;  // its range limits are the cast's, set there
  std::map<std::string, double> reflectivity;
  double default_reflectivity = 1.0;
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
    core::CastConfig config;
    try {
      spec.validate();
      config = spec.castConfig();
    } catch (const std::invalid_argument& e) {
      throw py::value_error(e.what());
    }
    config.threads = threads_;
    std::vector<double> reflectivity;
    if (measurement) {
      const core::Scene& s = scene.scene();
      reflectivity.assign(s.labels().size(), measurement->default_reflectivity);
      for (const auto& [name, value] : measurement->reflectivity) {
        const auto it = std::find(s.labels().begin(), s.labels().end(), name);
        if (it == s.labels().end()) {
          throw py::value_error("reflectivity: '" + name + "' is not a link with geometry");
        }
        reflectivity[it - s.labels().begin()] = value;
      }
    }

    const py::ssize_t n = static_cast<py::ssize_t>(sensors.size());
    const py::ssize_t beams = pattern.pattern.size();
    Scans out;
    out.ranges = py::array_t<double>({n, beams});
    out.links = py::array_t<std::int32_t>({n, beams});
    py::array_t<double> xyz;
    py::array_t<float> intensity;
    if (points) xyz = py::array_t<double>({n, beams, py::ssize_t{3}});
    const bool with_intensity = measurement && measurement->config.intensity;
    if (with_intensity) intensity = py::array_t<float>({n, beams});
    double* range_out = out.ranges.mutable_data();
    std::int32_t* link_out = out.links.mutable_data();
    double* xyz_out = points ? xyz.mutable_data() : nullptr;
    float* intensity_out = with_intensity ? intensity.mutable_data() : nullptr;
    const auto& dirs = pattern.pattern.directions();
    {
      py::gil_scoped_release release;
      std::optional<core::MeasurementModel> model;
      if (measurement) model.emplace(spec.output);
      core::MeasuredScan measured;
      for (py::ssize_t k = 0; k < n; ++k) {
        caster_.forget();  // every pose cast anew, as cast_scan casts a path
        const core::ScanResult& result = caster_.cast(
            scene.scene(), frames[frames.size() == 1 ? 0 : k], sensors[k], pattern.pattern, config);
        for (py::ssize_t b = 0; b < beams; ++b) {
          const int body = result.body[b];
          link_out[k * beams + b] = body >= 0 ? scene.scene().bodies()[body].label : -1;
        }
        if (model) {
          model->measure(scene.scene(), result, reflectivity, &measured);
          for (py::ssize_t b = 0; b < beams; ++b) {
            range_out[k * beams + b] = measured.ranges[b];
            link_out[k * beams + b] = measured.labels[b];
            if (intensity_out) intensity_out[k * beams + b] = measured.intensities[b];
          }
        } else {
          // A hit within the limits is itself (classifyRange's first rule, checked here so that
          // most beams skip the call); classifyRange decides every other.
          const double lo = spec.output.range_min, hi = spec.output.range_max;
          for (py::ssize_t b = 0; b < beams; ++b) {
            const double r = result.range[b];
            range_out[k * beams + b] =
                r >= lo && r <= hi ? r : core::classifyRange(r, spec.output);
          }
        }
        if (xyz_out) {
          for (py::ssize_t b = 0; b < beams; ++b) {
            const double r = range_out[k * beams + b];
            const bool valid = std::isfinite(r);
            for (int a = 0; a < 3; ++a) {
              xyz_out[(k * beams + b) * 3 + a] =
                  valid ? r * dirs[b][a] : std::numeric_limits<double>::quiet_NaN();
            }
          }
        }
      }
    }
    if (points) out.points = xyz;
    if (with_intensity) out.intensity = intensity;
    return out;
  }

 private:
  int threads_;
  core::Caster caster_;
};

py::array_t<double> matrixArray(const Eigen::MatrixXd& m) {
  py::array_t<double> out({static_cast<py::ssize_t>(m.rows()), static_cast<py::ssize_t>(m.cols())});
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) out.mutable_at(r, c) = m(r, c);
  return out;
}

}  // namespace
}  // namespace python
}  // namespace laser_raycast

PYBIND11_MODULE(_laser_raycast, m) {
  using laser_raycast::SceneLoadError;
  using laser_raycast::python::Caster;
  using laser_raycast::python::matrixArray;
  using laser_raycast::python::Measurement;
  using laser_raycast::python::Pattern;
  using laser_raycast::python::Scans;
  using laser_raycast::python::Scene;
  namespace core = laser_raycast::core;

  m.doc() =
      "Simulated laser scanners and lidars: load URDF models, describe a scan pattern, and cast "
      "it\n"
      "from many sensor poses at once. The same scene, casts and REP 117 ranges as the node and\n"
      "cast_scan (docs/python.md).";

  py::register_exception<SceneLoadError>(m, "SceneLoadError", PyExc_RuntimeError);

  py::class_<Scene, std::shared_ptr<Scene>>(
      m, "Scene",
      "The geometry of one or more URDF models: meshes (through assimp, or the STL reader) and\n"
      "primitives, each on the frame of its link. package:// URIs are found on ROS_PACKAGE_PATH.")
      .def_static(
          "from_urdf", &Scene::fromUrdf, py::arg("path_or_xml"), py::arg("geometry") = "visual",
          py::arg("tf_prefix") = "",
          "A scene of one URDF model: path_or_xml is a file path, a package:// URI, or the\n"
          "URDF's XML itself (text starting with '<'). geometry: 'visual' (a link without\n"
          "visual elements uses its collision ones) or 'collision'. tf_prefix is prepended\n"
          "to every link name. Raises SceneLoadError naming the file and the problem.")
      .def("add_urdf", &Scene::addUrdf, py::arg("path_or_xml"), py::arg("geometry") = "visual",
           py::arg("tf_prefix") = "",
           "Adds another model (as from_urdf); a model that fails to load leaves the scene as it "
           "was.")
      .def_property_readonly(
          "link_names", [](const Scene& s) { return s.scene().labels(); },
          "The links with geometry, in the order the `links` arrays of Caster.cast index them.")
      .def_property_readonly("links", &Scene::linkNames,
                             "Every link of the models (with their tf_prefix), geometry or not.")
      .def_property_readonly(
          "bodies", [](const Scene& s) { return s.scene().bodies().size(); },
          "How many bodies (meshes and primitives) the scene holds.")
      .def("__repr__", [](const Scene& s) {
        return "<laser_raycast.Scene: " + std::to_string(s.models().size()) + " model(s), " +
               std::to_string(s.scene().bodies().size()) + " bodies>";
      });

  py::class_<Pattern>(m, "Pattern",
                      "The beams of a scan in the sensor frame: a fan of azimuths (counter-"
                      "clockwise from x about z) at one or more elevations (up from the xy plane).")
      .def_static(
          "fan",
          [](double angle_min, double angle_max, std::optional<int> samples,
             std::optional<double> angle_increment) {
            return Pattern::make(angle_min, angle_max, samples, angle_increment, {0.0});
          },
          py::arg("angle_min"), py::arg("angle_max"), py::arg("samples") = py::none(),
          py::arg("angle_increment") = py::none(),
          "A planar fan (a LaserScan) from angle_min to angle_max (rad): samples beams\n"
          "spread evenly over it, both ends included, or one every angle_increment rad from\n"
          "angle_min (exactly one of the two). Raises ValueError naming a bad value.")
      .def_static(
          "rings",
          [](double angle_min, double angle_max, std::vector<double> elevations,
             std::optional<int> samples, std::optional<double> angle_increment) {
            return Pattern::make(angle_min, angle_max, samples, angle_increment,
                                 std::move(elevations));
          },
          py::arg("angle_min"), py::arg("angle_max"), py::arg("elevations"),
          py::arg("samples") = py::none(), py::arg("angle_increment") = py::none(),
          "One fan per elevation (rad, in [-pi/2, pi/2], distinct): ring r is the r-th\n"
          "lowest, and beam r * azimuths + i is azimuth i of ring r.")
      .def_static("preset", &Pattern::fromPreset, py::arg("name"),
                  "The pattern and range limits of a real sensor ('VLP-16', 'HDL-32E', 'OS1-64',\n"
                  "'UTM-30LX', 'TiM571', 'LDS-01'), from its datasheet (docs/sensors.md).")
      .def_property_readonly(
          "size", [](const Pattern& p) { return p.pattern.size(); }, "Beams in one scan.")
      .def_property_readonly("azimuth_count",
                             [](const Pattern& p) { return p.pattern.azimuthCount(); })
      .def_property_readonly(
          "azimuths",
          [](const Pattern& p) {
            std::vector<double> a(p.pattern.azimuthCount());
            for (int i = 0; i < p.pattern.azimuthCount(); ++i) a[i] = p.pattern.azimuth(i);
            return a;
          },
          "The azimuths (rad), the same in every ring.")
      .def_property_readonly(
          "elevations", [](const Pattern& p) { return p.elevations; },
          "The rings' elevations (rad), ascending.")
      .def_property_readonly(
          "directions",
          [](const Pattern& p) {
            const auto& d = p.pattern.directions();
            Eigen::MatrixXd m(d.size(), 3);
            for (std::size_t i = 0; i < d.size(); ++i) m.row(i) = d[i].transpose();
            return matrixArray(m);
          },
          "Unit beam directions in the sensor frame, shape (size, 3), ring-major.")
      .def_property_readonly(
          "range_min",
          [](const Pattern& p) -> py::object {
            return p.preset ? py::cast(p.preset->range_min) : py::none();
          },
          "A preset's range_min (m), or None.")
      .def_property_readonly(
          "range_max",
          [](const Pattern& p) -> py::object {
            return p.preset ? py::cast(p.preset->range_max) : py::none();
          },
          "A preset's range_max (m), or None.")
      .def_property_readonly(
          "rate",
          [](const Pattern& p) -> py::object {
            return p.preset ? py::cast(p.preset->rate) : py::none();
          },
          "A preset's scan rate (Hz), or None.")
      .def("__repr__", [](const Pattern& p) {
        return "<laser_raycast.Pattern: " + std::to_string(p.pattern.ringCount()) + " ring(s) x " +
               std::to_string(p.pattern.azimuthCount()) + " azimuths>";
      });

  py::class_<Measurement>(
      m, "Measurement",
      "What the sensor reports, beyond the geometry: the node's parameters of the same names.\n"
      "Ranges are then rounded to float as the node publishes them; the random draws follow\n"
      "noise_seed and continue from scan to scan within one cast().")
      .def(py::init([](double noise_stddev, std::uint64_t noise_seed, double range_bias,
                       double range_resolution, double dropout_probability, bool intensity,
                       std::map<std::string, double> reflectivity, double default_reflectivity) {
             Measurement out;
             out.config.noise_stddev = noise_stddev;
             out.config.noise_seed = noise_seed;
             out.config.range_bias = range_bias;
             out.config.range_resolution = range_resolution;
             out.config.dropout_probability = dropout_probability;
             out.config.intensity = intensity;
             out.reflectivity = std::move(reflectivity);
             out.default_reflectivity = default_reflectivity;
             core::MeasurementConfig check = out.config;
             try {
               check.validate();
             } catch (const std::invalid_argument& e) {
               throw py::value_error(e.what());
             }
             return out;
           }),
           py::arg("noise_stddev") = 0.0, py::arg("noise_seed") = 0, py::arg("range_bias") = 0.0,
           py::arg("range_resolution") = 0.0, py::arg("dropout_probability") = 0.0,
           py::arg("intensity") = false, py::arg("reflectivity") = std::map<std::string, double>{},
           py::arg("default_reflectivity") = 1.0,
           "noise_stddev (m): Gaussian noise on valid ranges; range_bias (m); range_resolution\n"
           "(m, 0: off); dropout_probability in [0, 1]: a valid return lost (+inf);\n"
           "intensity: fill Scans.intensity with reflectivity x cos(incidence), reflectivity by\n"
           "link name (default_reflectivity for the others).");

  py::class_<Scans>(m, "Scans", "What Caster.cast returns: numpy arrays, one row per sensor pose.")
      .def_readonly("ranges", &Scans::ranges,
                    "float64 (N, beams), REP 117: a hit in [range_min, range_max] is its range,\n"
                    "+inf no return, -inf too close (min_range_policy '-inf'), nan not castable.")
      .def_readonly("links", &Scans::links,
                    "int32 (N, beams): the index in Scene.link_names of the link hit, -1 none.")
      .def_readonly("points", &Scans::points,
                    "float64 (N, beams, 3) in the sensor frame (nan where no valid return), or "
                    "None.")
      .def_readonly("intensity", &Scans::intensity,
                    "float32 (N, beams) with Measurement(intensity=True), or None.");

  py::class_<Caster>(m, "Caster",
                     "Casts patterns against scenes. Results are the same for any thread count.")
      .def(py::init<int>(), py::arg("threads") = 0,
           "threads: the threads each scan is cast with (0: every core).")
      .def(
          "cast", &Caster::cast, py::arg("scene"), py::arg("sensor_poses"), py::arg("pattern"),
          py::arg("link_poses") = py::none(), py::arg("joints") = std::map<std::string, double>{},
          py::arg("range_min") = py::none(), py::arg("range_max") = py::none(),
          py::arg("min_range_policy") = "-inf", py::arg("measurement") = py::none(),
          py::arg("points") = false,
          "Casts pattern from each of sensor_poses, a float64 array (N, 4, 4) of homogeneous\n"
          "transforms (the sensor in the common frame), one scan each, with the GIL released.\n"
          "Links: each model's root link at the identity of the common frame and its joints at\n"
          "`joints` (name -> rad or m, 0 if absent); link_poses (link name -> (4, 4) or\n"
          "(N, 4, 4)) places those links instead. range_min, range_max (m): a preset's, or 0 and\n"
          "30. min_range_policy: '-inf', 'pass_through' or 'nan'. Without measurement, ranges are\n"
          "the exact ones as cast_scan prints them; with a Measurement, as the node publishes\n"
          "them. points: also the points. Returns Scans. Raises ValueError naming a bad argument.");
}
