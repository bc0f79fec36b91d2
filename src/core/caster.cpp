#include "laser_raycast/core/caster.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "laser_raycast/core/fan_slicer.h"
#include "laser_raycast/core/pose.h"

namespace laser_raycast {
namespace core {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Relative slack for the culling tests, which round a few times: a body is culled only if it is out
// by more than this fraction of the magnitudes compared. Not an absolute epsilon.
constexpr double kCullSlack = 8 * std::numeric_limits<double>::epsilon();

// What tracing one beam through a mesh costs, in units of placing one slice segment (see the planar
// path in cast()): on the benchmark's scenes a traversal takes about 150-300 ns and a segment
// 60-100 ns. Only speed depends on it.
constexpr double kBeamCostInSegments = 2.0;

// The elevation interval (rad) that a sphere at `center` (sensor frame) can occupy; all of
// [-pi/2, pi/2] if it contains the sensor.
void elevationWindow(const Eigen::Vector3d& center, double radius, double* lo, double* hi) {
  const double dist = center.norm();
  if (!(dist > radius * (1 + kCullSlack))) {
    *lo = -M_PI / 2;
    *hi = M_PI / 2;
    return;
  }
  // Widened for the rounding of asin and its arguments: relatively, and by kCullSlack rad, which is
  // relative too since elevations are of order 1.
  const double half = std::asin(std::min(1.0, radius * (1 + kCullSlack) / dist)) * (1 + kCullSlack);
  const double middle = std::asin(std::max(-1.0, std::min(1.0, center.z() / dist)));
  *lo = middle - half - kCullSlack;
  *hi = middle + half + kCullSlack;
}

struct BodyHit {
  double t;
  int triangle;
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
  switch (body.shape.index()) {
    case 0:
      if (const auto hit = intersect(ray, std::get<Box>(body.shape))) return BodyHit{hit->t, -1};
      return std::nullopt;
    case 1:
      if (const auto hit = intersect(ray, std::get<Cylinder>(body.shape)))
        return BodyHit{hit->t, -1};
      return std::nullopt;
    case 2:
      if (const auto hit = intersect(ray, std::get<Sphere>(body.shape))) return BodyHit{hit->t, -1};
      return std::nullopt;
    default: {
      const auto& mesh = std::get<std::shared_ptr<const Mesh>>(body.shape);
      if (const auto hit = mesh->bvh().closestHit<M>(ray, cull_backfaces)) {
        return BodyHit{hit->t, static_cast<int>(hit->triangle)};
      }
      return std::nullopt;
    }
  }
}

// The outward normal (sensor frame) where the beam hits the body, for the incidence angle.
Eigen::Vector3d hitNormal(const Body& body, const Caster::ActiveBody& active,
                          const Eigen::Vector3d& dir, double t, int triangle) {
  if (const auto* mesh = std::get_if<std::shared_ptr<const Mesh>>(&body.shape)) {
    return active.sensor_from_body.linear() * (*mesh)->normal(static_cast<std::uint32_t>(triangle));
  }
  // Re-intersect the primitive from just before the known distance: its first crossing is the hit.
  Ray ray;
  ray.origin = active.sensor_in_body;
  ray.dir = active.body_from_sensor_rot * dir;
  ray.tmin = t * (1 - kCullSlack);
  std::optional<PrimitiveHit> hit;
  if (const auto* box = std::get_if<Box>(&body.shape)) hit = intersect(ray, *box);
  if (const auto* cylinder = std::get_if<Cylinder>(&body.shape)) hit = intersect(ray, *cylinder);
  if (const auto* sphere = std::get_if<Sphere>(&body.shape)) hit = intersect(ray, *sphere);
  if (!hit) return Eigen::Vector3d::Zero();
  return active.sensor_from_body.linear() * hit->normal;
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

bool Caster::unchanged(const Scene& scene, const std::vector<Eigen::Isometry3d>& sensor_from_frame,
                       const std::vector<char>& valid, const ScanPattern& pattern,
                       const CastConfig& config) const {
  if (!has_previous_ || previous_scene_ != scene.version() || !(previous_config_ == config) ||
      previous_angle_min_ != pattern.angleMin() ||
      previous_increment_ != pattern.angleIncrement() ||
      previous_azimuths_ != pattern.azimuthCount() ||
      previous_elevations_ != pattern.elevations() || previous_valid_ != valid) {
    return false;
  }
  for (std::size_t f = 0; f < sensor_from_frame.size(); ++f) {
    if (valid[f] && sensor_from_frame[f].matrix() != previous_relative_[f].matrix()) return false;
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

  // Every frame relative to the sensor, in double, once per scan.
  std::vector<Eigen::Isometry3d> sensor_from_frame(frame_count, Eigen::Isometry3d::Identity());
  std::vector<char> valid(frame_count, 0);
  for (std::size_t f = 0; f < frame_count; ++f) {
    // A pose marked valid but not a finite rigid transform (FramePoses filled by hand rather than
    // by resolveFramePoses) would be inverted by transposing its rotation: treat it as unknown.
    valid[f] = sensor_ok && poses.valid[f] && isValidPose(poses.pose[f]);
    if (valid[f]) sensor_from_frame[f] = relativePose(world_from_sensor, poses.pose[f]);
  }
  if (sensor_ok && unchanged(scene, sensor_from_frame, valid, pattern, config)) {
    result_.stats.reused = true;
    return result_;
  }

  const int beams = pattern.size();
  const auto& bodies = scene.bodies();
  result_.range.assign(beams, sensor_ok ? kInf : std::numeric_limits<double>::quiet_NaN());
  result_.body.assign(beams, -1);
  result_.triangle.assign(beams, -1);
  result_.cos_incidence.clear();
  result_.stats = CastStats{};
  result_.stats.bodies = static_cast<int>(bodies.size());
  has_previous_ = false;
  if (!sensor_ok) return result_;

  // Bodies for this scan: pose relative to the sensor, then culled by bounding sphere.
  const bool planar = pattern.planar();
  active_.clear();
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const Body& body = bodies[b];
    if (!valid[body.frame]) {
      ++result_.stats.bodies_skipped;
      continue;
    }
    ActiveBody a;
    a.index = static_cast<int>(b);
    a.sensor_from_body = sensor_from_frame[body.frame] * body.frame_from_body;
    a.body_from_sensor_rot = a.sensor_from_body.linear().transpose();
    a.sensor_in_body = -(a.body_from_sensor_rot * a.sensor_from_body.translation());
    a.center = a.sensor_from_body * scene.sphereCenter(static_cast<int>(b));
    a.radius = scene.sphereRadius(static_cast<int>(b));
    const double dist = a.center.norm();
    const double slack = kCullSlack * (dist + a.radius + config.tmax);
    a.near = std::max(0.0, dist - a.radius - slack);
    bool culled = dist - a.radius > config.tmax + slack || dist + a.radius < config.tmin - slack;
    if (planar && std::abs(a.center.z()) > a.radius + kCullSlack * (dist + a.radius)) culled = true;
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
  std::vector<int> active_of_body(bodies.size(), -1);
  for (std::size_t k = 0; k < active_.size(); ++k) {
    active_of_body[active_[k].index] = static_cast<int>(k);
  }

  const auto& dirs = pattern.directions();
  const double tmin = config.tmin;
  dispatchTriangleMethod(config.method, [&](auto method) {
    constexpr TriangleMethod M = decltype(method)::value;
    auto test = [&](const ActiveBody& a, int i) {
      const auto hit =
          intersectBody<M>(bodies[a.index], a, dirs[i], tmin,
                           std::min(config.tmax, result_.range[i]), config.cull_backfaces);
      if (hit && hit->t < result_.range[i]) {
        result_.range[i] = hit->t;
        result_.body[i] = a.index;
        result_.triangle[i] = hit->triangle;
      }
    };

    // The beams of a body's window (azimuths, then the rings whose elevation it spans) that have
    // not hit anything nearer than the body's nearest point.
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

    for (const ActiveBody& a : active_) {
      const Body& body = bodies[a.index];
      const auto* mesh = std::get_if<std::shared_ptr<const Mesh>>(&body.shape);
      if (mesh && planar && config.planar_fast_path) {
        // Slice the mesh in the scan plane, or trace the beams it can still improve, whichever
        // does less work. A plane cuts about 2 sqrt(n) of a compact closed mesh's n triangles, each
        // a segment to place; a beam costs one BVH traversal, about kBeamCostInSegments segments.
        // Walls and rooms cover many beams and are sliced; a detailed object far away covers a
        // few and is traced. Both are watertight and agree, but where a surface only touches the
        // scan plane (see fan_slicer.h).
        int open_beams = 0;
        forEachBeamOf(a, [&](int) { ++open_beams; });
        if (open_beams == 0) continue;  // hidden behind nearer bodies
        const double segments = 2 * std::sqrt(double((*mesh)->bvh().triangleIds().size()));
        if (kBeamCostInSegments * open_beams >= segments) {
          sliceMesh(**mesh, a.sensor_from_body, pattern, tmin, config.tmax, config.cull_backfaces,
                    a.index, DepthBuffer{&result_.range, &result_.body, &result_.triangle});
          continue;
        }
      }
      // Traced beam by beam, skipping beams that pass beside the bounding sphere.
      const double slack_base = kCullSlack * (a.center.squaredNorm() + a.radius * a.radius);
      forEachBeamOf(a, [&](int i) {
        const Eigen::Vector3d& d = dirs[i];
        const double along = d.dot(a.center);
        const double miss2 = (a.center - along * d).squaredNorm() - a.radius * a.radius;
        if (miss2 > slack_base) return;
        test(a, i);
      });
    }
  });

  if (config.compute_incidence) {
    result_.cos_incidence.assign(beams, 0.0);
    for (int i = 0; i < beams; ++i) {
      const int b = result_.body[i];
      if (b < 0) continue;
      const ActiveBody& a = active_[active_of_body[b]];
      const Eigen::Vector3d n =
          hitNormal(bodies[b], a, dirs[i], result_.range[i], result_.triangle[i]);
      result_.cos_incidence[i] = std::min(1.0, std::abs(dirs[i].dot(n)));
    }
  }

  has_previous_ = true;
  previous_scene_ = scene.version();
  previous_config_ = config;
  previous_angle_min_ = pattern.angleMin();
  previous_increment_ = pattern.angleIncrement();
  previous_azimuths_ = pattern.azimuthCount();
  previous_elevations_ = pattern.elevations();
  previous_relative_ = std::move(sensor_from_frame);
  previous_valid_ = std::move(valid);
  return result_;
}

}  // namespace core
}  // namespace laser_raycast
