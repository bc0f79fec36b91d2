// Every parameter of the node, read in one place, logged once with its unit, and validated.
#pragma once

#include <ros/node_handle.h>

#include <map>
#include <string>
#include <vector>

#include "laser_raycast/core/scan_spec.h"
#include "laser_raycast/loader/scene_loader.h"

namespace laser_raycast {

// One entry of ~models: a URDF from a parameter or a file, with an optional TF prefix for its
// links.
struct ModelSource {
  std::string param;  // parameter name, resolved in the node's namespace (like robot_description)
  std::string file;   // path or package:// URI of a URDF file
  std::string tf_prefix;  // prepended to the model's link names, e.g. "robot2/"

  std::string describe() const;  // "parameter robot_description" / "file /path/x.urdf"
};

struct NodeParams {
  std::string frame_id = "laser";   // sensor frame; header.frame_id of the scans
  std::string fixed_frame = "map";  // frame the link and sensor poses are looked up in
  core::ScanSpec scan;  // beams, range limits, min-range policy, noise, intensity, triangle test
  double rate = 10.0;   // Hz
  double tf_timeout = 0.1;  // s, longest wait for the transforms of one scan
  GeometrySource geometry = GeometrySource::kVisual;
  bool skip_bad_geometry = false;
  std::vector<ModelSource> models;
  std::vector<std::string> ignore_links;
  std::map<std::string, double> reflectivity;  // link name (with TF prefix) -> reflectivity
  double default_reflectivity = 1.0;
  std::string pose_topic;  // empty: the sensor pose comes from TF
  std::string pose_frame;  // frame whose pose pose_topic gives; empty: frame_id
};

// Reads the private parameters of pnh into params, logging each with its value and unit. Returns
// false and sets *error to a message naming the parameter and the bad value if any is wrong (wrong
// type, out of range, inconsistent). Unknown private parameters are reported with a warning (they
// are usually typos).
bool readNodeParams(const ros::NodeHandle& pnh, NodeParams* params, std::string* error);

}  // namespace laser_raycast
