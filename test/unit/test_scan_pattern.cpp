// FanSpec and ScanPattern: beam counts and angles by the documented formulas, unit directions in
// order, ring-major layout, and validation messages that name the field and its value.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "expect_invalid.h"
#include "fan_specs.h"
#include "laser_raycast/core/scan_pattern.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

void expectFanInvalid(const FanSpec& fan, const std::vector<std::string>& needles) {
  expectMentions(invalidMessage([&] { fan.validate(); }), needles);
  // The pattern validates its fan.
  EXPECT_THROW(ScanPattern{fan}, std::invalid_argument);
}

// Angle from a to b, counter-clockwise, in (-pi, pi].
double angleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.x() * b.y() - a.y() * b.x(), a.x() * b.x() + a.y() * b.y());
}

// Increment mode: N = round((max - min) / increment) + 1, beams from angle_min spaced by the
// increment, including when the span is not a multiple of it (the last beam may pass angle_max).
TEST(FanSpec, IncrementModeCount) {
  struct Case {
    double min, max, increment;
    int n;  // by hand
  };
  const Case cases[] = {
      {-1.0, 1.0, 0.5, 5},  // exact multiple
      {0.0, 1.0, 0.3, 4},   // 3.33 -> 3 -> 4 beams, last at 0.9
      {0.0, 1.25, 0.5, 4},  // 2.5 (exact) rounds away from zero -> 4 beams, last at 1.5
      {0.0, 1.0, 0.45, 3},  // 2.22 -> 2 -> 3 beams
      {0.0, 0.1, 1.0, 1},   // 0.1 -> 0 -> a single beam
      {-M_PI, M_PI, M_PI / 180, 361},
  };
  for (const Case& c : cases) {
    const FanSpec fan = fanByIncrement(c.min, c.max, c.increment);
    ASSERT_NO_THROW(fan.validate());
    EXPECT_EQ(fan.beamCount(), c.n) << c.min << " " << c.max << " " << c.increment;
    EXPECT_EQ(fan.increment(), c.increment);
    const ScanPattern pattern(fan);
    ASSERT_EQ(pattern.size(), c.n);
    EXPECT_EQ(pattern.azimuthCount(), c.n);
    EXPECT_EQ(pattern.ringCount(), 1);
    EXPECT_EQ(pattern.angleMin(), c.min);
    EXPECT_EQ(pattern.angleIncrement(), c.increment);
    EXPECT_EQ(pattern.azimuth(0), c.min);
    EXPECT_DOUBLE_EQ(pattern.angleMax(), c.min + (c.n - 1) * c.increment);
    for (int i = 0; i < c.n; ++i) {
      const double a = c.min + i * c.increment;
      EXPECT_NEAR(pattern.azimuth(i), a, 1e-15);
      EXPECT_NEAR(pattern.directions()[i].x(), std::cos(a), 1e-15);
      EXPECT_NEAR(pattern.directions()[i].y(), std::sin(a), 1e-15);
      EXPECT_EQ(pattern.directions()[i].z(), 0.0);
    }
  }
}

// Samples mode: N = samples from angle_min to angle_max inclusive, spaced by (max - min) / (N - 1).
TEST(FanSpec, SamplesModeSpacing) {
  struct Case {
    double min, max;
    int samples;
  };
  const Case cases[] = {{-1.0, 1.0, 5}, {-M_PI, M_PI, 720}, {0.25, 0.5, 2}, {-2.0, 3.0, 1081}};
  for (const Case& c : cases) {
    const FanSpec fan = fanBySamples(c.min, c.max, c.samples);
    ASSERT_NO_THROW(fan.validate());
    EXPECT_EQ(fan.beamCount(), c.samples);
    const double spacing = (c.max - c.min) / (c.samples - 1);
    EXPECT_EQ(fan.increment(), spacing);
    const ScanPattern pattern(fan);
    ASSERT_EQ(pattern.size(), c.samples);
    EXPECT_EQ(pattern.angleIncrement(), spacing);
    // First beam exactly at angle_min, last at angle_max (to the rounding of (N - 1) * spacing).
    EXPECT_EQ(pattern.azimuth(0), c.min);
    const double tolerance = 4 * std::numeric_limits<double>::epsilon() * std::abs(c.max);
    EXPECT_NEAR(pattern.azimuth(c.samples - 1), c.max, tolerance);
    EXPECT_NEAR(pattern.angleMax(), c.max, tolerance);
    const Eigen::Vector3d& last = pattern.directions().back();
    EXPECT_NEAR(last.x(), std::cos(c.max), 1e-15);
    EXPECT_NEAR(last.y(), std::sin(c.max), 1e-15);
  }
  // The literal case: 5 samples over [-1, 1] are -1, -0.5, 0, 0.5, 1.
  const ScanPattern five(fanBySamples(-1, 1, 5));
  const double expected[] = {-1, -0.5, 0, 0.5, 1};
  for (int i = 0; i < 5; ++i) EXPECT_EQ(five.azimuth(i), expected[i]);
}

