// A pulse's returns from a divergent beam (returns.h).
#include "laser_raycast/core/returns.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <utility>

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

// The sub-rays of (fan, elevations, returns) in *kept, made again only if one of them changed
// since the last call with `kept`: a 3D pattern's divergent beams as one bundle, else patterns.
void keepSubRays(const FanSpec& fan, const std::vector<double>& elevations,
                 const ReturnsConfig& returns, PulseReturns::SubRays* kept) {
  const bool same_fan = kept->fan.angle_min == fan.angle_min &&
                        kept->fan.angle_max == fan.angle_max &&
                        kept->fan.angle_increment == fan.angle_increment &&
                        kept->fan.samples == fan.samples;
  if (same_fan && kept->elevations == elevations && kept->divergence == returns.beam_divergence &&
      kept->samples == returns.beam_samples && (kept->bundle || !kept->patterns.empty())) {
    return;
  }
  std::vector<ScanPattern> patterns = subRayPatterns(fan, elevations, returns);
  // A 3D pattern's sub-rays are cast as one bundle (Caster::castBundle: the same results as a cast
  // of each pattern, in one walk of the scene); a planar fan's (whose sub-rays leave its plane)
  // one pattern at a time.
  bool bundled = returns.beam_samples > 1;
  for (const ScanPattern& p : patterns) bundled = bundled && !p.planar();
  kept->bundle.reset();
  kept->patterns.clear();
  if (bundled) {
    kept->bundle = std::make_shared<const SubRayBundle>(std::move(patterns));
  } else {
    kept->patterns = std::move(patterns);
  }
  kept->fan = fan;
  kept->elevations = elevations;
  kept->divergence = returns.beam_divergence;
  kept->samples = returns.beam_samples;
}

// A beam's returns from its sub-ray hits [begin, end) (reordered), written at beam i of out's
// results by the return mode; groups: room for the returns.
void setBeamReturns(SubHit* begin, SubHit* end, const ReturnsConfig& returns, std::size_t i,
                    std::vector<Return>* groups_out, PulseReturns* out) {
  std::vector<Return>& groups = *groups_out;
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

// Casts each of patterns on its own (a planar fan's sub-rays, or the ideal ray) and gathers the
// results, with their surfaces where asked, beam by beam as a bundle's cast gives them (sub-ray k
// of beam i at i * patterns.size() + k): ranges, bodies, triangles, incidence. Returns the beams.
std::size_t castEachPattern(Caster* caster, const Scene& scene, const FramePoses& poses,
                            const Eigen::Isometry3d& world_from_sensor,
                            const std::vector<ScanPattern>& patterns, const CastConfig& cast,
                            bool surface_reflectance, double reflectance_from_color,
                            const std::vector<char>& label_fixed, ScanResult* gathered_out,
                            SurfaceSamples* surface_out) {
  ScanResult& gathered = *gathered_out;
  SurfaceSamples& surface = *surface_out;
  const int samples = static_cast<int>(patterns.size());
  std::size_t n = 0;
  SurfaceSamples one_surface;
  for (int k = 0; k < samples; ++k) {
    const ScanPattern& pattern = patterns[k];
    const ScanResult& result = caster->cast(scene, poses, world_from_sensor, pattern, cast);
    if (k == 0) {
      n = result.range.size();
      gathered.range.resize(n * samples);
      gathered.body.resize(n * samples);
      gathered.triangle.resize(n * samples);
      gathered.cos_incidence.resize(n * samples);
      if (surface_reflectance) {
        surface.reflectance.resize(n * samples);
        surface.cos_incidence.resize(n * samples);
      }
    }
    if (surface_reflectance) {
      sampleSurfaces(scene, poses, world_from_sensor, pattern, result, reflectance_from_color,
                     label_fixed, &one_surface);
    }
    for (std::size_t i = 0, s = k; i < n; ++i, s += samples) {
      gathered.range[s] = result.range[i];
      gathered.body[s] = result.body[i];
      gathered.triangle[s] = result.triangle[i];
      // (An invalid sensor pose leaves no hit and no incidence.)
      gathered.cos_incidence[s] = result.body[i] >= 0 ? result.cos_incidence[i] : 0.0;
      if (surface_reflectance) {
        surface.reflectance[s] = one_surface.reflectance[i];
        surface.cos_incidence[s] = one_surface.cos_incidence[i];
      }
    }
  }
  return n;
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
  keepSubRays(fan, elevations, returns, &out->sub_rays);
  const PulseReturns::SubRays& sub_rays = out->sub_rays;
  // Every sub-ray's hit beam by beam (sub-ray k of beam i at i * samples + k), as a bundle's cast
  // gives them, and its surface where asked.
  std::size_t n = 0;
  const ScanResult* all = nullptr;
  SurfaceSamples surface;
  ScanResult gathered;
  if (sub_rays.bundle) {
    all = &caster->castBundle(scene, poses, world_from_sensor, sub_rays.bundle, cast);
    n = sub_rays.bundle->beams();
    if (surface_reflectance) {
      sampleSurfaces(scene, poses, world_from_sensor, *sub_rays.bundle, *all,
                     reflectance_from_color, label_fixed, &surface);
    }
  } else {
    n = castEachPattern(caster, scene, poses, world_from_sensor, sub_rays.patterns, cast,
                        surface_reflectance, reflectance_from_color, label_fixed, &gathered,
                        &surface);
    all = &gathered;
  }
  resetResult(n, &out->first, &out->first_surface);
  resetResult(n, &out->second, &out->second_surface);
  const double weight = 1.0 / samples;
  SubHit hits[64];  // a beam's (ReturnsConfig::validate: at most 64 sub-rays)
  std::vector<Return> groups;
  for (std::size_t i = 0; i < n; ++i) {
    int hit_count = 0;
    for (int k = 0; k < samples; ++k) {
      const std::size_t s = i * samples + k;
      const int body = all->body[s];
      if (body < 0 || !std::isfinite(all->range[s])) continue;
      const int label = scene.bodies()[body].label;
      double rho = label < static_cast<int>(reflectivity.size()) ? reflectivity[label] : 1.0;
      double cos_incidence = all->cos_incidence[s];
      if (surface_reflectance) {
        if (!std::isnan(surface.reflectance[s])) rho = surface.reflectance[s];
        cos_incidence = surface.cos_incidence[s];
      }
      hits[hit_count++] = {all->range[s], weight * rho * cos_incidence, body, all->triangle[s], k};
    }
    if (hit_count > 0) setBeamReturns(hits, hits + hit_count, returns, i, &groups, out);
  }
}

}  // namespace core
}  // namespace laser_raycast
