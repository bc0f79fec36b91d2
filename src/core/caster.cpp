#include "laser_raycast/core/caster.h"

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

// The azimuth interval (from the fan's angle_min, width in [0, 2 pi]) that a sphere at `center`
// (sensor frame) can occupy. False if it contains the z axis: every azimuth.
bool azimuthWindow(const Eigen::Vector3d& center, double radius, double angle_min, double* start,
                   double* width) {
  const double rho = std::hypot(center.x(), center.y());
  if (!(rho > radius * (1 + kCullSlack))) return false;
  const double half = std::asin(radius / rho);
  double s = std::fmod(std::atan2(center.y(), center.x()) - half - angle_min, 2 * M_PI);
  if (s < 0) s += 2 * M_PI;
  *start = s;
  *width = 2 * half;
  return true;
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
  std::vector<int> active_of_body(bodies.size(), -1);
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
    bool culled = dist - a.radius > config.tmax + slack || dist + a.radius < config.tmin - slack;
    if (planar && std::abs(a.center.z()) > a.radius + kCullSlack * (dist + a.radius)) culled = true;
    double start, width;
    if (!culled && azimuthWindow(a.center, a.radius, pattern.angleMin(), &start, &width)) {
      bool any = false;
      forEachBeamRange(pattern, start, width, [&](int, int) { any = true; });
      culled = !any;
    }
    if (culled) {
      ++result_.stats.bodies_culled;
      continue;
    }
    active_of_body[b] = static_cast<int>(active_.size());
    active_.push_back(a);
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

    if (planar && config.planar_fast_path) {
      // Meshes are sliced; primitives are traced, only over the beams their bounding sphere spans.
      for (const ActiveBody& a : active_) {
        const Body& body = bodies[a.index];
        if (const auto* mesh = std::get_if<std::shared_ptr<const Mesh>>(&body.shape)) {
          sliceMesh(**mesh, a.sensor_from_body, pattern, tmin, config.tmax, config.cull_backfaces,
                    a.index, DepthBuffer{&result_.range, &result_.body, &result_.triangle});
          continue;
        }
        double start, width;
        if (azimuthWindow(a.center, a.radius, pattern.angleMin(), &start, &width)) {
          forEachBeamRange(pattern, start, width, [&](int first, int last) {
            for (int i = first; i <= last; ++i) test(a, i);
          });
        } else {
          for (int i = 0; i < beams; ++i) test(a, i);
        }
      }
      return;
    }

    // General path: every beam against every body whose bounding sphere it can reach.
    for (int i = 0; i < beams; ++i) {
      const Eigen::Vector3d& d = dirs[i];
      for (const ActiveBody& a : active_) {
        const double along = d.dot(a.center);
        const double reach = std::min(config.tmax, result_.range[i]);
        const double slack = kCullSlack * (std::abs(along) + a.radius + reach);
        if (along + a.radius < tmin - slack || along - a.radius > reach + slack) continue;
        const double miss2 = (a.center - along * d).squaredNorm() - a.radius * a.radius;
        if (miss2 > kCullSlack * (a.center.squaredNorm() + a.radius * a.radius)) continue;
        test(a, i);
      }
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