// Directions are unit vectors, each one increment counter-clockwise from the previous.
TEST(ScanPattern, DirectionsAreUnitAndInOrder) {
  for (const FanSpec& fan :
       {fanByIncrement(-M_PI, M_PI, 0.0174533), fanBySamples(-2.0, 2.5, 999),
        fanByIncrement(-0.3, 0.3, 0.001), fanByIncrement(-3 * M_PI, 3 * M_PI, 0.1)}) {
    const ScanPattern pattern(fan);
    const auto& d = pattern.directions();
    ASSERT_EQ(static_cast<int>(d.size()), fan.beamCount());
    for (int i = 0; i < pattern.size(); ++i) {
      EXPECT_NEAR(d[i].norm(), 1.0, 2e-16 * 4);
      if (i > 0) {
        EXPECT_NEAR(angleBetween(d[i - 1], d[i]), fan.increment(), 1e-12) << i;
      }
    }
  }
}

// planar(): a single ring at elevation exactly 0 (the default, or given explicitly; -0.0 is 0).
TEST(ScanPattern, Planar) {
  const FanSpec fan = fanBySamples(-1, 1, 11);
  EXPECT_TRUE(ScanPattern(fan).planar());
  EXPECT_TRUE(ScanPattern(fan, {0.0}).planar());
  EXPECT_TRUE(ScanPattern(fan, {-0.0}).planar());
  EXPECT_FALSE(ScanPattern(fan, {0.01}).planar());
  EXPECT_FALSE(ScanPattern(fan, {-1e-300}).planar());
  EXPECT_FALSE(ScanPattern(fan, {0.0, 0.0}).planar());  // two rings, even if both at 0
  EXPECT_FALSE(ScanPattern(fan, {0.0, 0.1}).planar());
  const ScanPattern planar(fan);
  for (const auto& d : planar.directions()) EXPECT_EQ(d.z(), 0.0);
}

// Rings are ring-major: beam r * azimuthCount() + i is azimuth i at elevation r, positive up.
TEST(ScanPattern, RingsAreRingMajor) {
  const std::vector<double> elevations = {-0.2, 0.0, 0.3, M_PI / 2, -M_PI / 2};
  const FanSpec fan = fanBySamples(-1.5, 1.5, 7);
  const ScanPattern pattern(fan, elevations);
  ASSERT_EQ(pattern.ringCount(), 5);
  ASSERT_EQ(pattern.azimuthCount(), 7);
  ASSERT_EQ(pattern.size(), 35);
  EXPECT_EQ(pattern.elevations(), elevations);
  for (int r = 0; r < 5; ++r) {
    for (int i = 0; i < 7; ++i) {
      const Eigen::Vector3d& d = pattern.directions()[r * 7 + i];
      const double e = elevations[r], a = -1.5 + i * 0.5;
      EXPECT_NEAR(d.x(), std::cos(e) * std::cos(a), 1e-15) << r << " " << i;
      EXPECT_NEAR(d.y(), std::cos(e) * std::sin(a), 1e-15) << r << " " << i;
      EXPECT_NEAR(d.z(), std::sin(e), 1e-15) << r << " " << i;
      EXPECT_NEAR(d.norm(), 1.0, 1e-15);
      EXPECT_NEAR(std::asin(d.z()), e, 1e-7);  // asin is ill-conditioned at +-pi/2
    }
  }
}

