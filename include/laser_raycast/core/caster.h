// Casts a scan pattern from a sensor pose against a scene: per beam, the nearest hit's distance,
// body and triangle. All geometry is done relative to the sensor (docs/design.md §4.1).
//
// The facade of the core: what a cast needs (CastConfig, ScanResult, the scene and the pattern) is
// declared below it, and the walks that do the work (src/core/walk/) never include it.
#pragma once

#include <Eigen/Geometry>
#include <memory>

#include "laser_raycast/core/beam_list.h"
#include "laser_raycast/core/cast_config.h"
#include "laser_raycast/core/pose_samples.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/scan_result.h"
#include "laser_raycast/core/scene.h"
#include "laser_raycast/core/sub_ray_bundle.h"

namespace laser_raycast {
namespace core {

struct CasterState;  // src/core/caster/caster_state.h

class Caster {
 public:
  Caster();
  ~Caster();
  Caster(Caster&&) noexcept;
  Caster& operator=(Caster&&) noexcept;

  // Casts pattern from world_from_sensor (both it and poses in the same common frame). Bodies whose
  // frame is invalid are skipped. If world_from_sensor is not a finite rigid transform, every beam
  // is NaN. If scene, pattern, config and every frame's pose relative to the sensor are unchanged
  // since the previous call, the previous result is returned without casting (stats.reused).
  const ScanResult& cast(const Scene& scene, const FramePoses& poses,
                         const Eigen::Isometry3d& world_from_sensor, const ScanPattern& pattern,
                         const CastConfig& config);

  // A rotating scan: the beams of azimuth index c (all rings) are taken at time c * time_increment
  // (s after the first beam, >= 0), each from the sensor and frame poses at that time, interpolated
  // in samples (PoseSamples). This is the motion distortion of a real scan. Never reused. Throws
  // std::invalid_argument for bad samples or a bad time_increment.
  const ScanResult& castSweep(const Scene& scene, const PoseSamples& samples,
                              const ScanPattern& pattern, const CastConfig& config,
                              double time_increment);

  // Beams off any grid (beam_list.h), each cast as its own ray from its origin with the exact tests
  // the grid's walks use: every beam from world_from_sensor. A list that lies on grids (columns of
  // every laser line from one origin, each line's azimuth advancing by one step: a calibrated
  // Velodyne's or Ouster's, src/core/beams/beam_list_grid.h) is cast through the grid's walks,
  // others one ray at a time through the scene's trees (src/core/caster/caster_beams.cpp). Result
  // i is beam i; the same for any thread count. Never reused.
  const ScanResult& castBeams(const Scene& scene, const FramePoses& poses,
                              const Eigen::Isometry3d& world_from_sensor, const BeamList& beams,
                              const CastConfig& config);
  // The same with each beam from the sensor and frame poses at its own time (beams.times, s from
  // the first sample's time), interpolated in samples as castSweep does (a list on grids is swept
  // in castSweep's blocks of columns, each beam still from the poses at its own time). Throws
  // std::invalid_argument for bad samples or beams.
  const ScanResult& castBeamsSweep(const Scene& scene, const PoseSamples& samples,
                                   const BeamList& beams, const CastConfig& config);
  // The same two for a list the caller shares and does not change while it does (a calibrated
  // head's turn, cast scan after scan): passed again, it is known by its pointer rather than
  // compared beam by beam with the one fitted last. Throws std::invalid_argument for a null list.
  const ScanResult& castBeams(const Scene& scene, const FramePoses& poses,
                              const Eigen::Isometry3d& world_from_sensor,
                              const std::shared_ptr<const BeamList>& beams,
                              const CastConfig& config);
  const ScanResult& castBeamsSweep(const Scene& scene, const PoseSamples& samples,
                                   const std::shared_ptr<const BeamList>& beams,
                                   const CastConfig& config);

  // A bundle: the 3D patterns `patterns`, all of the same rings and azimuths with sub-ray k of each
  // beam at patterns[k]'s (row, column) (a divergent beam's footprint: the same pattern shifted a
  // little in azimuth and elevation), cast from one pose in one walk of the scene: culled as
  // patterns[0] with windows widened by the farthest a sub-ray is from it, each sub-ray tested
  // exactly as a cast of its pattern tests it. Result k is cast(.., patterns[k], ..)'s (ranges,
  // bodies, triangles and, with compute_incidence, normals and incidence; one stats for all). Never
  // reused. Throws std::invalid_argument for patterns that are empty, planar or of other sizes or
  // ring orders.
  const std::vector<ScanResult>& castBundle(const Scene& scene, const FramePoses& poses,
                                            const Eigen::Isometry3d& world_from_sensor,
                                            const std::vector<ScanPattern>& patterns,
                                            const CastConfig& config);
  // The same cast for a bundle the caller keeps and casts scan after scan (castReturns does), its
  // results in one ScanResult beam by beam, as the walks keep them: sub-ray k of beam i at
  // i * bundle->subRays() + k (ranges, bodies, triangles and, with compute_incidence, normals and
  // incidence along bundle->directions()). Nothing is copied between the patterns' order and the
  // walks', and what the walks derive from the directions (their float copy for the pre-test, the
  // sub-rays' shears for the watertight test) is made once for as long as the same bundle is
  // passed (the caster holds the last bundle it was passed until it is passed another). Never
  // reused. Throws std::invalid_argument for a null bundle.
  const ScanResult& castBundle(const Scene& scene, const FramePoses& poses,
                               const Eigen::Isometry3d& world_from_sensor,
                               const std::shared_ptr<const SubRayBundle>& bundle,
                               const CastConfig& config);

  // Drops the remembered inputs, so that the next cast() computes even if nothing moved (timing).
  // Kept slices of meshes by scan planes (CastConfig::keep_slices) stay: like the meshes' BVHs,
  // they hold geometry, not results.
  void forget();

 private:
  ScanResult result_;
  // The scene's index, the walk's buffers, the threads, the kept slices.
  std::unique_ptr<CasterState> state_;
};

}  // namespace core
}  // namespace laser_raycast
