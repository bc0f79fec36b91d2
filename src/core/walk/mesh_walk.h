// One body against the open beams of a window of the scan, front to back.
//
// A mesh is walked through its wide BVH from the root: each node's box gives the beams that can
// reach it (its view) and its nearest distance; a node is skipped when none of its beams is open at
// that distance (the occlusion tiles), and children are visited nearest first. Where few beams
// remain, or at a leaf, each open beam is traced through the node's subtree with the exact
// triangle test.
//
// Under a planar fan a mesh's triangles can instead be sliced by the scan plane (slicer.h). Per
// connected component of the mesh, and the same for every beam and every thread, the cheaper of the
// two is chosen: a component's triangles share edges only with each other, so one component never
// mixes the two tests, and both are watertight on their own.
#pragma once

#include "beams/beam_set.h"
#include "laser_raycast/core/cast_config.h"
#include "beams/placed_body.h"
#include "laser_raycast/core/scene.h"

namespace laser_raycast {
namespace core {

// Casts the open beams of `within` (a rect of beams the body's bounding sphere can reach) against
// the body active.index of scene.
void walkMesh(BeamSet& beams, const Scene& scene, const PlacedBody& active,
              const CastConfig& config, const BeamRect& within);

}  // namespace core
}  // namespace laser_raycast
