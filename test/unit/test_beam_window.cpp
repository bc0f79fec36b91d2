// Beam windows: approxAtan2 within its stated bound of std::atan2, azimuthWindow containing every
// bearing of the sphere it is given, and forEachBeamRange against a check of every beam.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "fan_specs.h"
#include "beams/beam_window.h"
#include "laser_raycast/core/scan_pattern.h"
#include "random.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

// The beam windows' helpers: approxAtan2 stays within its stated bound of std::atan2 over every
// direction (both lie in (-pi, pi]; compared on the circle), and azimuthWindow contains the bearing
// of every point of the sphere it is given (sampled on its surface, the extreme bearings included).
TEST(BeamWindow, ApproxAtan2IsWithinItsBound) {
  Rng rng(41);
  double worst = 0;
  for (int i = 0; i < 200000; ++i) {
    const double a = uniform(rng, -M_PI, M_PI);
    const double r = std::pow(10.0, uniform(rng, -6, 6));
    const double x = r * std::cos(a), y = r * std::sin(a);
    double diff = std::abs(approxAtan2(y, x) - std::atan2(y, x));
    diff = std::min(diff, 2 * M_PI - diff);
    worst = std::max(worst, diff);
  }
  for (const double x : {1.0, -1.0, 0.0}) {  // the axes and the diagonals exactly
    for (const double y : {1.0, -1.0, 0.0}) {
      if (x == 0 && y == 0) continue;
      double diff = std::abs(approxAtan2(y, x) - std::atan2(y, x));
      worst = std::max(worst, std::min(diff, 2 * M_PI - diff));
    }
  }
  EXPECT_LE(worst, kBearingError);
  EXPECT_GT(worst, 0.0);  // it is an approximation: the bound is what matters
}

// approxAtan2Pair gives each point approxAtan2's bits (it makes the same operations two at a time):
// random points over twelve decades, the axes, the diagonals, signed zeros, the origin, infinities
// and NaN, in both places of the pair.
TEST(BeamWindow, ApproxAtan2PairGivesApproxAtan2sBits) {
  Rng rng(47);
  std::vector<double> values = {0.0, -0.0, 1.0, -1.0, 1e-300, -1e-300, INFINITY, -INFINITY, NAN};
  for (int i = 0; i < 2000; ++i) {
    values.push_back(std::pow(10.0, uniform(rng, -6, 6)) * (uniform(rng, -1, 1) < 0 ? -1 : 1));
  }
  auto bits = [](double v) {
    std::uint64_t b;
    std::memcpy(&b, &v, sizeof b);
    return b;
  };
  for (int i = 0; i < 40000; ++i) {
    const auto pick = [&] { return values[rng() % values.size()]; };
    const double y0 = pick(), x0 = pick(), y1 = pick(), x1 = pick();
    double r0, r1;
    approxAtan2Pair(y0, x0, y1, x1, &r0, &r1);
    ASSERT_EQ(bits(r0), bits(approxAtan2(y0, x0))) << y0 << ", " << x0;
    ASSERT_EQ(bits(r1), bits(approxAtan2(y1, x1))) << y1 << ", " << x1;
  }
}

TEST(BeamWindow, AzimuthWindowContainsTheSphere) {
  Rng rng(43);
  int limited = 0;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d c(uniform(rng, -20, 20), uniform(rng, -20, 20), uniform(rng, -5, 5));
    const double radius = std::pow(10.0, uniform(rng, -3, 1.2));
    const double angle_min = uniform(rng, -10, 10);
    double start, width;
    if (!azimuthWindow(c, radius, angle_min, &start, &width)) continue;
    ++limited;
    ASSERT_GE(start, 0.0);
    ASSERT_LT(start, 2 * M_PI);
    // The two tangent bearings of the sphere's horizontal disc, and random points of the sphere.
    const double rho = std::hypot(c.x(), c.y());
    const double centre = std::atan2(c.y(), c.x());
    std::vector<double> bearings = {centre + std::asin(radius / rho),
                                    centre - std::asin(radius / rho)};
    for (int k = 0; k < 20; ++k) {
      Eigen::Vector3d u(uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1));
      if (u.norm() == 0) continue;
      const Eigen::Vector3d p = c + radius * u.normalized();
      bearings.push_back(std::atan2(p.y(), p.x()));
    }
    for (const double b : bearings) {
      // Offset from the window's start, on the circle.
      double offset = std::fmod(b - angle_min - start, 2 * M_PI);
      if (offset < 0) offset += 2 * M_PI;
      EXPECT_LE(offset, width) << "sphere " << i;
    }
  }
  EXPECT_GT(limited, 2000);
}

