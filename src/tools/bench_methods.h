// The benchmark's rows: the workloads (beam patterns from several sensor poses), the rays each
// method gets, every method as one "pass" over a set of rays, and the timing of a pass.
#pragma once

#include <Eigen/Geometry>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bench_scenes.h"
#include "laser_raycast/core/beam_list.h"
#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/pose_samples.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/sub_ray_bundle.h"

namespace laser_raycast {
namespace bench {

// How the sensor moves in a workload.
enum class Motion {
  kStill,  // the scene's sensor poses, each cast again and again (the secondary rows)
  kPath,   // one scan per pose along a path the robot drives (bench_paths.h)
  kSweep,  // rotating scans along such a path, each column from the pose at its own time
};

struct Workload {
  std::string name;
  core::FanSpec fan;
  std::vector<double> elevations;  // rad; {0} for a planar fan
  // Still: sensor poses used (a prefix of the scene's list); moving: scans along the path.
  int full_poses, quick_poses;
  Motion motion = Motion::kStill;
  double scan_rate = 0;   // Hz, moving workloads: scans a second (a sweep lasts 1 / scan_rate s)
  double tilt_sigma = 0;  // rad, paths: each pose's roll and pitch ~ N(0, tilt_sigma)
  // Beams off any grid: every row of this scan pattern file (config/patterns/, core::PatternFile)
  // from each sensor pose, cast by Caster::castBeams; "" for the fan and elevations above.
  std::string pattern_file;
  // Beams off any grid: a VLP-16 with its published per-laser elevations, each laser at its own
  // azimuth and firing time (core::nominalVlp16(), one 0.1 s turn), by Caster::castBeams.
  bool calibrated_vlp16 = false;
  // Beams off any grid: an Ouster head's (this metadata file in config/ouster/, one 0.1 s turn of
  // its columns, each row at its own azimuth offset and from its beam origin), by
  // Caster::castBeams; "" for none.
  std::string ouster_metadata;
  // Divergent beams: each beam of the fan and elevations as this many sub-rays over a footprint of
  // this full angle (core::ReturnsConfig's pattern), all cast from each pose by
  // Caster::castBundle; 1: the ideal ray.
  int beam_samples = 1;
  double beam_divergence = 0;  // rad
};

// Still, from the scene's sensor poses: fan2d, 1081 beams over 270 degrees; rings3d, 64 rings
// from -15 to +15 degrees elevation x 1024 azimuths over the full turn. Moving, along a path from
// the scene's first sensor pose: fan_path and fan_path_tilted, the fan once per pose at 40 Hz
// (a UTM-30LX), level or tilted by N(0, 0.4 degrees); rings_path, a VLP-16 (16 rings from -15 to
// +15 degrees x 1800 azimuths) at 10 Hz; sweep_fan, a rotating 360-beam fan at 5 Hz (an LDS-01);
// sweep_rings, a rotating VLP-16 at 10 Hz. Still, beams off any grid: pattern_rosette, the
// 10000 points of config/patterns/rosette_4line.csv (a Livox-like rosette) from the scene's poses;
// vlp16_calibrated, a VLP-16's 1808 x 16 beams as a calibrated head fires them; os1_64_metadata,
// the 1024 x 64 beams of config/ouster/os1_64_nominal.json; sweeping along the path at 10 Hz,
// each beam from the pose at its own time: sweep_vlp16_calibrated and sweep_os1_64_metadata (by
// Caster::castBeamsSweep). Moving, divergent: rings_divergent,
// rings_path's VLP-16 with each beam 7 sub-rays over a 3 mrad footprint (the VLS-128 manual's
// horizontal divergence), 7 x 28,800 rays a scan.
const std::vector<Workload>& workloads();

// Every beam of a workload from each sensor pose, pose-major, as the triangle methods and peers get
// them: world-frame rays in double, and the same rounded to float. A method's distance is its t
// times the length of the direction it was given (scale, scale_f).
struct WorkloadRays {
  const Workload* workload = nullptr;
  std::unique_ptr<core::ScanPattern> pattern;  // the grid (a pattern file's workload: unused)
  core::BeamList beams;  // a pattern file's beams (Workload::pattern_file), else empty
  // Divergent beams (Workload::beam_samples > 1): the sub-ray patterns as castReturns keeps them,
  // whose directions, pattern after pattern, are also beams' (so that the peers cast each sub-ray
  // as a ray of its own).
  std::shared_ptr<const core::SubRayBundle> sub_rays;
  std::vector<SensorPose> poses;
  std::vector<Eigen::Isometry3d> sensors;  // the poses rounded to double (what the pipeline gets)
  std::vector<core::Ray> rays;
  std::vector<core::RayF> rays_f;
  std::vector<double> scale, scale_f;
  double tmax = 0;
  // Sweeps: each scan's pose samples and the time from one azimuth column to the next; poses and
  // sensors then hold one pose per column (scan-major), the one Caster::castSweep casts it from (a
  // beam list's: one per beam, at its time, as Caster::castBeamsSweep casts it).
  std::vector<core::PoseSamples> sweeps;
  double time_increment = 0;

