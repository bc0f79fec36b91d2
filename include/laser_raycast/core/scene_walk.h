// The caster's top level: the bodies of one frame, front to back through their tree
// (scene_index.h), each node with the beams its window holds, skipping nodes off the scan plane,
// beyond the range or hidden behind nearer hits; each body reached is cast with the beams of its
// own window (body_traversal.h).
#pragma once

#include <atomic>
#include <vector>

#include "laser_raycast/core/beam_set.h"
#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/scene_index.h"

namespace laser_raycast {
namespace core {

// A body placed for a scan, in steps so that a walk can cull by the cheap one first: its pose
// relative to the sensor and its bounding sphere there; then the sensor in the body's frame (what
// the exact tests need, placeSensorInBody); then how its box looks from the sensor (with elevation
// windows if `elevations`; viewActiveBody does both).
Caster::ActiveBody activeBody(const Scene& scene, int index,
                              const Eigen::Isometry3d& sensor_from_frame);
void placeSensorInBody(Caster::ActiveBody* a);
void viewActiveBody(const Scene& scene, double angle_min, bool elevations, Caster::ActiveBody* a);

// Casts the open beams of `within` against the bodies of group, placed by sensor_from_frame. Sets
// cast[b] for each body b it casts against (several walks may set them at once).
void castGroup(BeamSet& beams, const Scene& scene, const SceneIndex::Group& group,
               const Eigen::Isometry3d& sensor_from_frame, const CastConfig& config,
               const BeamRect& within, std::vector<std::atomic<char>>* cast);

}  // namespace core
}  // namespace laser_raycast
