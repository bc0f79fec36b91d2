#include "bench_methods.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>

#include "bench_paths.h"
#include "laser_raycast/core/pattern_file.h"
#include "laser_raycast/core/returns.h"
#include "laser_raycast/core/velodyne_beams.h"
#include "laser_raycast/loader/ouster_metadata.h"

namespace laser_raycast {
namespace bench {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kDeg = M_PI / 180;
// Every path is driven with this seed: the level and the tilted fans follow the same path.
constexpr std::uint64_t kPathSeed = 20261126;

template <typename T>
const std::vector<core::RayT<T>>& raysOf(const WorkloadRays& w);
template <>
const std::vector<core::Ray>& raysOf<double>(const WorkloadRays& w) {
  return w.rays;
}
template <>
const std::vector<core::RayF>& raysOf<float>(const WorkloadRays& w) {
  return w.rays_f;
}
template <typename T>
const std::vector<double>& scaleOf(const WorkloadRays& w) {
  return std::is_same<T, double>::value ? w.scale : w.scale_f;
}

// Closest hit through the BVH, exactly as the caster traverses a mesh.
template <typename T, core::TriangleMethod M>
Pass bvhPass(const core::BvhT<T>& bvh) {
  return [&bvh](const WorkloadRays& w, const std::vector<int>& idx, std::vector<double>* out) {
    const auto& rays = raysOf<T>(w);
    const auto& scale = scaleOf<T>(w);
    for (const int i : idx) {
      const auto hit = bvh.template closestHit<M>(rays[i]);
      (*out)[i] = hit ? static_cast<double>(hit->t) * scale[i] : kInf;
    }
  };
}

// Brute force: every non-degenerate triangle (the BVH's filtered copy, in its precision) tested
// with one prepared ray, the nearest kept by shrinking tmax. This is core::bruteForceClosestHit's
// loop without its per-call degeneracy test and method dispatch, so the row measures the
// intersector itself.
template <typename T, core::TriangleMethod M>
Pass brutePass(const core::BvhT<T>& bvh) {
  return [&bvh](const WorkloadRays& w, const std::vector<int>& idx, std::vector<double>* out) {
    const auto& rays = raysOf<T>(w);
    const auto& scale = scaleOf<T>(w);
    const auto& tris = bvh.triangleVertices();
    for (const int i : idx) {
      const core::PreparedRay<T, M> prepared(rays[i], false);
      T tmax = rays[i].tmax;
      bool hit = false;
      for (std::uint32_t slot = 0; slot < tris.size(); ++slot) {
        const auto tri = tris[slot];
        if (const auto h = prepared.intersect(tri[0], tri[1], tri[2], tmax)) {
          tmax = h->t;
          hit = true;
        }
      }
      (*out)[i] = hit ? static_cast<double>(tmax) * scale[i] : kInf;
    }
  };
}

// The pipeline as the node runs it: one Caster::cast per sensor pose over the whole pattern, or
// one Caster::castSweep per rotating scan. forget() first, so that an unchanged pose does not
// return the previous result (a sweep is never reused). The caster keeps
// its thread pool between casts, as the node's does, and its kept slices (kept_slice.h) unless
// keep_slices is false: then every planar fan is cast as one in a plane never met before (a tilting
// sensor's, or a robot's first scans).
Pass pipelinePass(const BenchScene& scene, int threads, bool keep_slices) {
  auto caster = std::make_shared<core::Caster>();
  return [caster, &scene, threads, keep_slices](const WorkloadRays& w, const std::vector<int>&,
                                                std::vector<double>* out) {
    core::CastConfig config;
    config.tmin = 0;
    config.tmax = w.tmax;
    config.threads = threads;
    config.keep_slices = keep_slices;
    const std::size_t beams = static_cast<std::size_t>(w.beamCount());
    // The workload's beams shared with the caster, as the node shares a calibrated head's.
    const auto list = std::make_shared<const core::BeamList>(w.beams);
    for (std::size_t p = 0; p < w.scans(); ++p) {
      caster->forget();
      if (w.sub_rays) {
        // Divergent beams: every sub-ray pattern in one bundle, as castReturns casts them; out
        // holds them pattern after pattern, the result beam by beam.
        const core::ScanResult& all =
            caster->castBundle(scene.scene, scene.frame_poses, w.sensors[p], w.sub_rays, config);
        const std::size_t count = w.sub_rays->subRays(), n = w.sub_rays->beams();
        double* at = out->data() + p * beams;
        for (std::size_t k = 0; k < count; ++k) {
          for (std::size_t i = 0; i < n; ++i) *at++ = all.range[i * count + k];
        }
        continue;
      }
      const core::ScanResult& result =
          w.offGrid() && !w.sweeps.empty()
              ? caster->castBeamsSweep(scene.scene, w.sweeps[p], list, config)
          : w.offGrid()
              ? caster->castBeams(scene.scene, scene.frame_poses, w.sensors[p], list, config)
          : w.sweeps.empty()
              ? caster->cast(scene.scene, scene.frame_poses, w.sensors[p], *w.pattern, config)
              : caster->castSweep(scene.scene, w.sweeps[p], *w.pattern, config, w.time_increment);
      std::copy(result.range.begin(), result.range.end(), out->begin() + p * beams);
    }
  };
}

template <typename T>
const core::BvhT<T>& bvhOf(const SceneGeometry& g);
template <>
const core::Bvh& bvhOf<double>(const SceneGeometry& g) {
  return g.bvh;
}
template <>
const core::BvhF& bvhOf<float>(const SceneGeometry& g) {
  return g.bvh_f;
}

// Row order within a method: double BVH, double brute, float BVH, float brute.
template <typename T, core::TriangleMethod M>
void addMethodRows(const SceneGeometry& g, const MethodFilter& wanted, std::vector<Method>* out) {
  const std::string base =
      std::string(core::toString(M)) + (std::is_same<T, float>::value ? "_f32" : "");
  const std::size_t triangles = g.scene->soup.triangles.size();
  if (wanted(base + "_bvh")) {
    out->push_back(Method{base + "_bvh", false, false, triangles, bvhPass<T, M>(bvhOf<T>(g))});
  }
  if (wanted(base + "_brute")) {
    out->push_back(Method{base + "_brute", true, false, triangles, brutePass<T, M>(bvhOf<T>(g))});
  }
}

// A fan of n beams over the full turn, from -pi (the last one an increment short of +pi).
core::FanSpec fullTurn(int n) {
  core::FanSpec fan;
  fan.angle_min = -M_PI;
  fan.angle_max = M_PI - 2 * M_PI / n;
  fan.samples = n;
  return fan;
}

// A UTM-30LX: 1081 beams over 270 degrees.
core::FanSpec utm30lxFan() {
  core::FanSpec fan;
  fan.angle_min = -135 * kDeg;
  fan.angle_max = 135 * kDeg;
  fan.samples = 1081;
  return fan;
}

// A VLP-16: 16 rings, 2 degrees apart from -15 to +15.
std::vector<double> vlp16Rings() {
  std::vector<double> rings;
  for (int k = 0; k < 16; ++k) rings.push_back((-15.0 + 2.0 * k) * kDeg);
  return rings;
}

Workload moving(const std::string& name, const core::FanSpec& fan,
                const std::vector<double>& elevations, Motion motion, double scan_rate,
                int full_scans, int quick_scans) {
  Workload w;
  w.name = name;
  w.fan = fan;
  w.elevations = elevations;
  w.full_poses = full_scans;
  w.quick_poses = quick_scans;
  w.motion = motion;
  w.scan_rate = scan_rate;
  return w;
}

std::vector<Workload> stillWorkloads() {
  Workload fan2d;
  fan2d.name = "fan2d";
  fan2d.fan = utm30lxFan();
  fan2d.elevations = {0.0};
  fan2d.full_poses = 6;
  fan2d.quick_poses = 2;

  Workload rings3d;
  rings3d.name = "rings3d";
  rings3d.fan = fullTurn(1024);
  for (int k = 0; k < 64; ++k) rings3d.elevations.push_back((-15.0 + 30.0 * k / 63) * kDeg);
  rings3d.full_poses = 6;
  rings3d.quick_poses = 1;
  return {fan2d, rings3d};
}

// One pose per scan, every (TF rate / scan rate)-th sample of the path: a UTM-30LX at 40 Hz scans
// from every TF sample, a VLP-16 at 10 Hz from every fourth.
std::vector<SensorPose> pathPoses(const BenchScene& scene, const core::Bvh& soup_bvh,
                                  const Workload& workload, int scans) {
  const int step = std::max(1, static_cast<int>(std::lround(kTfRate / workload.scan_rate)));
  const std::vector<SensorPose> path = drivePath(
      scene.sensor_poses, soup_bvh, (scans - 1) * step + 1, workload.tilt_sigma, kPathSeed);
  std::vector<SensorPose> poses;
  for (int k = 0; k < scans; ++k) poses.push_back(path[k * step]);
  return poses;
}

// Rotating scans one after another along a path: each scan's pose samples into w->sweeps, and the
// pose of every column (at c * time_increment into its scan, as castSweep interpolates it) into
// w->poses. Column c of a full turn of n columns is taken c / n of the scan time in.
void sweepPoses(const BenchScene& scene, const core::Bvh& soup_bvh, const Workload& workload,
                int scans, WorkloadRays* w) {
  const double scan_seconds = 1 / workload.scan_rate;
  const int samples = static_cast<int>(std::ceil(scans * scan_seconds * kTfRate)) + 2;
  const std::vector<SensorPose> path =
      drivePath(scene.sensor_poses, soup_bvh, samples, 0, kPathSeed);
  w->time_increment = w->pattern->angleIncrement() * scan_seconds / (2 * M_PI);
  for (int k = 0; k < scans; ++k) {
    w->sweeps.push_back(sweepSamples(path, k * scan_seconds, scan_seconds, scene.frame_poses));
    // A calibrated head's beams each at their own time (castBeamsSweep), a grid's by column.
    const int count = w->offGrid() ? w->beams.size() : w->pattern->azimuthCount();
    for (int i = 0; i < count; ++i) {
      SensorPose pose{0, 0, 0, 0, 0, 0};
      const double t = w->offGrid() ? w->beams.time(i) : i * w->time_increment;
      pose.base = fromIsometry(w->sweeps.back().sensorAt(t));
      w->poses.push_back(pose);
    }
  }
}

}  // namespace

const std::vector<Workload>& workloads() {
  static const std::vector<Workload> list = [] {
    std::vector<Workload> all = stillWorkloads();
    all.push_back(moving("fan_path", utm30lxFan(), {0.0}, Motion::kPath, 40, 300, 24));
    Workload tilted = moving("fan_path_tilted", utm30lxFan(), {0.0}, Motion::kPath, 40, 300, 24);
    tilted.tilt_sigma = 0.4 * kDeg;
    all.push_back(tilted);
    all.push_back(moving("rings_path", fullTurn(1800), vlp16Rings(), Motion::kPath, 10, 30, 2));
    Workload divergent =
        moving("rings_divergent", fullTurn(1800), vlp16Rings(), Motion::kPath, 10, 30, 2);
    divergent.beam_samples = 7;
    divergent.beam_divergence = 0.003;
    all.push_back(divergent);
    all.push_back(moving("sweep_fan", fullTurn(360), {0.0}, Motion::kSweep, 5, 40, 3));
    all.push_back(moving("sweep_rings", fullTurn(1800), vlp16Rings(), Motion::kSweep, 10, 20, 1));
    Workload rosette = stillWorkloads()[1];
    rosette.name = "pattern_rosette";
    rosette.pattern_file = "rosette_4line.csv";
    all.push_back(rosette);
    // The calibrated heads, from the still poses and swept along the path.
    auto addHeads = [&all](Workload base, const std::string& prefix) {
      base.pattern_file.clear();
      base.name = prefix + "vlp16_calibrated";
      base.calibrated_vlp16 = true;
      all.push_back(base);
      base.name = prefix + "os1_64_metadata";
      base.calibrated_vlp16 = false;
      base.ouster_metadata = "os1_64_nominal.json";
      all.push_back(base);
    };
    addHeads(rosette, "");
    addHeads(moving("", fullTurn(1800), vlp16Rings(), Motion::kSweep, 10, 20, 1), "sweep_");
    return all;
  }();
  return list;
}

WorkloadRays makeRays(const BenchScene& scene, const core::Bvh& soup_bvh, const Workload& workload,
                      int count, double tmax) {
  WorkloadRays w;
  w.workload = &workload;
  w.pattern = std::make_unique<core::ScanPattern>(workload.fan, workload.elevations);
  w.tmax = tmax;
  if (!workload.pattern_file.empty()) {
    const core::PatternFile file = core::PatternFile::load(
        std::string(LASER_RAYCAST_SOURCE_DIR "/config/patterns/") + workload.pattern_file);
    w.beams = file.scan(0, file.size(), 1.0);
  }
  if (workload.calibrated_vlp16) w.beams = core::nominalVlp16().scan(0.1);
  if (workload.beam_samples > 1) {
    // The sub-ray patterns castReturns casts.
    core::ReturnsConfig returns;
    returns.beam_samples = workload.beam_samples;
    returns.beam_divergence = workload.beam_divergence;
    w.sub_rays = std::make_shared<const core::SubRayBundle>(
        core::subRayPatterns(workload.fan, workload.elevations, returns));
    for (const core::ScanPattern& p : w.sub_rays->patterns()) {
      w.beams.directions.insert(w.beams.directions.end(), p.directions().begin(),
                                p.directions().end());
    }
  }
  if (!workload.ouster_metadata.empty()) {
    w.beams = loadOusterMetadata(std::string(LASER_RAYCAST_SOURCE_DIR "/config/ouster/") +
                                 workload.ouster_metadata)
                  .scan(0.1);
  }
  // Still workloads: every beam from the pose's one time; sweeps keep each beam's. The lines stay,
  // as the node's and cast_scan's lists have them (a calibrated lidar's list is fitted to grids by
  // its lines).
  if (workload.motion != Motion::kSweep) w.beams.times.clear();
  if (workload.motion == Motion::kPath) {
    w.poses = pathPoses(scene, soup_bvh, workload, count);
  } else if (workload.motion == Motion::kSweep) {
    sweepPoses(scene, soup_bvh, workload, count, &w);
  } else {
    count = std::min<int>(count, static_cast<int>(scene.sensor_poses.size()));
    w.poses.assign(scene.sensor_poses.begin(), scene.sensor_poses.begin() + count);
  }
  for (const SensorPose& p : w.poses) w.sensors.push_back(toIsometry(p.exact()));
  const auto& directions = w.directions();
  for (std::size_t scan = 0; scan < w.scans(); ++scan) {
    for (int b = 0; b < w.beamCount(); ++b) {
      const Eigen::Isometry3d& sensor = w.sensors[w.poseIndex(scan, b)];
      core::Ray ray;
      ray.origin = sensor * w.origin(b);
      ray.dir = sensor.linear() * directions[b];
      ray.tmin = 0;
      ray.tmax = tmax;
      const core::RayF ray_f = core::toFloat(ray);
      w.rays.push_back(ray);
      w.rays_f.push_back(ray_f);
      w.scale.push_back(ray.dir.norm());
      w.scale_f.push_back(ray_f.dir.cast<double>().norm());
    }
  }
  return w;
}

std::vector<Method> coreMethods(const SceneGeometry& g, const MethodFilter& wanted, int threads) {
  std::vector<Method> methods;
  for (const core::TriangleMethod m : core::kAllTriangleMethods) {
    core::dispatchTriangleMethod(m, [&](auto method) {
      constexpr core::TriangleMethod M = decltype(method)::value;
      addMethodRows<double, M>(g, wanted, &methods);
      addMethodRows<float, M>(g, wanted, &methods);
    });
  }
  if (wanted("pipeline")) {
    const std::size_t triangles = g.scene->scene.triangleCount();
    methods.push_back(
        Method{"pipeline", false, true, triangles, pipelinePass(*g.scene, 1, true), true});
    methods.back().moving = true;
    if (threads != 1) {
      methods.push_back(Method{"pipeline", false, true, triangles,
                               pipelinePass(*g.scene, threads, true), true, threads});
      methods.back().moving = true;
    }
  }
  if (wanted("pipeline_new_plane")) {
    const std::size_t triangles = g.scene->scene.triangleCount();
    methods.push_back(Method{"pipeline_new_plane", false, true, triangles,
                             pipelinePass(*g.scene, 1, false), true, 1, true});
  }
  return methods;
}

std::vector<std::string> coreMethodNames() {
  std::vector<std::string> names;
  for (const core::TriangleMethod m : core::kAllTriangleMethods) {
    for (const std::string precision : {"", "_f32"}) {
      for (const std::string kind : {"_bvh", "_brute"}) {
        names.push_back(core::toString(m) + precision + kind);
      }
    }
  }
  names.push_back("pipeline");
  names.push_back("pipeline_new_plane");
  return names;
}

double median(std::vector<double> values) {
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

int firstPass(const Pass& pass, const WorkloadRays& w, const std::vector<int>& rays,
              std::vector<double>* dist, double min_batch_seconds) {
  // The first pass may build what the method keeps between passes (the caster's scene index and
  // kept slices): the batch is sized from a second one, which is what a timed pass costs.
  pass(w, rays, dist);
  std::vector<double> scratch(dist->size());
  const auto start = std::chrono::steady_clock::now();
  pass(w, rays, &scratch);
  const double second =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return std::max(1, static_cast<int>(std::ceil(min_batch_seconds / std::max(second, 1e-9))));
}

double timeBatches(const Pass& pass, const WorkloadRays& w, const std::vector<int>& rays,
                   int per_batch, int reps) {
  using Clock = std::chrono::steady_clock;
  std::vector<double> scratch(w.rays.size());
  std::vector<double> per_pass;
  for (int r = 0; r < reps; ++r) {
    const auto start = Clock::now();
    for (int k = 0; k < per_batch; ++k) pass(w, rays, &scratch);
    per_pass.push_back(std::chrono::duration<double>(Clock::now() - start).count() / per_batch);
  }
  return median(std::move(per_pass));
}

}  // namespace bench
}  // namespace laser_raycast
