#include "laser_raycast/core/caster.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "laser_raycast/core/beam_window.h"
#include "laser_raycast/core/fan_slicer.h"
#include "laser_raycast/core/pose.h"

namespace laser_raycast {
namespace core {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// What tracing one beam through a mesh costs, in units of placing one slice segment (see
// castBodies): on the benchmark's scenes a traversal takes about 150-300 ns and a segment 60-100
// ns. Only speed depends on it.
constexpr double kBeamCostInSegments = 2.0;

// One beam's nearest hit on one body: distance, triangle (-1 for a primitive), and the surface
// normal in the body's frame (a mesh triangle's front normal, a primitive's outward normal).
struct BodyHit {
  double t;
  int triangle;
  Eigen::Vector3d normal;
};

// One beam (unit direction in the sensor frame) against one body, with t in [tmin, tmax].
template <TriangleMethod M>
std::optional<BodyHit> intersectBody(const Body& body, const Caster::ActiveBody& active,
                                     const Eigen::Vector3d& dir, double tmin, double tmax,
                                     bool cull_backfaces) {
  Ray ray;
  ray.origin = active.sensor_in_body;
  ray.dir = active.body_from_sensor_rot * dir;
  ray.tmin = tmin;
  ray.tmax = tmax;
  std::optional<PrimitiveHit> primitive;
  switch (body.shape.index()) {
    case 0:
      primitive = intersect(ray, std::get<Box>(body.shape));
      break;
    case 1:
      primitive = intersect(ray, std::get<Cylinder>(body.shape));
      break;
    case 2:
      primitive = intersect(ray, std::get<Sphere>(body.shape));
      break;
    default: {
      const auto& mesh = std::get<std::shared_ptr<const Mesh>>(body.shape);
      const auto hit = mesh->bvh().closestHit<M>(ray, cull_backfaces);
      if (!hit) return std::nullopt;
      return BodyHit{hit->t, static_cast<int>(hit->triangle), mesh->normal(hit->triangle)};
    }
  }
  if (!primitive) return std::nullopt;
  return BodyHit{primitive->t, -1, primitive->normal};
}

}  // namespace

void CastConfig::validate() const {
  std::ostringstream msg;
  if (!(std::isfinite(tmin) && tmin >= 0)) {
    msg << "tmin must be finite and >= 0, got " << tmin;
  } else if (!(tmax > tmin)) {
    msg << "tmax (" << tmax << " m) must be greater than tmin (" << tmin << " m)";
  } else {
    return;
  }
  throw std::invalid_argument(msg.str());
}

bool CastConfig::operator==(const CastConfig& o) const {
  return method == o.method && cull_backfaces == o.cull_backfaces && tmin == o.tmin &&
         tmax == o.tmax && planar_fast_path == o.planar_fast_path &&
         compute_incidence == o.compute_incidence;
}

bool Caster::ReuseKey::operator==(const ReuseKey& o) const {
  if (scene_version != o.scene_version || !(config == o.config) || angle_min != o.angle_min ||
      angle_increment != o.angle_increment || azimuths != o.azimuths ||
      elevations != o.elevations || valid != o.valid) {
    return false;
  }
  for (std::size_t f = 0; f < sensor_from_frame.size(); ++f) {
    if (valid[f] && sensor_from_frame[f].matrix() != o.sensor_from_frame[f].matrix()) return false;
  }
  return true;
}

const ScanResult& Caster::cast(const Scene& scene, const FramePoses& poses,
                               const Eigen::Isometry3d& world_from_sensor,
                               const ScanPattern& pattern, const CastConfig& config) {
  config.validate();
  const std::size_t frame_count = scene.frames().size();
  if (poses.pose.size() != frame_count || poses.valid.size() != frame_count) {
    std::ostringstream msg;
    msg << "FramePoses has " << poses.pose.size() << " poses for a scene of " << frame_count
        << " frames";
    throw std::invalid_argument(msg.str());
  }
  const bool sensor_ok = isValidPose(world_from_sensor);
  ReuseKey key = relativeInputs(scene, poses, world_from_sensor, pattern, config);
  if (sensor_ok && previous_ && *previous_ == key) {
    result_.stats.reused = true;
    return result_;
  }
  previous_.reset();
  resetResult(pattern.size(), static_cast<int>(scene.bodies().size()), sensor_ok,
              config.compute_incidence);
  if (!sensor_ok) return result_;

  prepareBodies(scene, key, pattern, config);
  castBodies(scene, pattern, config);
  if (config.compute_incidence) computeIncidence(pattern);
  previous_ = std::move(key);
  return result_;
}

// Every frame relative to the sensor, in double, once per scan (so that a scene far from the origin
// loses nothing), together with everything else the result depends on.
Caster::ReuseKey Caster::relativeInputs(const Scene& scene, const FramePoses& poses,
                                        const Eigen::Isometry3d& world_from_sensor,
                                        const ScanPattern& pattern,
                                        const CastConfig& config) const {
  const bool sensor_ok = isValidPose(world_from_sensor);
  const std::size_t frame_count = scene.frames().size();
  ReuseKey key;
  key.scene_version = scene.version();
  key.config = config;
  key.angle_min = pattern.angleMin();
  key.angle_increment = pattern.angleIncrement();
  key.azimuths = pattern.azimuthCount();
  key.elevations = pattern.elevations();
  key.sensor_from_frame.assign(frame_count, Eigen::Isometry3d::Identity());
  key.valid.assign(frame_count, 0);
  for (std::size_t f = 0; f < frame_count; ++f) {
    // A pose marked valid but not a finite rigid transform (FramePoses filled by hand rather than
    // by resolveFramePoses) would be inverted by transposing its rotation: treat it as unknown.
    key.valid[f] = sensor_ok && poses.valid[f] && isValidPose(poses.pose[f]);
    if (key.valid[f]) key.sensor_from_frame[f] = relativePose(world_from_sensor, poses.pose[f]);
  }
  return key;
}

void Caster::resetResult(int beams, int bodies, bool sensor_ok, bool with_normals) {
  result_.range.assign(beams, sensor_ok ? kInf : std::numeric_limits<double>::quiet_NaN());
  result_.body.assign(beams, -1);
  result_.triangle.assign(beams, -1);
  if (with_normals) {
    result_.normal.assign(beams, Eigen::Vector3d::Zero());
  } else {
    result_.normal.clear();
  }
  result_.cos_incidence.clear();
  result_.stats = CastStats{};
  result_.stats.bodies = bodies;
}

// Each body's pose relative to the sensor, then culled by bounding sphere against the search
// interval, the scan plane (planar fans) and the fan's azimuths; the rest sorted nearest first.
void Caster::prepareBodies(const Scene& scene, const ReuseKey& key, const ScanPattern& pattern,
                           const CastConfig& config) {
  const bool planar = pattern.planar();
  const auto& bodies = scene.bodies();
  active_.clear();
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const Body& body = bodies[b];
    if (!key.valid[body.frame]) {
      ++result_.stats.bodies_skipped;
      continue;
    }
    ActiveBody a;
    a.index = static_cast<int>(b);
    a.sensor_from_body = key.sensor_from_frame[body.frame] * body.frame_from_body;
    a.body_from_sensor_rot = a.sensor_from_body.linear().transpose();
    a.sensor_in_body = -(a.body_from_sensor_rot * a.sensor_from_body.translation());
    a.center = a.sensor_from_body * scene.sphereCenter(static_cast<int>(b));
    a.radius = scene.sphereRadius(static_cast<int>(b));
    const double dist = a.center.norm();
    const double slack = kWindowSlack * (dist + a.radius + config.tmax);
    a.near = std::max(0.0, dist - a.radius - slack);
    bool culled = dist - a.radius > config.tmax + slack || dist + a.radius < config.tmin - slack;
    if (planar && std::abs(a.center.z()) > a.radius + kWindowSlack * (dist + a.radius)) {
      culled = true;
    }
    a.azimuth_limited =
        azimuthWindow(a.center, a.radius, pattern.angleMin(), &a.azimuth_start, &a.azimuth_width);
    if (!culled && a.azimuth_limited) {
      bool any = false;
      forEachBeamRange(pattern, a.azimuth_start, a.azimuth_width, [&](int, int) { any = true; });
      culled = !any;
    }
    elevationWindow(a.center, a.radius, &a.elevation_lo, &a.elevation_hi);
    if (culled) {
      ++result_.stats.bodies_culled;
      continue;
    }
    active_.push_back(a);
  }
  // Nearest first: a beam that has already hit something nearer than a body can be skips it, so
  // bodies hidden behind nearer ones cost a comparison per beam of their window.
  std::sort(active_.begin(), active_.end(),
            [](const ActiveBody& x, const ActiveBody& y) { return x.near < y.near; });
}

