// What a cast gives: per beam, the nearest hit's distance, body and triangle, and what the cast
// skipped.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace laser_raycast {
namespace core {

struct CastStats {
  int bodies = 0;          // bodies in the scene
  int bodies_skipped = 0;  // frame pose unknown this scan
  // Bodies not cast against: beyond the range, outside the pattern's windows, off the scan plane
  // (planar fans), or hidden behind nearer hits.
  int bodies_culled = 0;
  bool reused = false;  // nothing moved relative to the sensor: the previous geometry was returned
  // Planar fans: frames cast through a kept slice of their bodies by the scan plane
  // (kept_slice.h).
  int kept_slices = 0;
};

struct ScanResult {
  std::vector<double> range;  // m; +inf: no hit in [tmin, tmax]; NaN: the beam could not be cast
  std::vector<int> body;      // index of the body hit, -1 for none
  std::vector<int> triangle;  // the triangle hit on a mesh body, -1 for a primitive or no hit
  // Filled only with CastConfig::compute_incidence (else empty):
  std::vector<Eigen::Vector3d> normal;  // unit normal at the hit, sensor frame (zero if no hit):
                                        // a mesh triangle's front normal, a primitive's outward one
  std::vector<double> cos_incidence;    // |cos| of the beam's angle to that normal (0 if no hit)
  CastStats stats;
};

}  // namespace core
}  // namespace laser_raycast
