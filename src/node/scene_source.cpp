#include "scene_source.h"

#include <ros/console.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <string>

#include "laser_raycast/loader/kinematics.h"
#include "laser_raycast/loader/map_file.h"
#include "laser_raycast/loader/package_resolver.h"
#include "laser_raycast/loader/scene_loader.h"
#include "param_reader.h"

namespace laser_raycast {
namespace {

// Link names the error about an unknown reflectivity link lists before "... (N more)".
constexpr std::size_t kLinksInError = 20;

// The process's loader: its mesh cache outlives the nodes (meshes stay loaded for the process).
struct SharedLoader {
  std::mutex mutex;
  SceneLoader loader{rosPackagePath};
};

SharedLoader& sharedLoader() {
  static SharedLoader shared;
  return shared;
}

// The loader options for one model: ~ignore_links may name links with or without its prefix.
LoaderOptions optionsFor(const NodeParams& params, const ModelSource& model) {
  LoaderOptions options;
  options.geometry = params.geometry;
  options.skip_bad_geometry = params.skip_bad_geometry;
  options.mesh_import = params.mesh_import;
  options.bvh.threads = params.threads;  // ~threads builds the meshes' BVHs too
  options.tf_prefix = model.tf_prefix;
  for (const std::string& link : params.ignore_links) {
    options.ignore_links.push_back(link);
    if (!model.tf_prefix.empty() && link.compare(0, model.tf_prefix.size(), model.tf_prefix) == 0) {
      options.ignore_links.push_back(link.substr(model.tf_prefix.size()));
    }
  }
  return options;
}

// Adds the walls of map file entry i to scene; "" or what is wrong (naming the file).
std::string loadMapFile(const NodeParams& params, std::size_t i, core::Scene* scene) {
  const ModelSource& model = params.models[i];
  MapWallOptions options;
  options.height = model.height;
  options.frame = model.frame;
  LoadedMap loaded;
  try {
    loaded = addMapFile(model.map, rosPackagePath, options, scene);
  } catch (const SceneLoadError& e) {
    // The message names the file and the problem.
    return "~models[" + std::to_string(i) + "]: " + e.what();
  }
  for (const std::string& warning : loaded.warnings)
    ROS_WARN_STREAM("~models[" << i << "]: " << warning);
  ROS_INFO(
      "map '%s': %d x %d cells of %g m, %zu occupied, walls %g m high in frame '%s' as %zu boxes; "
      "read in %.3f s, walls built in %.3f s",
      model.map.c_str(), loaded.width, loaded.height, loaded.resolution, loaded.occupied_cells,
      model.height, model.frame.c_str(), loaded.boxes, loaded.read_seconds, loaded.build_seconds);
  return "";
}

// Logs what a model's load did.
void logLoaded(const LoadedModel& loaded, const std::string& source) {
  for (const std::string& warning : loaded.warnings) ROS_WARN_STREAM("skipped: " << warning);
  // The meshes' memory, per triangle of the meshes built (an instanced mesh is held once).
  std::string memory;
  if (loaded.mesh_triangles_built > 0) {
    char text[128];
    std::snprintf(text, sizeof(text), "; meshes hold %.1f MB, %.0f bytes per triangle",
                  loaded.mesh_bytes_built / 1e6,
                  static_cast<double>(loaded.mesh_bytes_built) / loaded.mesh_triangles_built);
    memory = text;
  }
  ROS_INFO(
      "model '%s' (%s): %zu links, %zu bodies, %zu triangles; loaded in %.3f s, BVHs built in "
      "%.3f s%s",
      loaded.name.c_str(), source.c_str(), loaded.links, loaded.bodies, loaded.triangles,
      loaded.load_seconds, loaded.bvh_build_seconds, memory.c_str());
}

// Loads model i as a part; "" or what is wrong.
std::string loadModel(const NodeParams& params, const UrdfParam& urdf_param, std::size_t i,
                      ScenePart* part, std::set<std::string>* all_links) {
  const ModelSource& model = params.models[i];
  part->source = model.describe();
  if (!model.map.empty()) {
    part->name = model.name.empty() ? model.map : model.name;
    return loadMapFile(params, i, &part->scene);
  }
  std::string xml, source = model.describe();
  if (!model.param.empty()) {
    std::string resolved = model.param;
    if (!urdf_param(model.param, &xml, &resolved)) {
      return "~models[" + std::to_string(i) + "]: parameter " + resolved +
             " is not set or is not a string: no URDF to load";
    }
    source = "parameter " + resolved;
  }
  const std::string error = loadUrdfPart(params, xml, model.file, model.tf_prefix, source, part);
  if (!error.empty()) return error;
  part->source = source;
  if (!model.name.empty()) part->name = model.name;
  for (const auto& link : part->model.link_frames) all_links->insert(link.first);
  return "";
}

}  // namespace

std::string loadUrdfPart(const NodeParams& params, const std::string& xml, const std::string& file,
                         const std::string& tf_prefix, const std::string& source, ScenePart* part) {
  ModelSource model;
  model.tf_prefix = tf_prefix;
  const LoaderOptions options = optionsFor(params, model);
  try {
    SharedLoader& shared = sharedLoader();
    std::lock_guard<std::mutex> lock(shared.mutex);
    part->model = file.empty() ? shared.loader.addUrdfString(xml, "", options, &part->scene, source)
                               : shared.loader.addUrdfFile(file, options, &part->scene);
  } catch (const SceneLoadError& e) {
    // The message starts with the URDF's source (file or parameter).
    return e.what() + std::string(params.skip_bad_geometry
                                      ? ""
                                      : " (set ~skip_bad_geometry to skip bad elements)");
  }
  part->name = part->model.name;
  logLoaded(part->model, source);
  return "";
}

void composeScene(const std::vector<ScenePart>& parts, const std::string& fixed_frame,
                  core::Scene* scene) {
  for (const ScenePart& part : parts) {
    std::map<std::string, Eigen::Isometry3d> links;
    if (part.placed) links = forwardKinematics(part.model, part.root_pose, {});
    // Every label, and a TF-placed part's every frame, in the part's order: one part composed
    // alone is the scene it was loaded as.
    for (const std::string& label : part.scene.labels()) scene->addLabel(label);
    if (!part.placed) {
      for (const std::string& frame : part.scene.frames()) scene->addFrame(frame);
    }
    for (const core::Body& body : part.scene.bodies()) {
      core::Body copy = body;  // the mesh is shared, not copied
      const std::string& frame = part.scene.frames()[body.frame];
      copy.label = scene->addLabel(part.scene.labels()[body.label]);
      if (part.placed) {
        const auto link = links.find(frame);
        if (link == links.end()) {
          throw SceneLoadError("model '" + part.name + "': no pose for its frame '" + frame + "'");
        }
        copy.frame = scene->addFrame(fixed_frame);
        copy.frame_from_body = link->second * body.frame_from_body;
      } else {
        copy.frame = scene->addFrame(frame);
      }
      scene->addBody(std::move(copy));
    }
  }
}

std::string loadSceneParts(const NodeParams& params, const UrdfParam& urdf_param,
                           std::vector<ScenePart>* parts, std::vector<double>* reflectivity,
                           core::Scene* out) {
  std::set<std::string> all_links;
  for (std::size_t i = 0; i < params.models.size(); ++i) {
    if (!params.models[i].map_topic.empty()) continue;  // its walls come with its grids
    ScenePart part;
    const std::string error = loadModel(params, urdf_param, i, &part, &all_links);
    if (!error.empty()) return error;
    // Names are unique: a second model of one name (one URDF under two prefixes) takes its
    // prefix, then a number.
    const auto taken = [&](const std::string& name) {
      return std::any_of(parts->begin(), parts->end(),
                         [&](const ScenePart& p) { return p.name == name; });
    };
    if (taken(part.name) && !params.models[i].tf_prefix.empty()) {
      part.name = params.models[i].tf_prefix + part.name;
    }
    const std::string base = part.name;
    for (int n = 2; taken(part.name); ++n) part.name = base + "_" + std::to_string(n);
    parts->push_back(std::move(part));
  }
  composeScene(*parts, params.fixed_frame, out);
  core::Scene* scene = out;
  for (const std::string& link : params.ignore_links) {
    bool found = all_links.count(link) > 0;
    for (const ModelSource& model : params.models) {
      found |= all_links.count(model.tf_prefix + link) > 0;
    }
    if (!found) ROS_WARN_STREAM("~ignore_links: no model has a link '" << link << "'");
  }

  // Reflectivity per label (labels are the links, with their TF prefix).
  const auto& labels = scene->labels();
  const bool map_topics = std::any_of(params.models.begin(), params.models.end(),
                                      [](const ModelSource& m) { return !m.map_topic.empty(); });
  for (const auto& entry : params.reflectivity) {
    if (std::find(labels.begin(), labels.end(), entry.first) != labels.end()) continue;
    std::ostringstream message;
    message << "~reflectivity names link '" << entry.first
            << "', which has no geometry in any model (links with geometry: "
            << joinFirst(labels, kLinksInError) << ")";
    if (!map_topics) return message.str();
    ROS_WARN_STREAM(message.str() << ", unless a map topic's grids come in that frame");
  }
  *reflectivity = labelReflectivity(params, *scene);
  if (scene->bodies().empty() && !map_topics) {
    ROS_WARN("the scene has no geometry: every beam will report +Inf");
  }
  return "";
}

std::string loadScene(const NodeParams& params, const UrdfParam& urdf_param, core::Scene* scene,
                      std::vector<double>* reflectivity) {
  std::vector<ScenePart> parts;
  return loadSceneParts(params, urdf_param, &parts, reflectivity, scene);
}

std::vector<double> labelReflectivity(const NodeParams& params, const core::Scene& scene) {
  std::vector<double> reflectivity;
  for (const std::string& label : scene.labels()) {
    const auto it = params.reflectivity.find(label);
    reflectivity.push_back(it != params.reflectivity.end() ? it->second
                                                           : params.default_reflectivity);
  }
  return reflectivity;
}

std::vector<char> labelReflectivityFixed(const NodeParams& params, const core::Scene& scene) {
  std::vector<char> fixed;
  for (const std::string& label : scene.labels()) fixed.push_back(params.reflectivity.count(label));
  return fixed;
}

}  // namespace laser_raycast
