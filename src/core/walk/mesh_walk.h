// One body against the open beams of a window of the scan, front to back.
//
// A mesh is walked through its wide BVH from the root: each node's box gives the beams that can
// reach it (its view) and its nearest distance; a node is skipped when none of its beams is open at
// that distance (the occlusion tiles), and children are visited nearest first. Where few beams
// remain, or at a leaf, each open beam is traced through the node's subtree with the exact
// triangle test.
//
// Under a planar fan (with its fast path) every triangle is tested as its cut by the scan plane, a
// 2D segment (slicer.h), whether a beam is traced to it or meets it at a leaf; otherwise by the
// exact 3D test, or first rasterised against the leaf's beams (column_raster.h). One test per cast:
// neighbouring triangles share bitwise-equal segment ends or moved vertices however they are
// reached, so the walk's choices change the speed only (docs/design.md §5).
#pragma once

#include "beams/beam_set.h"
#include "laser_raycast/core/cast_config.h"
#include "beams/placed_body.h"
#include "laser_raycast/core/scene.h"

namespace laser_raycast {
namespace core {

// Casts the open beams of `within` (a rect of beams the body's bounding sphere can reach) against
// the mesh body active.index of scene (a primitive body is cast by castPrimitive, primitive_cast.h).
void walkMesh(BeamSet& beams, const Scene& scene, const PlacedBody& active,
              const CastConfig& config, const BeamRect& within);

}  // namespace core
}  // namespace laser_raycast
