// Beams that lie on no grid: each its own direction, origin and time. A non-repetitive scanner's
// pattern read from a file (pattern_file.h), or a calibrated lidar whose lasers each have their own
// elevation, azimuth offset, origin offset and firing time. Caster::castBeams casts them one ray
// at a time with the same exact tests as the grid's walks.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace laser_raycast {
namespace core {

struct BeamList {
  std::vector<Eigen::Vector3d> directions;  // unit, sensor frame
  // Where each beam leaves from, sensor frame (m); empty: every beam from the sensor's origin.
  // Ranges are measured from a beam's own origin.
  std::vector<Eigen::Vector3d> origins;
  // s after the scan's stamp, >= 0; empty: every beam at 0. Used by a rotating cast
  // (Caster::castBeamsSweep) to pick each beam's poses.
  std::vector<double> times;
  std::vector<int> lines;  // a ring or laser line per beam (for the outputs); may be empty

  int size() const { return static_cast<int>(directions.size()); }
  Eigen::Vector3d origin(int i) const {
    return origins.empty() ? Eigen::Vector3d::Zero() : origins[i];
  }
  double time(int i) const { return times.empty() ? 0.0 : times[i]; }
  int line(int i) const { return lines.empty() ? 0 : lines[i]; }

  // Throws std::invalid_argument naming the problem: sizes that differ from directions', a
  // direction that is not finite and unit (within 1e-9), an origin that is not finite, a time that
  // is negative or not finite, more than FanSpec::kMaxBeams beams.
  void validate() const;
  // Appends beam i of other.
  void append(const BeamList& other, int i);
};

// The unit direction at azimuth (counter-clockwise from x) and elevation (up from the xy plane),
// rad, as the grid patterns compute it.
Eigen::Vector3d beamDirection(double azimuth, double elevation);

}  // namespace core
}  // namespace laser_raycast
