// Beam lists cast one ray at a time, as the oracle of the grids' and the cells' walks
// (test_caster_beam_grid, test_caster_beam_cells): a list shuffled (which lies on no grid), cast
// in lists too short for cells, and two results compared beam by beam.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <vector>

#include "beams/beam_cells.h"
#include "cast_reference.h"
#include "laser_raycast/core/beam_list.h"
#include "laser_raycast/core/caster.h"
#include "random_scene.h"

namespace laser_raycast_test {

// The list's beams in a random order (beam k of the result is beams' order[k]).
inline core::BeamList shuffled(const core::BeamList& beams, Rng& rng, std::vector<int>* order) {
  order->resize(beams.size());
  std::iota(order->begin(), order->end(), 0);
  std::shuffle(order->begin(), order->end(), rng);
  core::BeamList out;
  for (int i : *order) out.append(beams, i);
  return out;
}

// castBeams of beams one ray at a time: in lists shorter than the cells take (kMinCellBeams), each
// cast by caster; beams must lie on no grid (a shuffled list).
inline core::ScanResult rayByRay(core::Caster& caster, const RandomScene& s,
                                 const Eigen::Isometry3d& sensor, const core::BeamList& beams,
                                 const core::CastConfig& c) {
  core::ScanResult out;
  for (int start = 0; start < beams.size(); start += core::kMinCellBeams - 1) {
    core::BeamList part;
    for (int i = start; i < std::min(beams.size(), start + core::kMinCellBeams - 1); ++i) {
      part.append(beams, i);
    }
    const core::ScanResult& r = caster.castBeams(s.scene, s.poses, sensor, part, c);
    out.range.insert(out.range.end(), r.range.begin(), r.range.end());
    out.body.insert(out.body.end(), r.body.begin(), r.body.end());
    out.triangle.insert(out.triangle.end(), r.triangle.begin(), r.triangle.end());
    out.normal.insert(out.normal.end(), r.normal.begin(), r.normal.end());
    out.cos_incidence.insert(out.cos_incidence.end(), r.cos_incidence.begin(),
                             r.cos_incidence.end());
  }
  return out;
}

// a (in the list's order) against b (its beams shuffled: b's beam k is a's order[k]): the same
// bodies and triangles, and ranges bit for bit with normals and incidence (tolerance 0) or ranges
// within tolerance (relative); the first five differences are reported.
inline void expectSameResult(const core::ScanResult& a, const core::ScanResult& b,
                             const std::vector<int>& order, double tolerance) {
  int differing = 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const int i = order[k];
    const bool same_range = tolerance == 0 ? a.range[i] == b.range[k]
                                           : near(a.range[i], b.range[k], tolerance);
    const bool same = same_range && a.body[i] == b.body[k] && a.triangle[i] == b.triangle[k] &&
                      (tolerance > 0 || (a.normal[i] == b.normal[k] &&
                                         a.cos_incidence[i] == b.cos_incidence[k]));
    if (!same && differing++ < 5) {
      ADD_FAILURE() << "beam " << i << ": range " << a.range[i] << " vs " << b.range[k]
                    << ", body " << a.body[i] << " vs " << b.body[k] << ", triangle "
                    << a.triangle[i] << " vs " << b.triangle[k];
    }
  }
  EXPECT_EQ(differing, 0);
}

}  // namespace laser_raycast_test
