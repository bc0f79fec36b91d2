// Run-time scene editing: the node's services ~spawn_model, ~delete_model, ~set_model_pose and
// ~list_models (srv/; README, "Changing the world"). The node's scene is a list of parts
// (scene_source.h: the models of ~models, then those spawned, then the walls of the map topics'
// grids); each change composes a new scene from the parts, whose meshes and BVHs are shared rather
// than rebuilt, and swaps it into the SharedScene whole (shared_scene.h) before the service
// answers: the cast thread takes it for its next job, so every scan stamped after the answer sees
// the change and no scan mixes the scenes before and after it.
//
// The services are served by a thread of their own (their own callback queue), so a slow load (a
// large mesh file) never holds up the node's timers, pose topics or TF.
#pragma once

#include <ros/callback_queue.h>
#include <ros/ros.h>

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "laser_raycast/DeleteModel.h"
#include "laser_raycast/ListModels.h"
#include "laser_raycast/SetModelPose.h"
#include "laser_raycast/SpawnModel.h"
#include "laser_raycast/node/node_params.h"
#include "scene_source.h"
#include "shared_scene.h"

namespace laser_raycast {

// A geometry_msgs/Pose as a rigid transform; false (with the reason in *error) if a value is not
// finite. An all-zero orientation (what a message left unset holds) is the identity; any other is
// normalized.
bool poseFromMsg(const geometry_msgs::Pose& msg, Eigen::Isometry3d* pose, std::string* error);

class SceneEditor {
 public:
  // parts: the models of ~models as loaded (loadSceneParts); scene: where the composed scenes go
  // (it must outlive this). Advertises the services in pnh's namespace.
  SceneEditor(const ros::NodeHandle& pnh, const NodeParams& params, std::vector<ScenePart> parts,
              SharedScene* scene);
  ~SceneEditor();  // stops serving; a call under way finishes first

  // The walls of every map topic's newest grid (map_topics.h), in a scene of their own: composed
  // after the models. Any thread.
  void setMapWalls(core::Scene walls);

  // The services, callable directly (tests); any thread.
  bool spawn(SpawnModel::Request& req, SpawnModel::Response& res);
  bool remove(DeleteModel::Request& req, DeleteModel::Response& res);
  bool setPose(SetModelPose::Request& req, SetModelPose::Response& res);
  bool list(ListModels::Request& req, ListModels::Response& res);

 private:
  // Composes the parts into a new scene and swaps it in; "" or what went wrong (the scene is then
  // left as it was). Under mutex_.
  std::string publish(const char* what, const std::string& name);
  // The part named name, or end() (and, if missing is given, a message saying so).
  std::vector<ScenePart>::iterator find(const std::string& name, std::string* missing = nullptr);

  const NodeParams params_;
  SharedScene* const scene_;
  std::mutex mutex_;  // parts_, walls_ and the order of the scenes swapped in
  std::vector<ScenePart> parts_;
  std::optional<ScenePart> walls_;
  ros::CallbackQueue queue_;
  std::vector<ros::ServiceServer> services_;
  std::unique_ptr<ros::AsyncSpinner> spinner_;
};

}  // namespace laser_raycast
