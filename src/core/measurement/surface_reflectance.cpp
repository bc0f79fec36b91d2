// The reflectance and incidence at each beam's hit from the surface hit (surface_reflectance.h).
#include "laser_raycast/core/surface_reflectance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "laser_raycast/core/pose.h"
#include "laser_raycast/core/surface.h"

namespace laser_raycast {
namespace core {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// Beam i leaves from origins[i] (sensor frame; the sensor's origin if origins is empty) along
// directions[i].
void sampleBeams(const Scene& scene, const FramePoses& poses,
                 const Eigen::Isometry3d& world_from_sensor,
                 const std::vector<Eigen::Vector3d>& directions,
                 const std::vector<Eigen::Vector3d>& origins, const ScanResult& result,
                 double reflectance_from_color, const std::vector<char>& label_fixed,
                 SurfaceSamples* out) {
  const std::size_t n = result.range.size();
  if (result.cos_incidence.size() != n || directions.size() != n ||
      !(origins.empty() || origins.size() == n)) {
    throw std::invalid_argument(
        "sampleSurfaces needs the cast's cos_incidence (compute_incidence) for every beam of its "
        "pattern");
  }
  out->reflectance.assign(n, kNan);
  out->cos_incidence = result.cos_incidence;
  // Each body's pose relative to the sensor, computed at its first hit.
  std::vector<Eigen::Isometry3d> body_from_sensor_of(scene.bodies().size());
  std::vector<char> placed(scene.bodies().size(), 0);
  for (std::size_t i = 0; i < n; ++i) {
    const int body_index = result.body[i];
    const int triangle = result.triangle[i];
    if (body_index < 0 || !std::isfinite(result.range[i])) continue;
    const Body& body = scene.bodies()[body_index];
    const bool fixed = body.label < static_cast<int>(label_fixed.size()) && label_fixed[body.label];
    // The body's own colour, unless its mesh gives one at the hit (below).
    if (!fixed && body.has_color) {
      out->reflectance[i] = reflectanceFromColor(body.color, reflectance_from_color);
    }
    const auto* mesh_ptr = std::get_if<std::shared_ptr<const Mesh>>(&body.shape);
    if (!mesh_ptr || !*mesh_ptr || triangle < 0) continue;
    const Mesh& mesh = **mesh_ptr;
    const SurfaceAttributes* surface = mesh.surface();
    if (!surface) continue;
    const bool wants_color = !fixed && surface->hasColor();
    if (!wants_color && surface->normals.empty()) continue;
    // The beam in the mesh's frame: the hit's barycentric coordinates on the triangle.
    if (body.frame >= static_cast<int>(poses.pose.size())) continue;
    if (!placed[body_index]) {
      body_from_sensor_of[body_index] =
          (relativePose(world_from_sensor, poses.pose[body.frame]) * body.frame_from_body)
              .inverse();
      placed[body_index] = 1;
    }
    const Eigen::Isometry3d& body_from_sensor = body_from_sensor_of[body_index];
    const Eigen::Vector3d origin = origins.empty() ? body_from_sensor.translation()
                                                   : Eigen::Vector3d(body_from_sensor * origins[i]);
    const Eigen::Vector3d dir = body_from_sensor.linear() * directions[i];
    const TriangleIndices& tri = mesh.triangles()[triangle];
    const auto& v = mesh.vertices();
    Eigen::Vector3d w;
    if (!barycentricAt(origin, dir, v[tri[0]], v[tri[1]], v[tri[2]], &w)) continue;
    auto interpolate = [&](const auto& values) {
      return (w[0] * values[tri[0]].template cast<double>() +
              w[1] * values[tri[1]].template cast<double>() +
              w[2] * values[tri[2]].template cast<double>())
          .eval();
    };
    if (!surface->normals.empty()) {
      const Eigen::Vector3d normal = interpolate(surface->normals);
      const double norm = normal.norm();
      if (norm > 0) out->cos_incidence[i] = std::min(1.0, std::abs(dir.dot(normal)) / norm);
    }
    if (!wants_color) continue;
    if (!surface->colors.empty()) {
      out->reflectance[i] =
          reflectanceFromColor(interpolate(surface->colors), reflectance_from_color);
      continue;
    }
    if (surface->materials.empty()) continue;
    const SurfaceMaterial& material =
        surface
            ->materials[surface->triangle_material.empty() ? 0
                                                           : surface->triangle_material[triangle]];
    if (material.texture && !surface->uvs.empty()) {
      const Eigen::Vector2d uv = interpolate(surface->uvs);
      out->reflectance[i] =
          reflectanceFromColor(material.texture->sample(uv.x(), uv.y()), reflectance_from_color);
    } else if (material.has_diffuse) {
      out->reflectance[i] = reflectanceFromColor(material.diffuse, reflectance_from_color);
    }
  }
}

}  // namespace

void sampleSurfaces(const Scene& scene, const FramePoses& poses,
                    const Eigen::Isometry3d& world_from_sensor, const ScanPattern& pattern,
                    const ScanResult& result, double reflectance_from_color,
                    const std::vector<char>& label_fixed, SurfaceSamples* out) {
  sampleBeams(scene, poses, world_from_sensor, pattern.directions(), {}, result,
              reflectance_from_color, label_fixed, out);
}

void sampleSurfaces(const Scene& scene, const FramePoses& poses,
                    const Eigen::Isometry3d& world_from_sensor, const BeamList& beams,
                    const ScanResult& result, double reflectance_from_color,
                    const std::vector<char>& label_fixed, SurfaceSamples* out) {
  sampleBeams(scene, poses, world_from_sensor, beams.directions, beams.origins, result,
              reflectance_from_color, label_fixed, out);
}

void sampleSurfaces(const Scene& scene, const FramePoses& poses,
                    const Eigen::Isometry3d& world_from_sensor, const SubRayBundle& bundle,
                    const ScanResult& result, double reflectance_from_color,
                    const std::vector<char>& label_fixed, SurfaceSamples* out) {
  sampleBeams(scene, poses, world_from_sensor, bundle.directions(), {}, result,
              reflectance_from_color, label_fixed, out);
}

}  // namespace core
}  // namespace laser_raycast
