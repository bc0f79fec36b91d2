// The Python module laser_raycast._laser_raycast (pybind11): the classes of python_api.h with
// their docstrings. The package laser_raycast (python/laser_raycast/__init__.py) re-exports it;
// docs/python.md describes it.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "python_api.h"

namespace {

using laser_raycast::SceneLoadError;
using laser_raycast::python::Caster;
using laser_raycast::python::matrixArray;
using laser_raycast::python::Measurement;
using laser_raycast::python::Pattern;
using laser_raycast::python::Scans;
using laser_raycast::python::Scene;
namespace core = laser_raycast::core;

void bindScene(py::module_& m) {
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
}

void bindPattern(py::module_& m) {
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
                  "'UTM-30LX', 'TiM571', 'LDS-01'), from its datasheet (docs/sensors.md). The\n"
                  "lidars' beams are off any grid, as the node's presets fire them: the\n"
                  "Velodynes' lasers by their manuals' tables and times, the OS1-64's from its\n"
                  "nominal metadata file in the package; the planar scanners are fans.")
      .def_static("from_calibration", &Pattern::fromCalibration, py::arg("path"),
                  py::arg("scan_time") = Pattern::kCalibratedScanTime,
                  "A Velodyne head from its calibration YAML (velodyne_pointcloud's, as the\n"
                  "node's calibration_file and cast_scan --calibration read it): each laser's\n"
                  "beam and origin over one turn of scan_time s (in (0, 1]), each laser at the\n"
                  "azimuth its firing time gives. Beams off any grid: the same every scan.")
      .def_static("from_ouster_metadata", &Pattern::fromOusterMetadata, py::arg("path"),
                  py::arg("scan_time") = py::none(),
                  "An Ouster head from its sensor metadata JSON (legacy or nested, as the node's\n"
                  "ouster_metadata and cast_scan --ouster-metadata read it): each column's beams\n"
                  "and origins over one turn of scan_time s (the file's lidar mode's if None).")
      .def_static("from_pattern_file", &Pattern::fromPatternFile, py::arg("path"),
                  py::arg("point_rate"), py::arg("points_per_scan") = py::none(),
                  "A scan pattern CSV 'Time/s,Azimuth/deg,Zenith/deg[,Line]' (Livox's simulation\n"
                  "files; the node's pattern_file, cast_scan --pattern-file) read as a loop: scan\n"
                  "k of a cast takes points_per_scan rows (all if None) from row k *\n"
                  "points_per_scan on, as cast_scan --poses does; point_rate (Hz) times them.")
      .def_property_readonly(
          "size", [](const Pattern& p) { return p.size(); }, "Beams in one scan.")
      .def_property_readonly(
          "off_grid", [](const Pattern& p) { return p.offGrid(); },
          "True for beams off any grid (a calibration, metadata or pattern file).")
      .def_property_readonly(
          "azimuth_count",
          [](const Pattern& p) -> py::object {
            return p.offGrid() ? py::none() : py::cast(p.pattern.azimuthCount());
          },
          "Azimuths in each ring, or None off a grid.")
      .def_property_readonly(
          "azimuths",
          [](const Pattern& p) -> py::object {
            if (p.offGrid()) return py::none();
            std::vector<double> a(p.pattern.azimuthCount());
            for (int i = 0; i < p.pattern.azimuthCount(); ++i) a[i] = p.pattern.azimuth(i);
            return py::cast(a);
          },
          "The azimuths (rad), the same in every ring; None off a grid.")
      .def_property_readonly(
          "elevations",
          [](const Pattern& p) -> py::object {
            return p.offGrid() ? py::none() : py::cast(p.elevations);
          },
          "The rings' elevations (rad), ascending; None off a grid.")
      .def_property_readonly(
          "directions",
          [](const Pattern& p) {
            core::BeamList scratch;
            const auto& d =
                p.offGrid() ? p.beamsOf(0, &scratch).directions : p.pattern.directions();
            Eigen::MatrixXd m(d.size(), 3);
            for (std::size_t i = 0; i < d.size(); ++i) m.row(i) = d[i].transpose();
            return matrixArray(m);
          },
          "Unit beam directions in the sensor frame, shape (size, 3): ring-major on a grid;\n"
          "off a grid in firing order (a pattern file's first scan).")
      .def_property_readonly(
          "origins",
          [](const Pattern& p) {
            core::BeamList scratch;
            Eigen::MatrixXd m = Eigen::MatrixXd::Zero(p.size(), 3);
            if (p.offGrid()) {
              const core::BeamList& b = p.beamsOf(0, &scratch);
              for (int i = 0; i < b.size(); ++i) m.row(i) = b.origin(i).transpose();
            }
            return matrixArray(m);
          },
          "Where each beam leaves from in the sensor frame (m), shape (size, 3): zeros but for\n"
          "a calibrated head's offsets. Ranges are measured from there; points are\n"
          "origin + range * direction.")
      .def_property_readonly(
          "times",
          [](const Pattern& p) {
            core::BeamList scratch;
            std::vector<double> t(p.size(), 0.0);
            if (p.offGrid()) {
              const core::BeamList& b = p.beamsOf(0, &scratch);
              for (int i = 0; i < b.size(); ++i) t[i] = b.time(i);
            }
            return t;
          },
          "Each beam's firing time (s after the scan's stamp) off a grid; zeros on a grid.\n"
          "Caster.cast casts every beam at once, from the scan's pose.")
      .def_property_readonly(
          "lines",
          [](const Pattern& p) {
            std::vector<int> l(p.size());
            if (p.offGrid()) {
              core::BeamList scratch;
              const core::BeamList& b = p.beamsOf(0, &scratch);
              for (int i = 0; i < b.size(); ++i) l[i] = b.line(i);
            } else {
              for (int i = 0; i < p.size(); ++i) l[i] = i / p.pattern.azimuthCount();
            }
            return l;
          },
          "Each beam's ring (numbered by ascending elevation) or a pattern file's line.")
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
        if (p.offGrid()) {
          return "<laser_raycast.Pattern: " + std::to_string(p.size()) +
                 " beams off any grid, from '" + p.source + "'>";
        }
        return "<laser_raycast.Pattern: " + std::to_string(p.pattern.ringCount()) + " ring(s) x " +
               std::to_string(p.pattern.azimuthCount()) + " azimuths>";
      });
}

void bindMeasurement(py::module_& m) {
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
}

void bindScans(py::module_& m) {
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
}

void bindCaster(py::module_& m) {
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

}  // namespace

PYBIND11_MODULE(_laser_raycast, m) {
  m.doc() =
      "Simulated laser scanners and lidars: load URDF models, describe a scan pattern, and cast\n"
      "it from many sensor poses at once. The same scene, casts and REP 117 ranges as the node\n"
      "and cast_scan (docs/python.md).";

  py::register_exception<SceneLoadError>(m, "SceneLoadError", PyExc_RuntimeError);
  bindScene(m);
  bindPattern(m);
  bindMeasurement(m);
  bindScans(m);
  bindCaster(m);
}
