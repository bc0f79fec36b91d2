// The second method for Caster::castSweep: each azimuth column cast on its own by Caster::cast, as a
// two-azimuth fan whose first azimuth is the column's (the same directions bit for bit), from the
// sensor and frame poses at the column's time. Slow and plain: what the blocks of a sweep must
// agree with.
#pragma once

#include <limits>
#include <vector>

#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/pose_samples.h"

namespace laser_raycast_test {

namespace core = laser_raycast::core;

inline core::ScanResult sweepByColumns(const core::Scene& scene, const core::PoseSamples& samples,
                                       const core::ScanPattern& pattern,
                                       const core::CastConfig& config, double time_increment) {
  const int azimuths = pattern.azimuthCount(), rings = pattern.ringCount();
  core::ScanResult out;
  out.range.assign(pattern.size(), std::numeric_limits<double>::quiet_NaN());
  out.body.assign(pattern.size(), -1);
  out.triangle.assign(pattern.size(), -1);
  out.normal.assign(pattern.size(), Eigen::Vector3d::Zero());
  out.cos_incidence.assign(pattern.size(), 0.0);
  core::FramePoses frames;
  for (int c = 0; c < azimuths; ++c) {
    const double t = c * time_increment;
    samples.framesAt(t, &frames);
    core::FanSpec column;
    column.angle_min = pattern.azimuth(c);
    column.angle_max = pattern.azimuth(c) + pattern.angleIncrement();
    column.samples = 2;
    const core::ScanPattern one(column, pattern.elevations());
    core::Caster caster;
    const core::ScanResult& r = caster.cast(scene, frames, samples.sensorAt(t), one, config);
    for (int ring = 0; ring < rings; ++ring) {
      const int from = ring * 2, to = ring * azimuths + c;
      out.range[to] = r.range[from];
      out.body[to] = r.body[from];
      out.triangle[to] = r.triangle[from];
      if (!r.normal.empty()) out.normal[to] = r.normal[from];
      if (!r.cos_incidence.empty()) out.cos_incidence[to] = r.cos_incidence[from];
    }
  }
  return out;
}

}  // namespace laser_raycast_test
