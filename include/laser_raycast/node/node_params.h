// Every parameter of the node: parsed in one place from the values of its private namespace,
// validated, and logged once with its unit. Parsing is a function of the values alone (no
// parameter server), so unit tests call it without roscore; readNodeParams() fetches and logs.
#pragma once

#include <xmlrpcpp/XmlRpcValue.h>

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "laser_raycast/core/enum_names.h"
#include "laser_raycast/core/returns.h"
#include "laser_raycast/core/pattern_file.h"
#include "laser_raycast/core/scan_spec.h"
#include "laser_raycast/loader/map_walls.h"
#include "laser_raycast/loader/scene_loader.h"
#include "laser_raycast/node/point_layout.h"

namespace ros {
class NodeHandle;
}

namespace laser_raycast {

// One entry of ~models: a URDF from a parameter or a file, with an optional TF prefix for its
// links; or a map world (map_walls.h), walls over the occupied cells of a map file or of the
// nav_msgs/OccupancyGrid messages on a topic. Exactly one of param, file, map and map_topic is set.
struct ModelSource {
  // The model's name (~list_models, ~delete_model); "": the URDF's robot name, or a map's path.
  std::string name;
  std::string param;  // parameter name, resolved in the node's namespace (like robot_description)
  std::string file;   // path or package:// URI of a URDF file
  std::string tf_prefix;  // prepended to the model's link names, e.g. "robot2/"
  std::string map;        // path or package:// URI of a map_server map file (YAML)
  std::string map_topic;  // topic of latched grids, relative or global; rebuilt on each new one
  double height = MapWallOptions::kDefaultHeight;  // m, > 0: a map's walls, from z = 0
  std::string frame = "map";  // the TF frame a map file's origin is in (a grid gives its own)

  static ModelSource fromParam(const std::string& name) {
    ModelSource m;
    m.param = name;
    return m;
  }
  bool isMap() const { return !map.empty() || !map_topic.empty(); }
  // "parameter robot_description" / "file /path/x.urdf" / "map /path/m.yaml" / "map topic /map"
  std::string describe() const;
};

// ~intensity: whether intensities are published.
inline const core::EnumNames<bool, 2> kIntensityNames{{{
    {false, "off"}, {true, "reflectivity"},  // reflectivity of the link hit x cos(incidence angle)
}}};

// ~sweep: when each beam is taken.
enum class Sweep {
  kInstant,   // "instant": every beam at the stamp (time_increment 0)
  kRotating,  // "rotating": the head turns once per scan_time; beam column c at stamp + c * dt
};
inline const core::EnumNames<Sweep, 2> kSweepNames{{{
    {Sweep::kInstant, "instant"},
    {Sweep::kRotating, "rotating"},
}}};

// One simulated sensor: its frame, beams, output, timing and pose source. The sensor parameters of
// the private namespace describe one (the shorthand); each entry of ~sensors describes one, with
// those as its defaults.
struct SensorParams {
  // ~rate above this is taken for a slip (a value meant in another unit) rather than served: it is
  // ten times the fastest real planar scanners (about 100 Hz), and at 1 kHz the cast thread has 1
  // ms a scan for the TF look-ups, the cast and publishing.
  static constexpr double kMaxRate = 1000.0;  // Hz

  // Entries of ~sensors: its name (in the log, the diagnostics, and the namespace of its live
  // parameters), default frame_id made a valid name ('/' and other characters a name may not hold
  // become '_', "sensor_" in front if it does not start with a letter); and its topic, default
  // <name>/scan or <name>/points. The shorthand: frame_id, and scan or points (relative to the
  // node's namespace).
  std::string name;
  std::string topic;
  std::string sensor_model;        // a preset (core::kSensorModelNames), "" for none
  std::string frame_id = "laser";  // sensor frame; header.frame_id of the scans
  // Beams, range limits, min-range policy, noise, intensity, triangle test. fan.samples is 0 here:
  // the parser sets core::FanSpec::kDefaultSamples when neither it nor angle_increment is given.
  core::ScanSpec scan;
  // Beam divergence and the return mode (core/returns.h); beam_samples 1: the ideal ray.
  core::ReturnsConfig returns;
  double rate = 10.0;  // Hz, in (0, kMaxRate]
  Sweep sweep = Sweep::kInstant;
  double scan_time = 0;    // s, in (0, 1 / rate]: one turn of a rotating head; 0: 1 / rate
  bool organized = false;  // PointCloud2: every beam, height = rings (else valid returns only)
  PointLayout point_layout = PointLayout::kVelodyne;  // PointCloud2: whose driver's fields
  std::string pose_topic;                             // empty: the sensor pose comes from TF
  std::string pose_frame;  // frame whose pose pose_topic gives; empty: frame_id
  // s, > 0: a topic pose older than this at a scan's time is stale (the scan is skipped). Pose
  // sources run at 10 to 100 Hz: this is five periods of the slowest.
  double pose_timeout = 0.5;
  // ~pattern_file: the beams from a scan pattern CSV (core::PatternFile) instead of the fan, each
  // scan the file's next points_per_scan rows (0: all of them), point k at k / point_rate s.
  std::string pattern_file;
  std::shared_ptr<const core::PatternFile> pattern;  // loaded from pattern_file
  int points_per_scan = 0;
  double point_rate = 0;  // Hz, > 0 with a pattern file
  // ~calibration_file: a Velodyne calibration YAML; its head's beams over one turn of scanTime(),
  // the same every scan (core::VelodyneHead::scan).
  std::string calibration_file;
  // ~ouster_metadata: an Ouster sensor metadata JSON; its W columns over one turn of scanTime(),
  // the same every scan (core::OusterHead::scan).
  std::string ouster_metadata;
  // The beams of calibration_file or ouster_metadata, or of sensor_model's head (one turn).
  std::shared_ptr<const core::BeamList> calibrated;
  // The head calibrated's beams are one turn of: its beams over one turn of the given s, to turn
  // them again when scanTime() changes (a live rate change, scan_time following the rate).
  std::function<core::BeamList(double)> head_turn;
  // calibrated is the preset's head (core::SensorModel::head), not a file's.
  bool preset_head = false;
  // Where calibrated came from: the file, or "the <sensor_model> preset's lasers".
  std::string calibratedFrom() const {
    if (preset_head) return "the " + sensor_model + " preset's lasers";
    return calibration_file.empty() ? ouster_metadata : calibration_file;
  }
  // Beams off any grid (a pattern file's or a calibrated head's): a PointCloud2 of one row.
  bool offGrid() const { return pattern || calibrated; }

