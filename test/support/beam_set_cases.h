// Beam sets as the walk's conservative pieces are tested against: a fresh one over a pattern,
// and a sweep block's random column poses (test_beam_views, test_candidate_filters).
#pragma once

#include <Eigen/Geometry>
#include <limits>
#include <vector>

#include "beams/beam_set.h"
#include "beams/column_motion.h"
#include "laser_raycast/core/cast_config.h"
#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/scan_result.h"
#include "random.h"

namespace laser_raycast_test {

// A sweep block's columns: each a random pose at most `shift` m and `turn` rad from the reference.
// steepest: the pattern's (steepestElevation, column_motion.h).
inline laser_raycast::core::ColumnMotion randomColumns(Rng& rng, int cols, double shift,
                                                       double turn, double steepest) {
  std::vector<Eigen::Isometry3d> m(cols);
  for (Eigen::Isometry3d& p : m) {
    p = Eigen::Isometry3d::Identity();
    p.linear() =
        Eigen::AngleAxisd(turn * uniform(rng, 0, 1), randomUnitVector(rng)).toRotationMatrix();
    p.translation() = shift * uniform(rng, 0, 1) * randomUnitVector(rng);
  }
  return laser_raycast::core::ColumnMotion(0, m, steepest);
}

// A beam set over a pattern with no hits yet, as a cast starts it.
struct FreshBeams {
  laser_raycast::core::ScanResult result;
  laser_raycast::core::BeamSet beams;
  FreshBeams(const laser_raycast::core::ScanPattern& pattern,
             const laser_raycast::core::CastConfig& config) {
    result.range.assign(pattern.size(), std::numeric_limits<double>::infinity());
    result.body.assign(pattern.size(), -1);
    result.triangle.assign(pattern.size(), -1);
    beams.reset(pattern, config, &result);
  }
};

}  // namespace laser_raycast_test
