// Caster::castBeams for a beam list that lies on grids (beams/beam_list_grid.h): a calibrated
// spinning lidar's beams, each cast exactly as its own ray, with the grid's walks finding what
// each may hit.
//
// Each part of the grid is cast as a bundle (BeamSet::Bundle) whose one sub-ray at a grid beam is
// the list's beam there, from a reference pose at the middle of the beams' origins: each column of
// the part leaves from its own origin (a ColumnMotion of translations, as a rotating sweep's block
// leaves from its columns' poses), and the windows are widened by that shift and by the part's
// turn. The walks test the sub-ray wherever they would test its grid beam, so a beam's range is
// what its own ray gives; only the work of finding its triangles is shared.
#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

#include "caster/caster_state.h"
#include "walk/frame_walk.h"

namespace laser_raycast {
namespace core {

const BeamListGrid* CasterState::gridOf(const BeamList& beams) {
  const std::vector<Eigen::Vector3d>& origins = beams.origins;
  if (!fitted || fitted->directions != beams.directions || fitted->origins != origins ||
      fitted->lines != beams.lines) {
    fitted.reset();
    beams.validate();
    fitted = FittedList{beams.directions, origins, beams.lines, fitBeamGrid(beams)};
  }
  return fitted->grid ? &*fitted->grid : nullptr;
}

void CasterState::castBeamGrids(const Scene& scene, const FramePoses& poses,
                                const Eigen::Isometry3d& world_from_sensor, const BeamList& list,
                                const BeamListGrid& grid, const CastConfig& config,
                                ScanResult* result) {
  const int bodies = static_cast<int>(scene.bodies().size());
  const Eigen::Isometry3d world_from_ref = world_from_sensor * Eigen::Translation3d(grid.center);
  std::vector<char> cast_any(bodies, 0);
  ScanResult& culling = grid_culling;
  ScanResult& own = grid_own;
  for (const BeamListGrid::Part& part : grid.parts) {
    const ReuseKey key = relativeInputs(scene, poses, world_from_ref, part.culling, config);
    result->stats.bodies_skipped = 0;
    placeGroups(scene, key, part.culling, &placed, &result->stats.bodies_skipped);
    std::vector<Eigen::Isometry3d> ref_from_column;
    ref_from_column.reserve(part.column_origin.size());
    for (const Eigen::Vector3d& o : part.column_origin) {
      ref_from_column.emplace_back(Eigen::Translation3d(o));
    }
    const ColumnMotion motion(0, std::move(ref_from_column), steepestElevation(part.culling),
                              part.turn);
    resetResult(part.culling.size(), bodies, true, false, &culling);
    resetResult(part.culling.size(), bodies, true, config.compute_incidence, &own);
    BeamSet::Bundle sub_rays;
    sub_rays.directions.push_back(&part.directions);
    sub_rays.results.push_back(&own);
    castOnThreads(
        scene, part.culling, config, &culling,
        [&](const BeamRect& within) {
          for (const PlacedGroup& p : placed) {
            walkFrame(beams, scene, *p.group, *p.sensor_from_frame, config, within, &cast,
                      &motion);
          }
        },
        &sub_rays);
    for (int b = 0; b < bodies; ++b) cast_any[b] |= cast[b].load(std::memory_order_relaxed);
    for (std::size_t k = 0; k < part.beam.size(); ++k) {
      const int i = part.beam[k];
      result->range[i] = own.range[k];
      result->body[i] = own.body[k];
      result->triangle[i] = own.triangle[k];
      if (config.compute_incidence && own.body[k] >= 0) {
        result->normal[i] = own.normal[k];
        result->cos_incidence[i] = std::min(1.0, std::abs(list.directions[i].dot(own.normal[k])));
      }
    }
  }
  int cast_count = 0;
  for (char c : cast_any) cast_count += c;
  result->stats.bodies_culled = bodies - result->stats.bodies_skipped - cast_count;
}

}  // namespace core
}  // namespace laser_raycast
