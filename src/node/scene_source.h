// The node's scene: every model of ~models loaded into one core::Scene, and the reflectivity of
// each of its labels. Meshes go through one loader per process, so that nodelets in one manager
// read each mesh file (with its scale) and build its BVH once between them.
#pragma once

#include <Eigen/Geometry>
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

// One model of the node's scene (an entry of ~models, or one spawned at run time), loaded into a
// scene of its own: the node's scene is its parts composed (composeScene), so a part can be removed
// or moved without loading the others again (their meshes are shared, not copied).
struct ScenePart {
  std::string name;    // unique among the node's parts (~list_models, ~delete_model)
  std::string source;  // where it came from, for ~list_models
  core::Scene scene;   // frames named after its links (or its map's frame), labels after its links
  // false: its frames' poses come from TF. true: it is fixed in the fixed frame, its root link at
  // root_pose and the other links by forward kinematics of `model` at zero joint values.
  bool placed = false;
  Eigen::Isometry3d root_pose = Eigen::Isometry3d::Identity();
  LoadedModel model;  // its links and joints (a map has none)
};

// Loads one URDF (its text in xml, or else the file or URI `file`) into part->scene with the
// node's loader options (~geometry, ~skip_bad_geometry, ~mesh_import_*, ~ignore_links) and
// tf_prefix, through the process's shared mesh cache; fills part->model. Returns "", or what is
// wrong (the message starts with source, or with the file's name).
std::string loadUrdfPart(const NodeParams& params, const std::string& xml, const std::string& file,
                         const std::string& tf_prefix, const std::string& source, ScenePart* part);

// The parts' bodies in one scene: a TF-placed part's on its frames, a placed part's on
// fixed_frame, at the poses of its links. Throws SceneLoadError if a placed part's frame has no
// link pose (not expected of a loaded model).
void composeScene(const std::vector<ScenePart>& parts, const std::string& fixed_frame,
                  core::Scene* scene);

// Loads the models of ~models as parts (named after the URDF's robot name, or the entry's name
// key; a map file after its path), as loadScene does; "" or what is wrong.
std::string loadSceneParts(const NodeParams& params, const UrdfParam& urdf_param,
                           std::vector<ScenePart>* parts, std::vector<double>* reflectivity,
                           core::Scene* scene);

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
