// The node's scene: every model of ~models loaded into one core::Scene, and the reflectivity of
// each of its labels. Meshes go through one loader per process, so that nodelets in one manager
// read each mesh file (with its scale) and build its BVH once between them.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "laser_raycast/core/scene.h"
#include "laser_raycast/node/node_params.h"

namespace laser_raycast {

// The text of a URDF given by parameter name (~models' {param: NAME}); false if there is none. Sets
// *resolved to the parameter's full name, for messages.
using UrdfParam =
    std::function<bool(const std::string& name, std::string* xml, std::string* resolved)>;

// Loads the models into *scene and fills *reflectivity (by label), logging each model (INFO) and
// what was skipped (WARN). Entries with a map_topic are left for map_topics.h. Returns "", or what
// is wrong for the caller to report: a missing URDF, bad geometry, a bad map file, a reflectivity
// for an unknown link (only a warning when a map topic's grids may bring it, in a frame not known
// before they come).
std::string loadScene(const NodeParams& params, const UrdfParam& urdf_param, core::Scene* scene,
                      std::vector<double>* reflectivity);

// The reflectivity of each of scene's labels: ~reflectivity's for those it names, else
// ~default_reflectivity.
std::vector<double> labelReflectivity(const NodeParams& params, const core::Scene& scene);
// Per label, 1 where ~reflectivity names it: that value then takes precedence over the colours of
// its meshes (core::sampleSurfaces).
std::vector<char> labelReflectivityFixed(const NodeParams& params, const core::Scene& scene);

}  // namespace laser_raycast
