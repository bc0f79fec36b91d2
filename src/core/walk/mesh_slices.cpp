#include "walk/mesh_slices.h"

#include <algorithm>

namespace laser_raycast {
namespace core {

MeshSlices::MeshSlices(BeamSet& beams, const Mesh& mesh, const PlacedBody& active,
                       const CastConfig& config)
    : beams_(beams), wide_(mesh.wideBvh()), ids_(mesh.bvh().triangleIds()), body_(active.index) {
  // Cut in the frame's plane coordinates when the walk gives them (as a kept slice is).
  if (active.plane) {
    slicer_.emplace(mesh, *active.plane, active.frame_from_body, active.sensor_from_body,
                    beams.grid().pattern(), config.tmin, config.tmax, config.cull_backfaces);
  } else {
    slicer_.emplace(mesh, active.sensor_from_body, beams.grid().pattern(), config.tmin,
                    config.tmax, config.cull_backfaces);
  }
}

void MeshSlices::sliceLeaf(WideBvh::Ref leaf, const BeamRect& rect, double near) {
  // No back face is skipped: a segment costs less than deciding (BodyTriangles hides none for a
  // walk that slices).
  for (std::uint32_t slot = leaf.index; slot < leaf.index + leaf.count; ++slot) {
    slicer_->sliceSlot(
        slot, rect.col_lo, rect.col_hi,
        [&](int col, double t) {
          beams_.keepNearestHit(0, col, t, body_, static_cast<int>(ids_[slot]),
                                [&] { return slicer_->sensorNormal(slot); });
        },
        [&](int col, double segment_near) {
          return beams_.range(0, col) >= std::max(near, segment_near);
        });
  }
}

void MeshSlices::sliceSubtree(WideBvh::Ref ref, const BeamRect& rect, double near,
                              const ViewBasis& basis) {
  WideBvh::Ref stack[64 * (WideBvh::kWidth - 1) + 1];
  int top = 0;
  stack[top++] = ref;
  while (top > 0) {
    const WideBvh::Ref r = stack[--top];
    if (r.isLeaf()) {
      sliceLeaf(r, rect, near);
      continue;
    }
    const WideBvh::Node& node = wide_.nodes()[r.index];
    const int mask = planeMask(node, basis);
    for (int k = 0; k < WideBvh::kWidth; ++k) {
      if (!(mask & (1 << k))) continue;
      stack[top++] = node.child(k);
      if (node.child(k).isLeaf()) prefetchLeaf(node.child(k));
    }
  }
}

}  // namespace core
}  // namespace laser_raycast
