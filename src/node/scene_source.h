// The node's scene: every model of ~models loaded into one core::Scene, and the reflectivity of
// each of its labels. Meshes go through one loader per process, so that nodelets in one manager
// read each mesh file (with its scale) and build its BVH once between them.
#pragma once

#include <ros/ros.h>

#include <vector>

#include "laser_raycast/core/scene.h"
#include "laser_raycast/node/node_params.h"

namespace laser_raycast {

// Loads the models into *scene and fills *reflectivity (by label). Entries with a map_topic are
// left for map_topics.h. Returns false after logging (ROS_FATAL) what is wrong: a missing URDF,
// bad geometry, a bad map file, a reflectivity for an unknown link (only a warning when a map
// topic's grids may bring it, in a frame not known before they come).
bool loadScene(const ros::NodeHandle& nh, const NodeParams& params, core::Scene* scene,
               std::vector<double>* reflectivity);

// The reflectivity of each of scene's labels: ~reflectivity's for those it names, else
// ~default_reflectivity.
std::vector<double> labelReflectivity(const NodeParams& params, const core::Scene& scene);

}  // namespace laser_raycast
