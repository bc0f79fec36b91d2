// The reflectance and incidence at each beam's hit from the surface hit: a mesh's vertex colours,
// texture or material colour (surface.h), and its vertex normals. A scan's second step after the
// cast (ScanResult gives each beam's body and triangle); MeasurementModel::measure uses it.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "laser_raycast/core/beam_list.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/scan_result.h"
#include "laser_raycast/core/scene.h"
#include "laser_raycast/core/sub_ray_bundle.h"

namespace laser_raycast {
namespace core {

struct SurfaceSamples {
  // Per beam: the surface's reflectance at the hit, NaN where it gives none (no hit, a primitive,
  // a mesh without colours, or a link whose reflectivity is set): the link's value applies there.
  std::vector<double> reflectance;
  // Per beam: |cos| of the angle between the beam and the mesh's vertex normals interpolated at
  // the hit where the mesh has them, else the cast's own (the triangle's or primitive's normal).
  std::vector<double> cos_incidence;
};

// For a hit on a mesh triangle, the order is: vertex colours, else the material's texture at the
// interpolated texture coordinates, else the material's diffuse colour, else the body's colour
// (Body::color, the URDF <material>'s); for a primitive, the body's colour. Each becomes a
// reflectance by reflectanceFromColor(colour, reflectance_from_color). label_fixed (by label,
// missing entries count as 0): nonzero where the link's reflectivity was set explicitly, which
// takes precedence over its surface. result must come from a cast with compute_incidence of pattern
// from world_from_sensor with poses (a sweep's beams are taken from its first pose: the barycentric
// coordinates are recomputed from that pose and clamped into the triangle).
void sampleSurfaces(const Scene& scene, const FramePoses& poses,
                    const Eigen::Isometry3d& world_from_sensor, const ScanPattern& pattern,
                    const ScanResult& result, double reflectance_from_color,
                    const std::vector<char>& label_fixed, SurfaceSamples* out);
// The same for beams off any grid (Caster::castBeams, castBeamsSweep): each beam from its own
// origin along its own direction (beam_list.h), from world_from_sensor (a sweep's first pose).
void sampleSurfaces(const Scene& scene, const FramePoses& poses,
                    const Eigen::Isometry3d& world_from_sensor, const BeamList& beams,
                    const ScanResult& result, double reflectance_from_color,
                    const std::vector<char>& label_fixed, SurfaceSamples* out);
// The same for a bundle's sub-rays (Caster::castBundle's result beam by beam: entry s is sub-ray s
// of bundle.directions()), all from world_from_sensor.
void sampleSurfaces(const Scene& scene, const FramePoses& poses,
                    const Eigen::Isometry3d& world_from_sensor, const SubRayBundle& bundle,
                    const ScanResult& result, double reflectance_from_color,
                    const std::vector<char>& label_fixed, SurfaceSamples* out);

}  // namespace core
}  // namespace laser_raycast
