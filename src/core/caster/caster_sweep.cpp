// Caster::castSweep: a rotating scan, each azimuth column cast from the poses at its own time.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "laser_raycast/core/caster.h"

namespace laser_raycast {
namespace core {

const ScanResult& Caster::castSweep(const Scene& scene, const PoseSamples& samples,
                                    const ScanPattern& pattern, const CastConfig& config,
                                    double time_increment) {
  config.validate();
  samples.validate(scene);
  if (!(std::isfinite(time_increment) && time_increment >= 0)) {
    std::ostringstream msg;
    msg << "time_increment must be finite and >= 0 s, got " << time_increment;
    throw std::invalid_argument(msg.str());
  }
  // Each column is cast on its own, as a two-azimuth fan whose first azimuth is the column's (the
  // same angle, so the same directions bit for bit), from the poses at its time.
  const int azimuths = pattern.azimuthCount(), rings = pattern.ringCount();
  const int beams = pattern.size();
  const bool with_normals = config.compute_incidence;
  ScanResult out;
  out.range.assign(beams, std::numeric_limits<double>::quiet_NaN());
  out.body.assign(beams, -1);
  out.triangle.assign(beams, -1);
  if (with_normals) {
    out.normal.assign(beams, Eigen::Vector3d::Zero());
    out.cos_incidence.assign(beams, 0.0);
  }
  out.stats.bodies = static_cast<int>(scene.bodies().size());
  Caster column_caster;
  FramePoses frames;
  for (int c = 0; c < azimuths; ++c) {
    const double t = c * time_increment;
    samples.framesAt(t, &frames);
    FanSpec column;
    column.angle_min = pattern.azimuth(c);
    column.angle_max = pattern.azimuth(c) + pattern.angleIncrement();
    column.samples = 2;
    const ScanPattern one(column, pattern.elevations());
    const ScanResult& r = column_caster.cast(scene, frames, samples.sensorAt(t), one, config);
    for (int ring = 0; ring < rings; ++ring) {
      const int from = ring * 2, to = ring * azimuths + c;
      out.range[to] = r.range[from];
      out.body[to] = r.body[from];
      out.triangle[to] = r.triangle[from];
      if (with_normals) {
        out.normal[to] = r.normal[from];
        out.cos_incidence[to] = r.cos_incidence[from];
      }
    }
    out.stats.bodies_skipped = std::max(out.stats.bodies_skipped, r.stats.bodies_skipped);
  }
  forget();  // a sweep is never reused, and the last single cast is not this one
  result_ = std::move(out);
  return result_;
}

}  // namespace core
}  // namespace laser_raycast
