// What a scan is, in one place: the beams (a fan of azimuths at one or more elevations), the
// triangle test, and what the sensor reports (range limits, min-range policy, noise, intensity).
// Validated once; the ScanPattern, the Caster's configuration and the MeasurementModel's are all made
// from it, so the interval the caster searches always matches the one the measurement model reports.
#pragma once

#include <vector>

#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/measurement_model.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/triangle.h"

namespace laser_raycast {
namespace core {

struct ScanSpec {
  FanSpec fan;  // azimuths: angle_min, angle_max, and angle_increment or samples
  // Elevations (rad, in [-pi/2, pi/2], distinct, any order). Ring r is the r-th lowest, as lidar
  // drivers number rings. {0}: a planar fan (a LaserScan).
  std::vector<double> elevations = {0.0};
  MeasurementConfig output;  // range_min, range_max, min_range_policy, noise, intensity
  TriangleMethod method = TriangleMethod::kWatertight;  // triangle test for meshes
  bool cull_backfaces = false;  // one-sided triangles: a beam reaching a back face passes through

  // Throws std::invalid_argument naming the field and the bad value.
  void validate() const;

  // The elevations in ring order (ascending).
  std::vector<double> ringElevations() const;
  // The beams: one fan per ring, ring-major. Validates first.
  ScanPattern pattern() const;
  // What the caster needs: the search interval follows the min-range policy (pass_through casts
  // from range_min, so nearer surfaces are invisible; the others from 0, so they can be reported as
  // too close), and the incidence angle only when intensities are wanted.
  CastConfig castConfig() const;
};

}  // namespace core
}  // namespace laser_raycast
