#include "walk/mesh_slices.h"

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

}  // namespace core
}  // namespace laser_raycast
