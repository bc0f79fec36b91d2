// Forward kinematics of a loaded URDF model: where each link is for given joint values. The node
// gets link poses from TF instead; the offline tools (cast_scan, bench) place links with this.
#pragma once

#include <Eigen/Geometry>
#include <map>
#include <string>

#include "laser_raycast/core/scene.h"
#include "laser_raycast/loader/scene_loader.h"

namespace laser_raycast {

// Pose of every link (names with the model's tf_prefix) in the world, with the root link at
// world_from_root and each joint at its value in joint_values (rad for revolute and continuous, m
// for prismatic; 0 if absent). Fixed, floating and planar joints do not move. Joint names are the
// URDF's.
std::map<std::string, Eigen::Isometry3d> forwardKinematics(
    const LoadedModel& model, const Eigen::Isometry3d& world_from_root,
    const std::map<std::string, double>& joint_values);

// Frame poses for a scene from link poses (scene frames are named after links). Frames without a
// pose in link_poses are invalid.
core::FramePoses framePosesFromLinks(const core::Scene& scene,
                                     const std::map<std::string, Eigen::Isometry3d>& link_poses);

// The URDF rotation for roll, pitch, yaw (rad): fixed axes X, then Y, then Z, i.e. Rz(yaw)
// Ry(pitch) Rx(roll).
Eigen::Isometry3d poseFromXyzRpy(double x, double y, double z, double roll, double pitch,
                                 double yaw);

}  // namespace laser_raycast
