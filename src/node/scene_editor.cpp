#include "scene_editor.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

namespace laser_raycast {

bool poseFromMsg(const geometry_msgs::Pose& msg, Eigen::Isometry3d* pose, std::string* error) {
  const auto& p = msg.position;
  const auto& q = msg.orientation;
  const Eigen::Vector4d coeffs(q.x, q.y, q.z, q.w);
  if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && coeffs.allFinite())) {
    *error = "the pose has a value that is not finite";
    return false;
  }
  const double norm = coeffs.norm();
  const Eigen::Quaterniond rotation =
      norm == 0 ? Eigen::Quaterniond::Identity() : Eigen::Quaterniond(coeffs / norm);
  *pose = Eigen::Translation3d(p.x, p.y, p.z) * rotation;
  return true;
}

SceneEditor::SceneEditor(const ros::NodeHandle& pnh, const NodeParams& params,
                         std::vector<ScenePart> parts, SharedScene* scene)
    : params_(params), scene_(scene), parts_(std::move(parts)) {
  ros::NodeHandle nh(pnh);
  nh.setCallbackQueue(&queue_);
  services_.push_back(nh.advertiseService("spawn_model", &SceneEditor::spawn, this));
  services_.push_back(nh.advertiseService("delete_model", &SceneEditor::remove, this));
  services_.push_back(nh.advertiseService("set_model_pose", &SceneEditor::setPose, this));
  services_.push_back(nh.advertiseService("list_models", &SceneEditor::list, this));
  spinner_ = std::make_unique<ros::AsyncSpinner>(1, &queue_);
  spinner_->start();
}

SceneEditor::~SceneEditor() {
  for (ros::ServiceServer& s : services_) s.shutdown();
  spinner_->stop();
}

std::vector<ScenePart>::iterator SceneEditor::find(const std::string& name, std::string* missing) {
  const auto it = std::find_if(parts_.begin(), parts_.end(),
                               [&](const ScenePart& p) { return p.name == name; });
  if (it == parts_.end() && missing) *missing = "no model named '" + name + "' (see ~list_models)";
  return it;
}

std::string SceneEditor::publish(const char* what, const std::string& name) {
  const auto start = std::chrono::steady_clock::now();
  auto next = std::make_shared<CastScene>();
  try {
    composeScene(parts_, params_.fixed_frame, &next->scene);
    if (walls_) composeScene({*walls_}, params_.fixed_frame, &next->scene);
  } catch (const std::exception& e) {
    return e.what();
  }
  next->reflectivity = labelReflectivity(params_, next->scene);
  next->reflectivity_fixed = labelReflectivityFixed(params_, next->scene);
  const std::size_t bodies = next->scene.bodies().size();
  scene_->set(std::move(next));
  if (what) {
    ROS_INFO("scene: %s '%s'; %zu bodies, composed in %.6f s", what, name.c_str(), bodies,
             std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  return "";
}

void SceneEditor::setMapWalls(core::Scene walls) {
  std::lock_guard<std::mutex> lock(mutex_);
  walls_.emplace();
  walls_->name = "map topics";
  walls_->scene = std::move(walls);
  const std::string error = publish(nullptr, "");
  if (!error.empty()) ROS_ERROR_STREAM("the map topics' walls are left out: " << error);
}

bool SceneEditor::spawn(SpawnModel::Request& req, SpawnModel::Response& res) {
  res.success = false;
  if (req.urdf.empty() == req.file.empty()) {
    res.message = "give exactly one of 'urdf' (the URDF's text) and 'file' (a path or URI)";
    return true;
  }
  if (!req.tf_prefix.empty() && req.tf_prefix[0] == '/') {
    res.message = "tf_prefix '" + req.tf_prefix + "': tf2 frame ids must not start with '/'";
    return true;
  }
  ScenePart part;
  part.placed = !req.use_tf;
  if (part.placed && !poseFromMsg(req.pose, &part.root_pose, &res.message)) return true;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!req.name.empty() && find(req.name) != parts_.end()) {
      res.message = "a model named '" + req.name + "' is already in the scene";
      return true;
    }
  }
  // Loaded without the lock: the other services (and the map topics) go on meanwhile.
  const std::string source =
      req.file.empty() ? "URDF string of spawn_model '" + req.name + "'" : "file " + req.file;
  const std::string error = loadUrdfPart(params_, req.urdf, req.file, req.tf_prefix, source, &part);
  if (!error.empty()) {
    res.message = "not spawned: " + error;
    ROS_WARN_STREAM("spawn_model: " << res.message);
    return true;
  }
  if (!req.name.empty()) part.name = req.name;
  part.source = "spawned, " + (req.file.empty() ? std::string("URDF string") : req.file) +
                (part.placed ? ", placed" : ", poses from TF");
  std::lock_guard<std::mutex> lock(mutex_);
  if (part.name.empty() || find(part.name) != parts_.end()) {
    res.message = part.name.empty() ? "the model has no name: give one"
                                    : "a model named '" + part.name + "' is already in the scene";
    return true;
  }
  const std::string name = part.name;
  const std::size_t bodies = part.scene.bodies().size();
  parts_.push_back(std::move(part));
  const std::string failed = publish("spawned", name);
  if (!failed.empty()) {
    parts_.pop_back();
    res.message = "not spawned: " + failed;
    return true;
  }
  res.success = true;
  res.message = "spawned '" + name + "' (" + std::to_string(bodies) + " bodies)";
  return true;
}

bool SceneEditor::remove(DeleteModel::Request& req, DeleteModel::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  res.success = false;
  const auto it = find(req.name, &res.message);
  if (it == parts_.end()) return true;
  ScenePart removed = std::move(*it);
  const auto at = parts_.erase(it);
  const std::string failed = publish("deleted", req.name);
  if (!failed.empty()) {
    parts_.insert(at, std::move(removed));
    res.message = "not deleted: " + failed;
    return true;
  }
  res.success = true;
  res.message = "deleted '" + req.name + "'";
  return true;
}

bool SceneEditor::setPose(SetModelPose::Request& req, SetModelPose::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  res.success = false;
  const auto it = find(req.name, &res.message);
  if (it == parts_.end()) return true;
  if (!it->placed) {
    res.message = "model '" + req.name +
                  "' takes its link poses from TF (a model of ~models, or spawned with use_tf): "
                  "move it through TF";
    return true;
  }
  Eigen::Isometry3d pose;
  if (!poseFromMsg(req.pose, &pose, &res.message)) return true;
  const Eigen::Isometry3d previous = it->root_pose;
  it->root_pose = pose;
  const std::string failed = publish("moved", req.name);
  if (!failed.empty()) {
    it->root_pose = previous;
    res.message = "not moved: " + failed;
    return true;
  }
  res.success = true;
  res.message = "moved '" + req.name + "'";
  return true;
}

bool SceneEditor::list(ListModels::Request&, ListModels::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const ScenePart& part : parts_) {
    res.names.push_back(part.name);
    res.sources.push_back(part.source);
  }
  return true;
}

}  // namespace laser_raycast
