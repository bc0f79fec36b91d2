#include "laser_raycast/loader/kinematics.h"

#include <vector>

namespace laser_raycast {

std::map<std::string, Eigen::Isometry3d> forwardKinematics(
    const LoadedModel& model, const Eigen::Isometry3d& world_from_root,
    const std::map<std::string, double>& joint_values) {
  std::multimap<std::string, const ModelJoint*> children;  // parent link -> joints
  for (const ModelJoint& joint : model.joints) children.emplace(joint.parent_link, &joint);

  std::map<std::string, Eigen::Isometry3d> poses;
  poses[model.root_link] = world_from_root;
  std::vector<std::string> todo{model.root_link};
  while (!todo.empty()) {
    const std::string parent = todo.back();
    todo.pop_back();
    const Eigen::Isometry3d world_from_parent = poses[parent];
    const auto range = children.equal_range(parent);
    for (auto it = range.first; it != range.second; ++it) {
      const ModelJoint& joint = *it->second;
      const auto value_it = joint_values.find(joint.name);
      const double value = value_it == joint_values.end() ? 0.0 : value_it->second;
      Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
      if (joint.type == ModelJoint::Type::kRevolute ||
          joint.type == ModelJoint::Type::kContinuous) {
        motion.linear() = Eigen::AngleAxisd(value, joint.axis).toRotationMatrix();
      } else if (joint.type == ModelJoint::Type::kPrismatic) {
        motion.translation() = value * joint.axis;
      }
      poses[joint.child_link] = world_from_parent * joint.parent_from_joint * motion;
      todo.push_back(joint.child_link);
    }
  }
  return poses;
}

core::FramePoses framePosesFromLinks(const core::Scene& scene,
                                     const std::map<std::string, Eigen::Isometry3d>& link_poses) {
  core::FramePoses poses;
  core::resolveFramePoses(
      scene,
      [&](const std::string& frame, Eigen::Isometry3d& pose) {
        const auto it = link_poses.find(frame);
        if (it == link_poses.end()) return false;
        pose = it->second;
        return true;
      },
      &poses);
  return poses;
}

Eigen::Isometry3d poseFromXyzRpy(double x, double y, double z, double roll, double pitch,
                                 double yaw) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  pose.translation() = Eigen::Vector3d(x, y, z);
  return pose;
}

}  // namespace laser_raycast