  bool offGrid() const { return !beams.directions.empty(); }
  int beamCount() const { return offGrid() ? beams.size() : pattern->size(); }
  const std::vector<Eigen::Vector3d>& directions() const {
    return offGrid() ? beams.directions : pattern->directions();
  }
  // Where beam b leaves from, sensor frame (an Ouster head's beam origins; the grid's: 0).
  Eigen::Vector3d origin(int b) const {
    return offGrid() ? beams.origin(b) : Eigen::Vector3d::Zero();
  }
  bool planar() const { return !offGrid() && pattern->planar(); }
  std::size_t scans() const { return sweeps.empty() ? sensors.size() : sweeps.size(); }
  // The pose beam b (ring-major, as in the pattern; a list's in its order) of a scan is cast from.
  std::size_t poseIndex(std::size_t scan, int beam) const {
    if (sweeps.empty()) return scan;
    if (offGrid()) return scan * beams.size() + beam;
    return scan * pattern->azimuthCount() + beam % pattern->azimuthCount();
  }
};

// The rays of count poses or scans of the workload; the paths keep clear of the soup (soup_bvh).
WorkloadRays makeRays(const BenchScene& scene, const core::Bvh& soup_bvh, const Workload& workload,
                      int count, double tmax);

// One pass: casts the rays with the given indices, writing each one's distance (m, +inf for no
// hit) into dist[index].
using Pass =
    std::function<void(const WorkloadRays&, const std::vector<int>&, std::vector<double>*)>;

struct Method {
  std::string name;
  bool brute = false;         // too slow for every ray: gets a deterministic subset
  bool pipeline = false;      // measured against the pipeline reference
  std::size_t triangles = 0;  // triangles in the geometry it is given
  Pass pass;
  bool paired = false;  // timed in alternating rounds with the other paired rows (speed ratios)
  int threads = 1;      // threads the method casts with (the pipeline's CastConfig::threads)
  bool planar_only = false;  // a row only a planar fan differs in (not run on other workloads)
  bool moving = false;       // a row of the moving workloads too (the pipeline and Embree)
};

// Which methods to build (--method); a method not wanted costs nothing.
using MethodFilter = std::function<bool(const std::string& name)>;

// The soup's BVHs, in both precisions, and the scene (for the pipeline); built once per scene.
struct SceneGeometry {
  const BenchScene* scene = nullptr;
  core::Bvh bvh;
  core::BvhF bvh_f;
};

// The core's methods: every intersector in double and float, brute force and BVH, then the
// pipeline (Caster::cast, with Caster::forget() before every cast so nothing is reused); those
// wanted. With threads != 1 the pipeline has a second row cast with that many threads (0: every
// core); pipeline_new_plane casts planar fans without kept slices. The float rows need
// geometry.bvh_f.
std::vector<Method> coreMethods(const SceneGeometry& geometry, const MethodFilter& wanted,
                                int threads);
// Their names, in the same order, for --list-methods.
std::vector<std::string> coreMethodNames();

// The median of values (the upper one of an even count); values must not be empty.
double median(std::vector<double> values);

// Runs pass twice over rays (warming caches and building what the method keeps; the first
// result is kept in dist) and returns how many passes, timed as the second, a batch needs to last
// at least min_batch_seconds.
int firstPass(const Pass& pass, const WorkloadRays& w, const std::vector<int>& rays,
              std::vector<double>* dist, double min_batch_seconds);
// Times `reps` batches of per_batch passes; returns the median seconds per pass. Single-threaded,
// std::chrono::steady_clock.
double timeBatches(const Pass& pass, const WorkloadRays& w, const std::vector<int>& rays,
                   int per_batch, int reps);

}  // namespace bench
}  // namespace laser_raycast