// Each invalid fan throws std::invalid_argument naming the field and the value given.
TEST(FanSpec, ValidateNamesFieldAndValue) {
  expectFanInvalid(fanByIncrement(kNan, 1, 0.1), {"angle_min", "nan"});
  expectFanInvalid(fanByIncrement(-kInf, 1, 0.1), {"angle_min", "inf"});
  expectFanInvalid(fanByIncrement(0, kNan, 0.1), {"angle_max", "nan"});
  expectFanInvalid(fanByIncrement(0, kInf, 0.1), {"angle_max", "inf"});
  expectFanInvalid(fanByIncrement(1, 1, 0.1), {"angle_max", "angle_min", "1"});
  expectFanInvalid(fanByIncrement(1, -2, 0.1), {"angle_max", "angle_min", "-2"});

  // Both or neither of angle_increment and samples.
  FanSpec both = fanByIncrement(-1, 1, 0.25);
  both.samples = 9;
  expectFanInvalid(both, {"angle_increment", "samples", "0.25", "9"});
  expectFanInvalid(fanByIncrement(-1, 1, 0), {"angle_increment", "samples"});

  expectFanInvalid(fanByIncrement(-1, 1, -0.125), {"angle_increment", "-0.125"});
  expectFanInvalid(fanByIncrement(-1, 1, kNan), {"angle_increment", "nan"});
  expectFanInvalid(fanByIncrement(-1, 1, kInf), {"angle_increment", "inf"});
  expectFanInvalid(fanBySamples(-1, 1, 1), {"samples", "1"});
  expectFanInvalid(fanBySamples(-1, 1, -4), {"samples", "-4"});

  // Too many beams: by increment (the count is in the message) and by samples.
  expectFanInvalid(fanByIncrement(0, 1, 1e-8), {"angle_increment", "1e-08", "10000000"});
  expectFanInvalid(fanBySamples(0, 1, FanSpec::kMaxBeams + 1), {"samples", "10000001"});
  // The limit itself is accepted (validate only: no directions are allocated).
  EXPECT_NO_THROW(fanBySamples(0, 1, FanSpec::kMaxBeams).validate());
  EXPECT_NO_THROW(fanByIncrement(0, 1, 1.0 / (FanSpec::kMaxBeams - 1)).validate());
}

// Elevations: empty, outside [-pi/2, pi/2] or NaN throw and name the elevation; the bounds pass.
TEST(ScanPattern, ElevationErrors) {
  const FanSpec fan = fanBySamples(-1, 1, 3);
  auto pattern = [&](std::vector<double> elevations) {
    return invalidMessage([&] { ScanPattern p(fan, elevations); });
  };
  expectMentions(pattern({}), {"elevations"});
  expectMentions(pattern({0.0, 2.0}), {"elevation 1", "2"});
  expectMentions(pattern({-1.6}), {"elevation 0", "-1.6"});
  expectMentions(pattern({0.1, 0.2, kNan}), {"elevation 2", "nan"});
  expectMentions(pattern({kInf}), {"elevation 0", "inf"});
  EXPECT_NO_THROW(ScanPattern(fan, {-M_PI / 2, M_PI / 2}));
  EXPECT_THROW(ScanPattern(fan, {std::nextafter(M_PI / 2, 4.0)}), std::invalid_argument);
}

// Azimuths x rings above kMaxBeams is refused before anything is allocated.
TEST(ScanPattern, TooManyBeamsAcrossRings) {
  const FanSpec fan = fanBySamples(-1, 1, 4000000);
  ASSERT_NO_THROW(fan.validate());
  expectMentions(invalidMessage([&] {
                   ScanPattern p(fan, {-0.1, 0.0, 0.1});
                 }),
                 {"4000000", "3", "10000000"});
}

}  // namespace
}  // namespace laser_raycast_test
