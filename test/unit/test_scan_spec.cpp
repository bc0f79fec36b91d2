// ScanSpec: one validated description of a scan, from which the pattern, the caster's configuration
// and the measurement model's are made.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "expect_invalid.h"
#include "laser_raycast/core/scan_spec.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

ScanSpec spec(double range_min, double range_max, MinRangePolicy policy) {
  ScanSpec s;
  s.fan.samples = 8;
  s.output.range_min = range_min;
  s.output.range_max = range_max;
  s.output.min_range_policy = policy;
  return s;
}

// The cast interval each policy needs: pass_through casts from range_min, the others from 0 (so
// that too-close surfaces are seen and reported); all stop at range_max.
TEST(ScanSpec, CastIntervalFollowsTheMinRangePolicy) {
  EXPECT_EQ(spec(0.5, 12.0, MinRangePolicy::kPassThrough).castConfig().tmin, 0.5);
  EXPECT_EQ(spec(0.5, 12.0, MinRangePolicy::kNegInf).castConfig().tmin, 0.0);
  EXPECT_EQ(spec(0.5, 12.0, MinRangePolicy::kNan).castConfig().tmin, 0.0);
  for (const MinRangePolicy p : {MinRangePolicy::kPassThrough, MinRangePolicy::kNegInf}) {
    EXPECT_EQ(spec(0.5, 12.0, p).castConfig().tmax, 12.0);
  }
}

TEST(ScanSpec, CastConfigCarriesMethodBackfacesAndIncidence) {
  ScanSpec s = spec(0.0, 5.0, MinRangePolicy::kNegInf);
  EXPECT_EQ(s.castConfig().method, TriangleMethod::kWatertight);
  EXPECT_FALSE(s.castConfig().cull_backfaces);
  EXPECT_FALSE(s.castConfig().compute_incidence);
  s.method = TriangleMethod::kCramer;
  s.cull_backfaces = true;
  s.output.intensity = true;
  const CastConfig c = s.castConfig();
  EXPECT_EQ(c.method, TriangleMethod::kCramer);
  EXPECT_TRUE(c.cull_backfaces);
  EXPECT_TRUE(c.compute_incidence);
  EXPECT_NO_THROW(c.validate());
}

TEST(ScanSpec, RingsAreTheElevationsInAscendingOrder) {
  ScanSpec s = spec(0.0, 5.0, MinRangePolicy::kNegInf);
  s.elevations = {0.2, -0.1, 0.05};
  const ScanPattern p = s.pattern();
  ASSERT_EQ(p.ringCount(), 3);
  EXPECT_EQ(p.elevations(), (std::vector<double>{-0.1, 0.05, 0.2}));
  EXPECT_EQ(p.size(), 24);
  // Ring 0 is the lowest: its beams point down.
  EXPECT_LT(p.directions()[0].z(), 0.0);
  EXPECT_GT(p.directions()[2 * 8].z(), 0.0);
  EXPECT_FALSE(p.planar());
  EXPECT_TRUE(spec(0.0, 5.0, MinRangePolicy::kNegInf).pattern().planar());
}

TEST(ScanSpec, ValidateNamesTheBadField) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ScanSpec s = spec(0.0, 5.0, MinRangePolicy::kNegInf);
  s.elevations = {};
  expectMentions(invalidMessage([&] { s.validate(); }), {"elevations", "empty"});
  s.elevations = {0.1, nan};
  expectMentions(invalidMessage([&] { s.validate(); }), {"elevations[1]", "nan"});
  s.elevations = {0.1, 2.0};
  expectMentions(invalidMessage([&] { s.validate(); }), {"elevations[1]", "2"});
  s.elevations = {0.1, -0.2, 0.1};
  expectMentions(invalidMessage([&] { s.validate(); }), {"distinct", "0.1"});
  s = spec(1.0, 0.5, MinRangePolicy::kNegInf);
  expectMentions(invalidMessage([&] { s.validate(); }), {"range_max"});
  s = spec(0.0, 5.0, MinRangePolicy::kNegInf);
  s.fan.angle_increment = 0.1;  // and samples: both given
  expectMentions(invalidMessage([&] { s.validate(); }), {"angle_increment", "samples"});
  s = spec(0.0, 5.0, MinRangePolicy::kNegInf);
  s.fan.samples = 100000;
  s.elevations.assign(200, 0.0);
  for (int r = 0; r < 200; ++r) s.elevations[r] = -0.5 + r * 0.005;
  expectMentions(invalidMessage([&] { s.validate(); }), {"100000 azimuths x 200 elevations"});
  EXPECT_THROW(s.pattern(), std::invalid_argument);
}

}  // namespace
}  // namespace laser_raycast_test
