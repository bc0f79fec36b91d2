// The caster's top level: the bodies of one frame, front to back through their tree
// (scene_index.h), each node with the beams its window holds, skipping nodes off the scan plane,
// beyond the range or hidden behind nearer hits; each body reached is cast with the beams of its
// own window (mesh_walk.h).
#pragma once

#include <atomic>
#include <vector>

#include "beams/beam_set.h"
#include "beams/column_motion.h"
#include "laser_raycast/core/cast_config.h"
#include "scene/scene_index.h"

namespace laser_raycast {
namespace core {

// Casts the open beams of `within` against the bodies of group, placed by sensor_from_frame. Sets
// cast[b] for each body b it casts against (several walks may set them at once). With a motion
// (a block of a rotating sweep, `within` inside its columns), sensor_from_frame is the block's
// reference pose and each column's beams leave from the column's own pose.
void walkFrame(BeamSet& beams, const Scene& scene, const SceneIndex::Group& group,
               const Eigen::Isometry3d& sensor_from_frame, const CastConfig& config,
               const BeamRect& within, std::vector<std::atomic<char>>* cast,
               const ColumnMotion* motion = nullptr);

}  // namespace core
}  // namespace laser_raycast
