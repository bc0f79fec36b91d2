// A planar fan's mesh walk (mesh_walk.cpp, from one pose): the triangles of the leaves it reaches
// cut by the scan plane into 2D segments (slice/slicer.h) and tested with the fan's beams, leaf by
// leaf or, for a small subtree seen across many beams, its whole subtree at once.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <optional>
#include <vector>

#include "accel/wide_bvh.h"
#include "beams/beam_set.h"
#include "beams/node_views.h"
#include "beams/placed_body.h"
#include "laser_raycast/core/cast_config.h"
#include "laser_raycast/core/mesh.h"
#include "slice/slicer.h"

namespace laser_raycast {
namespace core {

class MeshSlices {
 public:
  // The mesh of body active.index, placed as active has it; beams: the fan's (its one row).
  MeshSlices(BeamSet& beams, const Mesh& mesh, const PlacedBody& active, const CastConfig& config);

  // True if a subtree of `triangles` triangles whose window holds `beams` beams is sliced whole
  // (sliceSubtree), without windows or occlusion tests on the way: for a small subtree seen across
  // many beams they cost more than they save.
  static bool slicedWhole(std::uint32_t triangles, long long beams) {
    return triangles <= kPlainSliceTriangles && beams >= kPlainSliceBeamsPerTriangle * triangles;
  }

  // Asks for a leaf's triangles now, to be in the cache when it is sliced (on a tilted fan in the
  // warehouse, loading a triangle's vertices took 40% of its cut).
  void prefetchLeaf(WideBvh::Ref leaf) const {
    wide_.binary().triangleVertices().prefetch(leaf.index, leaf.count);
  }
  // The leaf's triangles against the beams of rect's columns still open beyond near (no point of
  // the leaf is nearer), each hit offered to the beam set. Flattened: compiled apart from the walk
  // that held it before, the cut's column search or the occlusion tiles' update was no longer
  // inlined into its loop (bench's tilted fan on tb3: 5.7-8.5% more instructions; flattened, 1%
  // fewer than in the walk).
  __attribute__((flatten)) void sliceLeaf(WideBvh::Ref leaf, const BeamRect& rect, double near) {
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
  // The same for every leaf below ref that meets the scan plane (basis: the walk's).
  void sliceSubtree(WideBvh::Ref ref, const BeamRect& rect, double near, const ViewBasis& basis) {
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

  // The triangle in `slot` against the one beam in column col (a traced beam's test).
  bool sliceBeam(std::uint32_t slot, int col, double* t) const {
    return slicer_->sliceBeam(slot, col, t);
  }
  Eigen::Vector3d sensorNormal(std::uint32_t slot) const { return slicer_->sensorNormal(slot); }

 private:
  // The values come from the benchmark's scenes; they change only the speed.
  static constexpr std::uint32_t kPlainSliceTriangles = 64;
  static constexpr double kPlainSliceBeamsPerTriangle = 0.5;

  BeamSet& beams_;
  const WideBvh& wide_;
  const std::vector<std::uint32_t>& ids_;
  const int body_;
  std::optional<Slicer> slicer_;  // made in the constructor, in one of two ways
};

}  // namespace core
}  // namespace laser_raycast
