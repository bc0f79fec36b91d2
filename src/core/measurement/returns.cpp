// A pulse's returns from a divergent beam (returns.h).
#include "laser_raycast/core/returns.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace laser_raycast {
namespace core {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// One sub-ray's hit: its range and power share, and what it hit.
struct SubHit {
  double range;
  double rho_cos;  // weight x reflectance x cos(incidence)
  int body, triangle, sub;
};

// A return: sub-ray hits merged.
struct Return {
  double range = 0, rho_cos = 0, power = 0;
  int body = -1, triangle = -1;
  double best = -1;  // the largest member's rho_cos: it names the body and triangle
};

void setReturn(const Return& r, std::size_t beam, ScanResult* result, SurfaceSamples* surface) {
  result->range[beam] = r.range;
  result->body[beam] = r.body;
  result->triangle[beam] = r.triangle;
  result->cos_incidence[beam] = r.body >= 0 ? 1.0 : 0.0;
  surface->reflectance[beam] = r.rho_cos;
  surface->cos_incidence[beam] = result->cos_incidence[beam];
}

void resetResult(std::size_t n, ScanResult* result, SurfaceSamples* surface) {
  result->range.assign(n, kInf);
  result->body.assign(n, -1);
  result->triangle.assign(n, -1);
  result->normal.clear();
  result->cos_incidence.assign(n, 0.0);
  result->stats = CastStats{};
  surface->reflectance.assign(n, std::numeric_limits<double>::quiet_NaN());
  surface->cos_incidence.assign(n, 0.0);
}

// subRayPatterns(fan, elevations, returns), built again only if one of them changed since the last
// call with `kept`.
const std::vector<ScanPattern>& keptSubRayPatterns(const FanSpec& fan,
                                                   const std::vector<double>& elevations,
                                                   const ReturnsConfig& returns,
                                                   PulseReturns::SubRays* kept) {
  const bool same_fan = kept->fan.angle_min == fan.angle_min &&
                        kept->fan.angle_max == fan.angle_max &&
                        kept->fan.angle_increment == fan.angle_increment &&
                        kept->fan.samples == fan.samples;
  if (!(same_fan && kept->elevations == elevations &&
        kept->divergence == returns.beam_divergence && kept->samples == returns.beam_samples)) {
    kept->patterns = subRayPatterns(fan, elevations, returns);
    kept->fan = fan;
    kept->elevations = elevations;
    kept->divergence = returns.beam_divergence;
    kept->samples = returns.beam_samples;
  }
  return kept->patterns;
}

}  // namespace

void ReturnsConfig::validate() const {
  std::ostringstream msg;
  if (!(std::isfinite(beam_divergence) && beam_divergence >= 0 && beam_divergence < 0.5)) {
    msg << "beam_divergence must be finite, >= 0 and < 0.5 rad, got " << beam_divergence;
  } else if (beam_samples < 1 || beam_samples > 64) {
    msg << "beam_samples must be in [1, 64], got " << beam_samples;
  } else if (!(std::isfinite(min_return_separation) && min_return_separation >= 0)) {
    msg << "min_return_separation must be finite and >= 0 m, got " << min_return_separation;
  }
  if (!msg.str().empty()) throw std::invalid_argument(msg.str());
}

Eigen::Vector2d ReturnsConfig::offset(int k) const {
  if (k == 0) return Eigen::Vector2d::Zero();
  const double angle = 2 * M_PI * (k - 1) / (beam_samples - 1);
  const double radius = beam_divergence / 3;
  return Eigen::Vector2d(radius * std::cos(angle), radius * std::sin(angle));
}

std::vector<ScanPattern> subRayPatterns(const FanSpec& fan, const std::vector<double>& elevations,
                                        const ReturnsConfig& returns) {
  std::vector<ScanPattern> patterns;
  patterns.reserve(returns.beam_samples);
  for (int k = 0; k < returns.beam_samples; ++k) {
    const Eigen::Vector2d offset = returns.offset(k);
    FanSpec shifted = fan;
    shifted.angle_min += offset.x();
    shifted.angle_max += offset.x();
    std::vector<double> rings = elevations;
    // Clamped at the poles: a sub-ray cannot lean past straight up or down.
    for (double& e : rings) e = std::clamp(e + offset.y(), -M_PI / 2, M_PI / 2);
    patterns.emplace_back(shifted, rings);
  }
  return patterns;
}

