// The sub-rays of divergent beams as the caster casts them scan after scan (Caster::castBundle):
// the sub-ray patterns (returns.h: subRayPatterns, each the same rings and azimuths shifted a
// little), checked once, and all their directions beam by beam. Made once and then only read, so a
// caster handed the same bundle again casts from its directions as they are.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "laser_raycast/core/scan_pattern.h"

namespace laser_raycast {
namespace core {

class SubRayBundle {
 public:
  // Sub-ray k of each beam is the beam at the same (ring, column) of patterns[k]; patterns[0] is
  // the one the walks cull by. Throws std::invalid_argument for patterns that are empty, planar
  // or of other rings, azimuths or ring order than patterns[0].
  explicit SubRayBundle(std::vector<ScanPattern> patterns);

  const std::vector<ScanPattern>& patterns() const { return patterns_; }
  // Sub-rays a beam (the number of patterns), and beams (each pattern's).
  int subRays() const { return static_cast<int>(patterns_.size()); }
  std::size_t beams() const { return patterns_.front().size(); }
  // Every sub-ray's unit direction in the sensor frame, beam by beam: sub-ray k of beam i (pattern
  // k's beam i) at i * subRays() + k.
  const std::vector<Eigen::Vector3d>& directions() const { return directions_; }
  // The farthest a sub-ray turns from patterns[0]'s beam at its ring and column (rad), a little
  // more for rounding: what the walks widen their windows by.
  double turn() const { return turn_; }

 private:
  std::vector<ScanPattern> patterns_;
  std::vector<Eigen::Vector3d> directions_;
  double turn_ = 0;
};

}  // namespace core
}  // namespace laser_raycast
