// A pulse's returns from a divergent beam: each beam of a pattern is cast as sub-rays over its
// footprint, and their hits, weighted by the footprint and the radiometry (rho cos(theta) / r^2),
// are grouped by range into returns, of which the return mode keeps one or two. Built on casts of
// ordinary grid patterns (each sub-ray offset is the whole pattern shifted in azimuth and
// elevation), so every fast path of the caster applies.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/enum_names.h"
#include "laser_raycast/core/sub_ray_bundle.h"
#include "laser_raycast/core/surface_reflectance.h"

namespace laser_raycast {
namespace core {

enum class ReturnMode {
  kStrongest,  // "strongest": the return of the largest received power
  kLast,       // "last": the farthest return
  kFirst,      // "first": the nearest return
  kDual,       // "dual": the strongest and the last (one if they are the same), as VLP-16 reports
};
inline const EnumNames<ReturnMode, 4> kReturnModeNames{{{
    {ReturnMode::kStrongest, "strongest"},
    {ReturnMode::kLast, "last"},
    {ReturnMode::kFirst, "first"},
    {ReturnMode::kDual, "dual"},
}}};

struct ReturnsConfig {
  double beam_divergence = 0.0;  // rad, full angle of the footprint, >= 0
  // Sub-rays a beam, >= 1: 1 is the ideal ray (no divergence used); otherwise one at the beam's
  // centre and samples - 1 equally spaced on a circle of radius beam_divergence / 3 (in azimuth and
  // elevation angles), the first at zero elevation offset and positive azimuth offset. Each
  // carries an equal share of the pulse's power.
  int beam_samples = 1;
  ReturnMode return_mode = ReturnMode::kStrongest;
  // m, >= 0: sub-ray hits closer in range than this to the nearest hit of a return merge into it,
  // at their power-weighted mean range (a mixed pixel).
  double min_return_separation = 0.0;

  // Throws std::invalid_argument naming the field and its value.
  void validate() const;
  // The (azimuth, elevation) offset of sub-ray k, rad.
  Eigen::Vector2d offset(int k) const;
};

// One or two returns per beam, as casts of pattern give them: first (the mode's return, or in dual
// mode the strongest) and second (dual mode only: the last, where it differs from the strongest;
// elsewhere no hit). Each is a ScanResult of the pattern (range, body, triangle, cos_incidence
// 1) with SurfaceSamples whose reflectance is the return's share of the footprint times its
// surfaces' rho cos(theta) and whose cos_incidence is 1: MeasurementModel::measure then gives the
// intensity and applies the detection range to the return's power.
struct PulseReturns {
  ScanResult first, second;
  SurfaceSamples first_surface, second_surface;
  // The sub-ray patterns of the last call, which the next with the same fan, rings and footprint
  // reuses (building them works out every sub-ray's direction): a 3D pattern's divergent beams'
  // as one bundle (Caster::castBundle), the others' (a planar fan's, the ideal ray's) as patterns
  // cast one at a time; the other of the two is empty.
  struct SubRays {
    FanSpec fan;
    std::vector<double> elevations;
    double divergence = 0;
    int samples = 0;
    std::vector<ScanPattern> patterns;
    std::shared_ptr<const SubRayBundle> bundle;
  } sub_rays;
};

// The pattern of each sub-ray k of returns (returns.offset(k)): (fan, elevations) shifted by its
// azimuth and elevation offsets, the elevations clamped at the poles.
std::vector<ScanPattern> subRayPatterns(const FanSpec& fan, const std::vector<double>& elevations,
                                        const ReturnsConfig& returns);

// Casts the beam_samples shifted patterns from world_from_sensor and forms the returns. The
// reflectance of each sub-ray hit is the surface's (sampleSurfaces, with reflectance_from_color and
// label_fixed) where it gives one, else reflectivity[label] (missing entries 1). config's
// compute_incidence is forced on.
void castReturns(Caster* caster, const Scene& scene, const FramePoses& poses,
                 const Eigen::Isometry3d& world_from_sensor, const FanSpec& fan,
                 const std::vector<double>& elevations, const CastConfig& config,
                 const ReturnsConfig& returns, const std::vector<double>& reflectivity,
                 const std::vector<char>& label_fixed, double reflectance_from_color,
                 bool surface_reflectance, PulseReturns* out);

}  // namespace core
}  // namespace laser_raycast
