// A frame's bodies under a planar fan, through a kept slice of them (kept_slice.h): the slice's
// tree walked front to back, each node with the beams its window holds, skipping nodes beyond the
// range or hidden behind nearer hits, tracing the beams of small windows one at a time; each
// segment tested as the fan slicer tests it, each primitive analytically.
#pragma once

#include <atomic>
#include <vector>

#include "beams/beam_set.h"
#include "beams/column_motion.h"
#include "laser_raycast/core/cast_config.h"
#include "slice/slicer.h"
#include "slice/kept_slice.h"

namespace laser_raycast {
namespace core {

// Casts the open beams of `within` against the bodies of a frame through slice, their slice by
// plane (the plane of sensor_from_frame). Sets cast[b] for each body b it casts against. With a
// motion (a block of a rotating sweep, `within` inside its columns, every column in the reference's
// plane: ColumnMotion::inPlane()), sensor_from_frame and plane are the block's reference, and each
// column's beams are tested from the column's own pose, the segments mapped to its sensor x, y.
void walkSlice(BeamSet& beams, const Scene& scene, const KeptSlice& slice, const ScanPlane& plane,
               const Eigen::Isometry3d& sensor_from_frame, const CastConfig& config,
               const BeamRect& within, std::vector<std::atomic<char>>* cast,
               const ColumnMotion* motion = nullptr);

}  // namespace core
}  // namespace laser_raycast
