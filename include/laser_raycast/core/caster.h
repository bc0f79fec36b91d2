// Casts a scan pattern from a sensor pose against a scene: per beam, the nearest hit's distance,
// body and triangle. All geometry is done relative to the sensor (docs/design.md §4.1).
#pragma once

#include <Eigen/Geometry>
#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include "laser_raycast/core/beam_window.h"
#include "laser_raycast/core/pose_samples.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/scene.h"
#include "laser_raycast/core/scene_index.h"
#include "laser_raycast/core/triangle.h"

namespace laser_raycast {
namespace core {

struct CastConfig {
  TriangleMethod method = TriangleMethod::kWatertight;  // triangle test for meshes
  bool cull_backfaces = false;  // one-sided triangles: a beam reaching a back face passes through
  double tmin = 0.0;            // m, nearest accepted hit (>= 0)
  double tmax = 30.0;  // m, farthest accepted hit (> tmin); bodies wholly beyond are skipped
  bool planar_fast_path =
      true;  // planar fans: slice meshes in the scan plane instead of tracing beams
  bool raster_fast_path = true;  // other patterns: rasterise nearby meshes instead of tracing beams
  bool compute_incidence = false;  // fill ScanResult::cos_incidence
  // Threads a cast uses (the calling one included); 0: every core. The beams are split between
  // them; the result is the same, bit for bit, for any number.
  int threads = 1;
  static constexpr int kMaxThreads = 1024;  // more is a mistake, not a machine
  // Skip bodies and BVH nodes that every beam able to reach them has already passed (a nearer
  // hit). Never changes the result; off only to test that.
  bool occlusion_culling = true;
  // Planar fans: keep each mesh's slice by a scan plane met again (a sensor moving in its own
  // plane, as on a floor) and cast later scans through it (plane_slice.h). Never changes the
  // result; off to measure a cast whose plane is new every scan, or to test that.
  bool plane_cache = true;

  // Throws std::invalid_argument naming the field and its value.
  void validate() const;
  bool operator==(const CastConfig& o) const;
};

struct CastStats {
  int bodies = 0;          // bodies in the scene
  int bodies_skipped = 0;  // frame pose unknown this scan
  // Bodies not cast against: beyond the range, outside the pattern's windows, off the scan plane
  // (planar fans), or hidden behind nearer hits.
  int bodies_culled = 0;
  bool reused = false;  // nothing moved relative to the sensor: the previous geometry was returned
  // Planar fans: frames cast through a kept slice of their bodies by the scan plane
  // (plane_slice.h).
  int kept_slices = 0;
};

struct ScanResult {
  std::vector<double> range;  // m; +inf: no hit in [tmin, tmax]; NaN: the beam could not be cast
  std::vector<int> body;      // index of the body hit, -1 for none
  std::vector<int> triangle;  // the triangle hit on a mesh body, -1 for a primitive or no hit
  // Filled only with CastConfig::compute_incidence (else empty):
  std::vector<Eigen::Vector3d> normal;  // unit normal at the hit, sensor frame (zero if no hit):
                                        // a mesh triangle's front normal, a primitive's outward one
  std::vector<double> cos_incidence;    // |cos| of the beam's angle to that normal (0 if no hit)
  CastStats stats;
};

class BeamSet;
struct PlaneFrame;
class PlaneSliceCache;
class ThreadPool;

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

  // Drops the remembered inputs, so that the next cast() computes even if nothing moved (timing).
  // Kept slices of meshes by scan planes (CastConfig::plane_cache) stay: like the meshes' BVHs,
  // they hold geometry, not results.
  void forget() { previous_.reset(); }

  // A body prepared for this scan: its pose relative to the sensor and its culling data.
  struct ActiveBody {
    int index;
    Eigen::Isometry3d sensor_from_body;
    Eigen::Matrix3d body_from_sensor_rot;  // rotates sensor-frame directions into the body frame
    Eigen::Vector3d sensor_in_body;        // the sensor origin in the body frame
    Eigen::Vector3d center;                // bounding sphere centre, sensor frame
    double radius;
    View view;  // how the body's box looks from the sensor: nearest distance, windows
    // Planar fans: the scan plane in the body's frame's coordinates (fan_slicer.h), and where the
    // body is in that frame: a mesh is cut there, as a kept slice of the frame is.
    const PlaneFrame* plane = nullptr;
    Eigen::Isometry3d frame_from_body = Eigen::Isometry3d::Identity();
  };

 private:
  // What a result was computed from: if all of it is equal, the result is too.
  struct ReuseKey {
    std::uint64_t scene_version = 0;
    CastConfig config;
    double angle_min = 0, angle_increment = 0;
    int azimuths = 0;
    std::vector<double> elevations;
    std::vector<Eigen::Isometry3d> sensor_from_frame;  // meaningful where valid
    std::vector<char> valid;
    bool operator==(const ReuseKey& o) const;
  };

  // The stages of cast(), in order.
  ReuseKey relativeInputs(const Scene& scene, const FramePoses& poses,
                          const Eigen::Isometry3d& world_from_sensor, const ScanPattern& pattern,
                          const CastConfig& config) const;
  void resetResult(int beams, int bodies, bool sensor_ok, bool with_normals);
  // The scene's frames with bodies this scan, nearest first, each with its pose in the sensor
  // frame; the bodies on unknown frames are counted as skipped.
  struct PlacedGroup {
    const SceneIndex::Group* group;
    const Eigen::Isometry3d* sensor_from_frame;
    double near;
  };
  void placeGroups(const Scene& scene, const ReuseKey& key, const ScanPattern& pattern);
  void castBodies(const Scene& scene, const ScanPattern& pattern, const CastConfig& config);
  void computeIncidence(const ScanPattern& pattern);

  ScanResult result_;
  std::unique_ptr<SceneIndex> index_;  // the scene's body trees, rebuilt when the scene changes
  std::vector<PlacedGroup> placed_;
  std::vector<std::atomic<char>> cast_;      // per body: cast against this scan (for the stats)
  std::unique_ptr<BeamSet> beams_;           // the walk's per-scan state, kept to reuse its memory
  std::unique_ptr<ThreadPool> pool_;         // for CastConfig::threads > 1, kept between casts
  std::unique_ptr<PlaneSliceCache> planes_;  // CastConfig::plane_cache, kept between casts
  std::optional<ReuseKey> previous_;         // the inputs of result_, if it is complete
};

}  // namespace core
}  // namespace laser_raycast