// forEachBeamRange against every beam: for random fans (a fraction of a turn up to three turns,
// coarse and fine) and random windows (empty and full ones too), the ranges are increasing and
// disjoint, every beam whose bearing lies in the window (modulo a turn) is visited, and no visited
// beam lies outside it by more than rounding.
TEST(BeamWindow, BeamRangesHoldTheWindowAndNothingBeyondRounding) {
  Rng rng(47);
  long inside = 0, padding = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const double angle_min = uniform(rng, -7, 7);
    const double span = uniform(rng, 0.05, 6 * M_PI);
    const int samples = 2 + static_cast<int>(logUniform(rng, 0, 3.5));
    const ScanPattern fan(fanBySamples(angle_min, angle_min + span, samples));
    const double start = uniform(rng, 0, 2 * M_PI);
    const double width = trial % 7 == 0   ? 0.0
                         : trial % 7 == 1 ? 2 * M_PI
                                          : uniform(rng, 0, 2 * M_PI);
    const double inc = fan.angleIncrement();
    const int n = fan.azimuthCount();
    std::vector<char> visited(n, 0);
    int previous_last = -1;
    forEachBeamRange(fan, start, width, [&](int first, int last) {
      EXPECT_GE(first, 0) << "trial " << trial;
      EXPECT_GT(first, previous_last) << "trial " << trial;
      EXPECT_LE(first, last) << "trial " << trial;
      EXPECT_LT(last, n) << "trial " << trial;
      for (int i = std::max(first, 0); i <= std::min(last, n - 1); ++i) visited[i] = 1;
      previous_last = last;
    });
    for (int i = 0; i < n; ++i) {
      // The beam's offset from the window's start, on the circle, and how far it is outside.
      double offset = std::fmod(i * inc - start, 2 * M_PI);
      if (offset < 0) offset += 2 * M_PI;
      const double outside = offset <= width ? 0.0 : std::min(offset - width, 2 * M_PI - offset);
      if (outside == 0) {
        ++inside;
        EXPECT_TRUE(visited[i]) << "trial " << trial << " beam " << i << " of " << n;
      } else if (visited[i]) {
        ++padding;
        EXPECT_LE(outside, 1e-12) << "trial " << trial << " beam " << i << " of " << n;
      }
    }
    if (HasFailure()) return;
  }
  EXPECT_GT(inside, 100000);
  EXPECT_LT(padding, 100);  // only beams exactly at a window's end, within rounding
}

// Regression (found by test/fuzz/fuzz_core): a fan of 720 beams over 1e-9 rad has an increment of
// 1.4e-12 rad, and a window's far end divided by it (4.5e12) was converted to int: undefined, and
// in practice INT_MIN (the sanitizer build stops there). Windows beyond the fan visit nothing;
// a window holding it visits every beam once.
TEST(BeamWindow, TinyIncrementRegression) {
  const ScanPattern fan(fanBySamples(0.5, 0.5 + 1e-9, 720));
  // How often each beam is visited.
  const auto visits = [&](double start, double width) {
    std::vector<int> count(720, 0);
    forEachBeamRange(fan, start, width, [&](int first, int last) {
      for (int i = first; i <= last; ++i) ++count.at(i);
    });
    return count;
  };
  const std::vector<int> none(720, 0), once(720, 1);
  EXPECT_EQ(visits(1.0, 2.0), none);
  EXPECT_EQ(visits(3.0, 0.0), none);
  EXPECT_EQ(visits(0.0, 1e-6), once);
  EXPECT_EQ(visits(2 * M_PI - 1e-6, 2e-6), once);  // from just before a turn
  EXPECT_EQ(visits(0.0, 2 * M_PI), once);
}

}  // namespace
}  // namespace laser_raycast_test