// Every active body against the beams of its window that have not hit anything nearer than it: a
// mesh under a planar fan is sliced or traced, whichever does less work; everything else is traced
// beam by beam.
void Caster::castBodies(const Scene& scene, const ScanPattern& pattern, const CastConfig& config) {
  const auto& bodies = scene.bodies();
  const auto& dirs = pattern.directions();
  const bool with_normals = config.compute_incidence;
  const bool slice_meshes = pattern.planar() && config.planar_fast_path;

  // The beams of a body's window (azimuths, then the rings whose elevation it spans) that have not
  // hit anything nearer than the body's nearest point.
  auto forEachBeamOf = [&](const ActiveBody& a, auto&& f) {
    const int azimuths = pattern.azimuthCount();
    for (int ring = 0; ring < pattern.ringCount(); ++ring) {
      const double elevation = pattern.elevations()[ring];
      if (elevation < a.elevation_lo || elevation > a.elevation_hi) continue;
      const int offset = ring * azimuths;
      auto run = [&](int first, int last) {
        for (int i = offset + first; i <= offset + last; ++i) {
          if (result_.range[i] > a.near) f(i);
        }
      };
      if (a.azimuth_limited) {
        forEachBeamRange(pattern, a.azimuth_start, a.azimuth_width, run);
      } else {
        run(0, azimuths - 1);
      }
    }
  };

  dispatchTriangleMethod(config.method, [&](auto method) {
    constexpr TriangleMethod M = decltype(method)::value;
    for (const ActiveBody& a : active_) {
      const Body& body = bodies[a.index];
      const auto* mesh = std::get_if<std::shared_ptr<const Mesh>>(&body.shape);
      if (mesh && slice_meshes) {
        // A plane cuts about 2 sqrt(n) of a compact closed mesh's n triangles, each a segment to
        // place; a beam costs one BVH traversal, about kBeamCostInSegments segments. Walls and
        // rooms cover many beams and are sliced; a detailed object far away covers a few and is
        // traced. Both are watertight and agree, but where a surface only touches the scan plane
        // (see fan_slicer.h).
        int open_beams = 0;
        forEachBeamOf(a, [&](int) { ++open_beams; });
        if (open_beams == 0) continue;  // hidden behind nearer bodies
        const double segments = 2 * std::sqrt(double((*mesh)->bvh().triangleIds().size()));
        if (kBeamCostInSegments * open_beams >= segments) {
          sliceMesh(**mesh, a.sensor_from_body, pattern, config.tmin, config.tmax,
                    config.cull_backfaces, a.index,
                    DepthBuffer{&result_.range, &result_.body, &result_.triangle, nullptr,
                                with_normals ? &result_.normal : nullptr});
          continue;
        }
      }
      // Traced beam by beam, skipping beams that pass beside the bounding sphere.
      const double slack_base = kWindowSlack * (a.center.squaredNorm() + a.radius * a.radius);
      forEachBeamOf(a, [&](int i) {
        const Eigen::Vector3d& d = dirs[i];
        const double along = d.dot(a.center);
        const double miss2 = (a.center - along * d).squaredNorm() - a.radius * a.radius;
        if (miss2 > slack_base) return;
        const auto hit =
            intersectBody<M>(body, a, d, config.tmin, std::min(config.tmax, result_.range[i]),
                             config.cull_backfaces);
        if (!hit || !(hit->t < result_.range[i])) return;
        result_.range[i] = hit->t;
        result_.body[i] = a.index;
        result_.triangle[i] = hit->triangle;
        if (with_normals) result_.normal[i] = a.sensor_from_body.linear() * hit->normal;
      });
    }
  });
}

void Caster::computeIncidence(const ScanPattern& pattern) {
  const auto& dirs = pattern.directions();
  result_.cos_incidence.assign(dirs.size(), 0.0);
  for (std::size_t i = 0; i < dirs.size(); ++i) {
    if (result_.body[i] < 0) continue;
    result_.cos_incidence[i] = std::min(1.0, std::abs(dirs[i].dot(result_.normal[i])));
  }
}

}  // namespace core
}  // namespace laser_raycast
