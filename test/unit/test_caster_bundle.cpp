// Caster::castBundle against its definition: each sub-ray pattern cast on its own (Caster::cast).
// Random scenes of meshes and primitives on a fixed and a moving frame, sensors in random poses,
// rings patterns shifted as a divergent beam's sub-rays are (returns.h), footprints from a fraction
// of a beam spacing to several, one thread and two, incidence on and off, the fast paths on and
// off: every range, body, triangle and normal bit for bit, since each sub-ray is tested exactly as
// its own cast tests it and the bundle's culling only skips what no sub-ray can reach.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <vector>

#include "cast_reference.h"
#include "expect_invalid.h"
#include "fan_specs.h"
#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/returns.h"
#include "random.h"
#include "random_scene.h"

namespace laser_raycast_test {
namespace {

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// The sub-ray patterns of `samples` sub-rays over a footprint of full angle `divergence` about
// each beam of (fan, rings), as castReturns shifts them.
std::vector<core::ScanPattern> subPatterns(const core::FanSpec& fan,
                                           const std::vector<double>& rings, double divergence,
                                           int samples) {
  core::ReturnsConfig returns;
  returns.beam_divergence = divergence;
  returns.beam_samples = samples;
  std::vector<core::ScanPattern> patterns;
  for (int k = 0; k < samples; ++k) {
    const Eigen::Vector2d offset = returns.offset(k);
    core::FanSpec shifted = fan;
    shifted.angle_min += offset.x();
    shifted.angle_max += offset.x();
    std::vector<double> shifted_rings = rings;
    for (double& e : shifted_rings) e += offset.y();
    patterns.emplace_back(shifted, shifted_rings);
  }
  return patterns;
}

TEST(CastBundle, EachSubRayIsItsPatternsOwnCast) {
  Rng rng(4711);
  long long beams = 0, hits = 0, differing = 0;
  for (int trial = 0; trial < 16; ++trial) {
    const RandomScene rs = randomScene(rng);
    const Eigen::Isometry3d sensor =
        pose(uniformInBox(rng, Eigen::Vector3d(-5, -5, -0.5), Eigen::Vector3d(5, 5, 0.5)),
             rpy(uniform(rng, -0.3, 0.3), uniform(rng, -0.3, 0.3), uniform(rng, -3, 3)));
    const int azimuths = trial % 3 == 0 ? 360 : 720;
    const core::FanSpec fan = fanBySamples(-M_PI, M_PI - 2 * M_PI / azimuths, azimuths);
    const std::vector<double> rings = {-0.26, -0.17, -0.09, -0.03, 0.0, 0.04, 0.11, 0.2, 0.3};
    // From a tenth of an azimuth step to four of them.
    const double step = 2 * M_PI / azimuths;
    const double divergence = step * (trial % 4 == 0 ? 0.1 : trial % 4 == 1 ? 1.0 : 4.0) * 3;
    const int samples = trial % 2 ? 7 : 4;
    const std::vector<core::ScanPattern> patterns = subPatterns(fan, rings, divergence, samples);
    core::CastConfig config;
    config.tmax = 40;
    config.threads = trial % 3 == 1 ? 2 : 1;
    config.compute_incidence = trial % 2 == 0;
    config.raster_fast_path = trial % 5 != 4;
    config.occlusion_culling = trial % 7 != 6;
    core::Caster bundle_caster;
    const std::vector<core::ScanResult> bundle =
        bundle_caster.castBundle(rs.scene, rs.poses, sensor, patterns, config);
    ASSERT_EQ(bundle.size(), patterns.size());
    for (std::size_t k = 0; k < patterns.size(); ++k) {
      core::Caster one;
      const core::ScanResult& own = one.cast(rs.scene, rs.poses, sensor, patterns[k], config);
      ASSERT_EQ(bundle[k].range.size(), own.range.size());
      for (std::size_t i = 0; i < own.range.size(); ++i) {
        ++beams;
        hits += std::isfinite(own.range[i]);
        const bool same = sameBits(bundle[k].range[i], own.range[i]) &&
                          bundle[k].body[i] == own.body[i] &&
                          bundle[k].triangle[i] == own.triangle[i] &&
                          (!config.compute_incidence ||
                           (bundle[k].normal[i] == own.normal[i] &&
                            sameBits(bundle[k].cos_incidence[i], own.cos_incidence[i])));
        if (!same) {
          ++differing;
          ADD_FAILURE() << "trial " << trial << " sub-ray " << k << " beam " << i << ": "
                        << bundle[k].range[i] << " (body " << bundle[k].body[i] << ") vs "
                        << own.range[i] << " (body " << own.body[i] << ")";
          if (differing > 20) return;
        }
      }
    }
  }
  EXPECT_GT(hits, beams / 4);
  std::printf("bundles vs their patterns' casts: %lld beams, %lld hits, %lld differ\n", beams,
              hits, differing);
}

// The kept form, as castReturns casts scan after scan: one SubRayBundle handed to one caster again
// and again (its directions' float copy made once), then another footprint, then the first again.
// Entry i * subRays() + k of each result is sub-ray k of beam i, bit for bit its pattern's own
// cast from that scan's pose.
TEST(CastBundle, AKeptBundleGivesEachSubRayItsPatternsOwnCastScanAfterScan) {
  Rng rng(90210);
  const RandomScene rs = randomScene(rng);
  const core::FanSpec fan = fanBySamples(-M_PI, M_PI - 2 * M_PI / 360, 360);
  const std::vector<double> rings = {-0.2, -0.1, -0.02, 0.0, 0.05, 0.15, 0.25};
  const double step = 2 * M_PI / 360;
  const auto narrow = std::make_shared<const core::SubRayBundle>(subPatterns(fan, rings, step, 7));
  const auto wide =
      std::make_shared<const core::SubRayBundle>(subPatterns(fan, rings, 6 * step, 4));
  core::CastConfig config;
  config.tmax = 40;
  config.compute_incidence = true;
  core::Caster kept;
  long long sub_rays = 0, hits = 0;
  for (int scan = 0; scan < 5; ++scan) {
    const std::shared_ptr<const core::SubRayBundle>& bundle = scan == 2 ? wide : narrow;
    const Eigen::Isometry3d sensor =
        pose(uniformInBox(rng, Eigen::Vector3d(-4, -4, -0.3), Eigen::Vector3d(4, 4, 0.3)),
             rpy(uniform(rng, -0.2, 0.2), uniform(rng, -0.2, 0.2), uniform(rng, -3, 3)));
    config.threads = scan % 2 ? 2 : 1;
    const core::ScanResult& all = kept.castBundle(rs.scene, rs.poses, sensor, bundle, config);
    const int count = bundle->subRays();
    ASSERT_EQ(all.range.size(), bundle->beams() * count);
    ASSERT_EQ(all.normal.size(), all.range.size());
    ASSERT_EQ(all.cos_incidence.size(), all.range.size());
    for (int k = 0; k < count; ++k) {
      core::Caster one;
      const core::ScanResult& own =
          one.cast(rs.scene, rs.poses, sensor, bundle->patterns()[k], config);
      ASSERT_EQ(own.range.size(), bundle->beams());
      for (std::size_t i = 0; i < own.range.size(); ++i) {
        const std::size_t s = i * count + k;
        ++sub_rays;
        hits += std::isfinite(own.range[i]);
        ASSERT_TRUE(sameBits(all.range[s], own.range[i]) && all.body[s] == own.body[i] &&
                    all.triangle[s] == own.triangle[i] && all.normal[s] == own.normal[i] &&
                    sameBits(all.cos_incidence[s], own.cos_incidence[i]))
            << "scan " << scan << " sub-ray " << k << " beam " << i << ": " << all.range[s]
            << " (body " << all.body[s] << ") vs " << own.range[i] << " (body " << own.body[i]
            << ")";
        EXPECT_TRUE(bundle->directions()[s] == bundle->patterns()[k].directions()[i]);
      }
    }
  }
  EXPECT_GT(hits, sub_rays / 4);
  core::Caster caster;
  expectMentions(invalidMessage([&] {
                   caster.castBundle(rs.scene, rs.poses, Eigen::Isometry3d::Identity(),
                                     std::shared_ptr<const core::SubRayBundle>(), config);
                 }),
                 {"null"});
}

TEST(CastBundle, RefusesPatternsItCannotBundle) {
  const core::Scene scene = sceneWithFrame();
  const core::FramePoses poses = core::FramePoses::identity(scene);
  core::Caster caster;
  const core::CastConfig config;
  const core::FanSpec fan = fanBySamples(-1, 1, 11);
  auto refusal = [&](const std::vector<core::ScanPattern>& patterns) {
    return invalidMessage(
        [&] { caster.castBundle(scene, poses, Eigen::Isometry3d::Identity(), patterns, config); });
  };
  expectMentions(refusal({}), {"no patterns"});
  expectMentions(refusal({core::ScanPattern(fan, {0.0})}), {"planar"});
  expectMentions(refusal({core::ScanPattern(fan, {0.1, 0.2}), core::ScanPattern(fan, {0.1})}),
                 {"pattern 1", "1 rings", "2 x 11"});
  expectMentions(refusal({core::ScanPattern(fan, {0.1, 0.2}), core::ScanPattern(fan, {0.3, 0.2})}),
                 {"pattern 1", "order"});
  // A SubRayBundle checks the same when it is made.
  expectMentions(invalidMessage([&] {
                   core::SubRayBundle({core::ScanPattern(fan, {0.1}), core::ScanPattern(fan, {0.0})});
                 }),
                 {"pattern 1", "planar"});
}

}  // namespace
}  // namespace laser_raycast_test