  // A single ring at elevation 0 and no pattern file: a LaserScan (otherwise a PointCloud2).
  bool planar() const {
    return !offGrid() && scan.elevations.size() == 1 && scan.elevations[0] == 0.0;
  }
  double scanTime() const { return scan_time > 0 ? scan_time : 1.0 / rate; }
  // s between beam columns: angle_increment * scan_time / 2 pi when rotating, else 0.
  double timeIncrement() const;
  // s from the first beam column to the last (0 when instantaneous).
  double sweepDuration() const;
  std::string labelsTopic() const { return topic + "_labels"; }
};

struct NodeParams {
  // ~tf_timeout above this is taken for a slip (milliseconds given as seconds): it is how old a
  // scan may be when it is cast, and the TF buffer keeps 10 s.
  static constexpr double kMaxTfTimeout = 10.0;  // s

  std::string fixed_frame = "map";  // frame the link and sensor poses are looked up in
  // s, in [0, kMaxTfTimeout]: how late a transform may arrive. A scan waits (in the cast thread,
  // never the timer) until TF covers its last beam's time; a transform whose newest data is older
  // than this is not waited for (its link is left out, or without the sensor's the scan is
  // skipped). TF 0.1 to 0.3 s late (a loaded tree, a bag, a slow link) is served at full rate.
  double tf_timeout = 0.5;
  // Threads each cast uses (core::CastConfig::threads; 0: every core). The ranges do not depend on
  // it; a large 3D scan is cast faster, a 2D fan stays on one thread.
  int threads = 1;
  GeometrySource geometry = GeometrySource::kVisual;
  bool skip_bad_geometry = false;
  // ~mesh_import_max_memory_mb, ~mesh_import_timeout: the bounds of one mesh file's import, 0 (the
  // default) for bounds that follow the file's size (MeshImportBounds).
  MeshImportBounds mesh_import;
  std::vector<ModelSource> models = {ModelSource::fromParam("robot_description")};
  std::vector<std::string> ignore_links;
  std::map<std::string, double> reflectivity;  // link name (with TF prefix) -> reflectivity
  double default_reflectivity = 1.0;
  std::vector<SensorParams> sensors;  // at least one after parsing

  // TF and pose topics keep data as far back as the oldest time a queued scan can still need: this
  // many seconds (tf_timeout, the longest period, and a second to spare).
  double history() const;
  // s of TF the buffer keeps: history(), and at least tf2's default of 10 s.
  double tfCache() const;
  // s of a sensor's pose topic messages kept: history() and the age a message may still serve at.
  double poseHistory(const SensorParams& sensor) const;
};

// What parsing reports besides the values.
struct ParamReport {
  // One line per parameter with its value and unit ("~rate = 10 Hz"), for the start-up log.
  std::vector<std::string> values;
  // Set parameters the node does not read (usually typos), and settings that have no effect.
  std::vector<std::string> warnings;
};

// Parses the node's private parameters from `values`, a struct of them as the parameter server
// returns the private namespace (an invalid value: none set). `ns` is the namespace the node
// resolves its topics in (its NodeHandle's: "/" or e.g. "/robot1"; std::invalid_argument if it is
// not a global name), so that two sensors publishing on one topic are refused however their names
// are written. Unset parameters take their defaults. Entries of ~models that name a parameter are
// kept as names (the node reads the URDF). Returns "" on success, or the first error: a message
// naming the parameter and its bad value (wrong type, out of range, inconsistent with another
// parameter). The report is filled either way.
std::string parseNodeParams(const XmlRpc::XmlRpcValue& values, const std::string& ns,
                            NodeParams* params, ParamReport* report);

// The name of every parameter parseNodeParams reads, in the order it reads them.
std::vector<std::string> nodeParamNames();

// Fetches the private namespace of pnh from the parameter server and parses it for a node whose
// topics are advertised in nh, logging each value (INFO) and each warning (WARN). Returns false
// with the message in *error on a bad value.
bool readNodeParams(const ros::NodeHandle& nh, const ros::NodeHandle& pnh, NodeParams* params,
                    std::string* error);

}  // namespace laser_raycast