void castReturns(Caster* caster, const Scene& scene, const FramePoses& poses,
                 const Eigen::Isometry3d& world_from_sensor, const FanSpec& fan,
                 const std::vector<double>& elevations, const CastConfig& config,
                 const ReturnsConfig& returns, const std::vector<double>& reflectivity,
                 const std::vector<char>& label_fixed, double reflectance_from_color,
                 bool surface_reflectance, PulseReturns* out) {
  returns.validate();
  CastConfig cast = config;
  cast.compute_incidence = true;
  const int samples = returns.beam_samples;
  const double weight = 1.0 / samples;
  std::size_t n = 0;
  // Beam i's sub-ray hits: hits[i * samples, i * samples + hit_count[i]).
  std::vector<SubHit> hits;
  std::vector<int> hit_count;
  SurfaceSamples surface;
  const std::vector<ScanPattern>& patterns =
      keptSubRayPatterns(fan, elevations, returns, &out->sub_rays);
  // A 3D pattern's sub-rays are cast as one bundle (Caster::castBundle: the same results as a cast
  // of each pattern, in one walk of the scene); a planar fan's (whose sub-rays leave its plane)
  // one pattern at a time.
  bool bundled = samples > 1;
  for (const ScanPattern& p : patterns) bundled = bundled && !p.planar();
  const std::vector<ScanResult>* bundle =
      bundled ? &caster->castBundle(scene, poses, world_from_sensor, patterns, cast) : nullptr;
  for (int k = 0; k < samples; ++k) {
    const ScanPattern& pattern = patterns[k];
    const ScanResult& result =
        bundle ? (*bundle)[k] : caster->cast(scene, poses, world_from_sensor, pattern, cast);
    if (k == 0) {
      n = result.range.size();
      hits.resize(n * samples);
      hit_count.assign(n, 0);
    }
    if (surface_reflectance) {
      sampleSurfaces(scene, poses, world_from_sensor, pattern, result, reflectance_from_color,
                     label_fixed, &surface);
    }
    for (std::size_t i = 0; i < n; ++i) {
      const int body = result.body[i];
      if (body < 0 || !std::isfinite(result.range[i])) continue;
      const int label = scene.bodies()[body].label;
      double rho = label < static_cast<int>(reflectivity.size()) ? reflectivity[label] : 1.0;
      double cos_incidence = result.cos_incidence[i];
      if (surface_reflectance) {
        if (!std::isnan(surface.reflectance[i])) rho = surface.reflectance[i];
        cos_incidence = surface.cos_incidence[i];
      }
      hits[i * samples + hit_count[i]++] = {result.range[i], weight * rho * cos_incidence, body,
                                            result.triangle[i], k};
    }
  }
  resetResult(n, &out->first, &out->first_surface);
  resetResult(n, &out->second, &out->second_surface);
  std::vector<Return> groups;
  for (std::size_t i = 0; i < n; ++i) {
    if (hit_count[i] == 0) continue;
    const auto begin = hits.begin() + i * samples, end = begin + hit_count[i];
    // By range, ties by sub-ray: the same order on every run.
    std::sort(begin, end, [](const SubHit& a, const SubHit& b) {
      return a.range < b.range || (a.range == b.range && a.sub < b.sub);
    });
    groups.clear();
    double group_start = 0;
    for (auto it = begin; it != end; ++it) {
      const SubHit& s = *it;
      if (groups.empty() || s.range - group_start > returns.min_return_separation) {
        groups.emplace_back();
        group_start = s.range;
      }
      Return& g = groups.back();
      // Power-weighted range; a member of zero power (black, or grazing) still counts a little, so
      // that a group of only such hits has a range.
      const double w = s.rho_cos / (s.range * s.range) + 1e-300;
      g.range += w * s.range;
      g.power += w;
      g.rho_cos += s.rho_cos;
      if (s.rho_cos > g.best) {
        g.best = s.rho_cos;
        g.body = s.body;
        g.triangle = s.triangle;
      }
    }
    for (Return& g : groups) g.range /= g.power;
    // The received power of a return: its rho cos over its range squared.
    auto power = [](const Return& g) { return g.rho_cos / (g.range * g.range); };
    std::size_t strongest = 0;
    for (std::size_t g = 1; g < groups.size(); ++g) {
      if (power(groups[g]) > power(groups[strongest])) strongest = g;
    }
    const std::size_t last = groups.size() - 1;
    switch (returns.return_mode) {
      case ReturnMode::kStrongest:
        setReturn(groups[strongest], i, &out->first, &out->first_surface);
        break;
      case ReturnMode::kLast:
        setReturn(groups[last], i, &out->first, &out->first_surface);
        break;
      case ReturnMode::kFirst:
        setReturn(groups[0], i, &out->first, &out->first_surface);
        break;
      case ReturnMode::kDual:
        setReturn(groups[strongest], i, &out->first, &out->first_surface);
        if (last != strongest) setReturn(groups[last], i, &out->second, &out->second_surface);
        break;
    }
  }
}

}  // namespace core
}  // namespace laser_raycast
