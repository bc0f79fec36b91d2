// A parsed URDF model as the loader's joints, link frames and bodies: the stages of
// SceneLoader::addUrdf (scene_loader.cpp), in order: joints, fixed-joint merging, elements,
// shapes, commit. Only the last one touches the scene.
#pragma once

#include <urdf_model/model.h>

#include <Eigen/Geometry>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "laser_raycast/core/mesh.h"
#include "laser_raycast/core/scene.h"
#include "laser_raycast/loader/scene_loader.h"
#include "urdf_parse.h"

namespace laser_raycast {
namespace urdf_model {

// s in single quotes, as the loader's messages name things.
std::string inQuotes(const std::string& s);
// Throws SceneLoadError naming `what` unless every component of v is finite and > 0.
void requirePositive(const char* what, const Eigen::Vector3d& v);

// Joints: every joint of the model, for forward kinematics. Throws SceneLoadError for an origin
// or axis that is not usable.
std::vector<ModelJoint> modelJoints(const urdf::ModelInterface& model, const std::string& prefix,
                                    const std::string& source);

// Where each link sits: the scene frame it moves with and its pose there (names without prefix).
struct LinkFrames {
  std::vector<urdf::LinkConstSharedPtr> order;  // breadth first from the root
  std::map<std::string, std::pair<std::string, Eigen::Isometry3d>> frame_of;
};
// Fixed-joint merging: each link moves with the topmost link of its fixed chain. Breadth first
// from the root, so a parent is placed before its children.
LinkFrames mergeFixedJoints(const urdf::ModelInterface& model,
                            const urdf::LinkConstSharedPtr& root);

// Reads (or finds in the cache) the mesh of a <mesh> element.
using MeshLoader = std::function<std::shared_ptr<const core::Mesh>(const urdf::Mesh&)>;

// A body waiting for the commit stage; frame and label without the prefix.
struct PendingBody {
  core::Shape shape;
  std::string frame, label;
  Eigen::Isometry3d frame_from_body;
  bool has_color = false;
  Eigen::Vector3d color = Eigen::Vector3d::Zero();
};
// The bodies of every link that is not ignored. A problem is an error, or under skip_bad_geometry
// a warning in *warnings and the element is left out.
std::vector<PendingBody> linkBodies(const LinkFrames& frames, const DroppedElements& dropped,
                                    const LoaderOptions& options, const std::string& source,
                                    const MeshLoader& load_mesh,
                                    std::vector<std::string>* warnings);

// Commit: the bodies into the scene. Called only once every element has succeeded, so a failure
// leaves the scene untouched.
void commitBodies(std::vector<PendingBody> pending, const std::string& prefix,
                  const std::string& source, core::Scene* scene, LoadedModel* out);

}  // namespace urdf_model
}  // namespace laser_raycast
