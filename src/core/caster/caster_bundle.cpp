// Caster::castBundle: the sub-ray patterns of divergent beams cast in one walk of the scene, and
// SubRayBundle, the patterns made ready for it.
//
// A bundle is cast as a rotating sweep's block whose columns never move (every column's pose the
// sensor's: beams/column_motion.h) but whose beams may turn from the culling pattern's directions
// by the farthest a sub-ray lies from its beam: the walks widen every window by that turn (the
// Spread of beams/beam_window.h), and wherever they would test a beam they test each of its
// sub-rays exactly as a cast of the sub-ray's pattern tests it (BeamSet::Bundle), each keeping its
// own nearest hit. So each result is that cast's, and the walk through the trees, the windows and
// the occlusion culling are paid once for all the sub-rays. The walks keep a beam's sub-rays side
// by side (BeamSet: sub-ray k of beam i at i * sub-rays + k), as a SubRayBundle holds their
// directions and its cast returns them; the patterns' form copies them in and out.
#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "caster/caster_state.h"
#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/pose.h"
#include "laser_raycast/core/sub_ray_bundle.h"
#include "walk/frame_walk.h"

namespace laser_raycast {
namespace core {
namespace {

// Throws std::invalid_argument unless the patterns can be cast as a bundle.
void checkBundle(const std::vector<ScanPattern>& patterns) {
  std::ostringstream msg;
  if (patterns.empty()) {
    msg << "castBundle: no patterns";
  } else {
    const ScanPattern& first = patterns.front();
    std::vector<int> order, order_k;
    ringsByElevation(first, &order);
    for (std::size_t k = 0; k < patterns.size() && msg.str().empty(); ++k) {
      const ScanPattern& p = patterns[k];
      if (p.planar()) {
        msg << "castBundle: pattern " << k << " is planar (a bundle is cast in 3D; cast a planar "
            << "fan's sub-rays one pattern at a time)";
      } else if (p.ringCount() != first.ringCount() || p.azimuthCount() != first.azimuthCount()) {
        msg << "castBundle: pattern " << k << " has " << p.ringCount() << " rings x "
            << p.azimuthCount() << " azimuths, pattern 0 " << first.ringCount() << " x "
            << first.azimuthCount();
      } else {
        ringsByElevation(p, &order_k);
        if (order_k != order) {
          msg << "castBundle: pattern " << k << "'s rings are not in pattern 0's order";
        }
      }
    }
  }
  if (!msg.str().empty()) throw std::invalid_argument(msg.str());
}

// The farthest any beam of a pattern lies from the culling pattern's beam at its row and column:
// a beam at azimuth A + a, elevation E + e is within |e| + |a| of the one at (A, E) (along a
// meridian by |e|, then along a parallel, whose arc |a| cos is at most |a|). The azimuth offset of
// column c is the difference of the two fans' azimuths, the same for every column but for rounding.
double bundleTurn(const std::vector<ScanPattern>& patterns) {
  const ScanPattern& first = patterns.front();
  double turn = 0;
  for (const ScanPattern& p : patterns) {
    const double azimuth = std::max(std::abs(p.angleMin() - first.angleMin()),
                                    std::abs(p.angleMax() - first.angleMax()));
    double elevation = 0;
    for (int r = 0; r < first.ringCount(); ++r) {
      elevation = std::max(elevation, std::abs(p.elevations()[r] - first.elevations()[r]));
    }
    turn = std::max(turn, azimuth + elevation);
  }
  return turn * (1 + 1e-9);
}

}  // namespace

SubRayBundle::SubRayBundle(std::vector<ScanPattern> patterns) : patterns_(std::move(patterns)) {
  checkBundle(patterns_);
  turn_ = bundleTurn(patterns_);
  const std::size_t n = beams(), k_count = patterns_.size();
  directions_.resize(n * k_count);
  for (std::size_t k = 0; k < k_count; ++k) {
    const std::vector<Eigen::Vector3d>& d = patterns_[k].directions();
    for (std::size_t i = 0, s = k; i < n; ++i, s += k_count) directions_[s] = d[i];
  }
}

const ScanResult& Caster::castBundle(const Scene& scene, const FramePoses& poses,
                                     const Eigen::Isometry3d& world_from_sensor,
                                     const std::shared_ptr<const SubRayBundle>& sub_rays,
                                     const CastConfig& config) {
  if (!sub_rays) throw std::invalid_argument("castBundle: the bundle is null");
  config.validate();
  checkFramePoses(scene, poses);
  forget();  // result_ is only the bundle's culling ranges now
  const ScanPattern& culling = sub_rays->patterns().front();
  const bool sensor_ok = isValidPose(world_from_sensor);
  const int bodies = static_cast<int>(scene.bodies().size());
  ScanResult& out = state_->bundle_result;
  resetResult(static_cast<int>(sub_rays->directions().size()), bodies, sensor_ok,
              config.compute_incidence, &out);
  resetResult(culling.size(), bodies, sensor_ok, false, &result_);
  if (!sensor_ok) return out;

  const ReuseKey key = relativeInputs(scene, poses, world_from_sensor, culling, config);
  state_->placeGroups(scene, key, culling, &state_->placed, &result_.stats.bodies_skipped);
  const ColumnMotion motion(
      0, std::vector<Eigen::Isometry3d>(culling.azimuthCount(), Eigen::Isometry3d::Identity()),
      steepestElevation(culling), sub_rays->turn());
  BeamSet::Bundle bundle;
  bundle.from_origin = true;
  bundle.per_beam = sub_rays->subRays();
  bundle.directions = &sub_rays->directions();
  bundle.result = &out;
  bundle.owner = sub_rays;
  state_->castOnThreads(
      scene, culling, config, &result_,
      [&](const BeamRect& within) {
        for (const PlacedGroup& p : state_->placed) {
          walkFrame(state_->beams, scene, *p.group, *p.sensor_from_frame, config, within,
                    &state_->cast, &motion);
        }
      },
      &bundle);
  out.stats = result_.stats;
  if (config.compute_incidence) computeIncidence(sub_rays->directions(), &out);
  return out;
}

const std::vector<ScanResult>& Caster::castBundle(const Scene& scene, const FramePoses& poses,
                                                  const Eigen::Isometry3d& world_from_sensor,
                                                  const std::vector<ScanPattern>& patterns,
                                                  const CastConfig& config) {
  const auto sub_rays = std::make_shared<const SubRayBundle>(patterns);
  const ScanResult& all = castBundle(scene, poses, world_from_sensor, sub_rays, config);
  const std::size_t n = sub_rays->beams(), k_count = patterns.size();
  std::vector<ScanResult>& results = state_->bundle;
  results.resize(k_count);
  for (std::size_t k = 0; k < k_count; ++k) {
    ScanResult& r = results[k];
    r.range.resize(n);
    r.body.resize(n);
    r.triangle.resize(n);
    r.normal.resize(all.normal.empty() ? 0 : n);
    r.cos_incidence.resize(all.cos_incidence.empty() ? 0 : n);
    for (std::size_t i = 0, s = k; i < n; ++i, s += k_count) {
      r.range[i] = all.range[s];
      r.body[i] = all.body[s];
      r.triangle[i] = all.triangle[s];
      if (!all.normal.empty()) r.normal[i] = all.normal[s];
      if (!all.cos_incidence.empty()) r.cos_incidence[i] = all.cos_incidence[s];
    }
    r.stats = all.stats;
  }
  return results;
}

}  // namespace core
}  // namespace laser_raycast
