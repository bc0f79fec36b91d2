// The measurement model's range realism options: range_bias, range_resolution (quantizeRange) and
// dropout_probability. Exact values by hand, dropout statistics with fixed seeds, the documented
// order (bias, noise, clamp, quantise, dropout), and that invalid readings get none of it.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "measurement_inputs.h"
#include "expect_invalid.h"
#include "laser_raycast/core/measurement_model.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr float kInfF = std::numeric_limits<float>::infinity();

MeasuredScan encodeOnce(const MeasurementConfig& config, const ScanResult& result) {
  MeasurementModel model(config);
  MeasuredScan out;
  model.measure(labelledScene(), result, {}, &out);
  return out;
}

// A result whose ranges are given; every beam hits body 0.
ScanResult resultWithRanges(const std::vector<double>& ranges) {
  ScanResult r = uniformResult(static_cast<int>(ranges.size()), 0.0, true);
  r.range = ranges;
  return r;
}

TEST(MeasurementModelRealism, ValidateNamesFieldAndValue) {
  auto message = [](const MeasurementConfig& c) { return invalidMessage([&] { c.validate(); }); };
  MeasurementConfig c;
  c.range_bias = -0.05;
  c.range_resolution = 0.002;
  c.dropout_probability = 1.0;
  EXPECT_NO_THROW(c.validate());
  c.dropout_probability = 0.0;
  EXPECT_NO_THROW(c.validate());
  for (const double bad : {kNan, kInf, -kInf}) {
    c = MeasurementConfig{};
    c.range_bias = bad;
    expectMentions(message(c), {"range_bias", std::isnan(bad) ? "nan" : "inf"});
  }
  for (const double bad : {-0.001, kNan, kInf}) {
    c = MeasurementConfig{};
    c.range_resolution = bad;
    expectMentions(message(c), {"range_resolution", std::isnan(bad) ? "nan"
                                                    : bad < 0       ? "-0.001"
                                                                    : "inf"});
  }
  for (const double bad : {-0.1, 1.5, kNan}) {
    c = MeasurementConfig{};
    c.dropout_probability = bad;
    expectMentions(message(c), {"dropout_probability", std::isnan(bad) ? "nan"
                                                       : bad < 0       ? "-0.1"
                                                                       : "1.5"});
  }
  EXPECT_THROW(MeasurementModel{c}, std::invalid_argument);
}

// Hand-computed multiples, clamped to [range_min, range_max].
TEST(MeasurementModelRealism, QuantizeRangeByHand) {
  MeasurementConfig c = measurementConfig(0.5, 10.0);
  EXPECT_EQ(quantizeRange(1.2345, c), 1.2345);  // resolution 0: off
  c.range_resolution = 0.002;
  EXPECT_EQ(quantizeRange(1.2345, c), 617 * 0.002);   // 617.25 steps
  EXPECT_EQ(quantizeRange(2.0031, c), 1002 * 0.002);  // 1001.55 steps
  EXPECT_EQ(quantizeRange(0.9999, c), 500 * 0.002);   // 499.95 steps
  c.range_resolution = 0.3;
  EXPECT_EQ(quantizeRange(5.0, c), 17 * 0.3);   // 16.67 steps
  EXPECT_EQ(quantizeRange(0.65, c), 2 * 0.3);   // 2.17 steps
  EXPECT_EQ(quantizeRange(0.5, c), 2 * 0.3);    // 1.67 steps: 0.6, inside
  EXPECT_EQ(quantizeRange(10.0, c), 33 * 0.3);  // 33.33 steps: 9.9, inside
  // The nearest multiple lies outside: the limit.
  c = measurementConfig(0.5, 9.9);
  c.range_resolution = 0.4;
  EXPECT_EQ(quantizeRange(0.55, c), 0.5);  // 1.375 steps: 0.4 < range_min
  EXPECT_EQ(quantizeRange(9.85, c), 9.9);  // 24.6 steps: 10.0 > range_max
}

// Through the measurement model: every valid output is a multiple of the resolution (to float), within half
// a step of the range, and inside the limits.
TEST(MeasurementModelRealism, QuantisationInTheMeasurementModel) {
  std::vector<double> ranges;
  for (int i = 0; i < 2000; ++i) ranges.push_back(0.5 + 0.004749 * i);  // 0.5 .. 9.99
  MeasurementConfig c = measurementConfig(0.5, 10.0);
  c.range_resolution = 0.01;
  const MeasuredScan out = encodeOnce(c, resultWithRanges(ranges));
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    const double steps = static_cast<double>(out.ranges[i]) / 0.01;
    ASSERT_NEAR(steps, std::round(steps), 1e-4) << i << " " << out.ranges[i];
    ASSERT_LE(std::abs(out.ranges[i] - ranges[i]), 0.005 + 1e-6) << i;
    ASSERT_GE(out.ranges[i], 0.5f);
    ASSERT_LE(out.ranges[i], 10.0f);
  }
  EXPECT_EQ(out.ranges[0], 0.5f);
  EXPECT_EQ(out.ranges[1], static_cast<float>(50 * 0.01));    // 0.504749
  EXPECT_EQ(out.ranges[2], static_cast<float>(51 * 0.01));    // 0.509498
  EXPECT_EQ(out.ranges[100], static_cast<float>(97 * 0.01));  // 0.9749
}

// The bias shifts valid ranges exactly, clamped to the limits; bias then quantisation.
TEST(MeasurementModelRealism, BiasThenQuantisation) {
  MeasurementConfig c = measurementConfig(0.5, 10.0);
  c.range_bias = 0.05;
  MeasuredScan out = encodeOnce(c, resultWithRanges({4.0, 9.99, 10.0, 0.5}));
  EXPECT_EQ(out.ranges[0], static_cast<float>(4.0 + 0.05));
  EXPECT_EQ(out.ranges[1], 10.0f);  // 10.04 clamped: still valid
  EXPECT_EQ(out.ranges[2], 10.0f);
  EXPECT_EQ(out.ranges[3], static_cast<float>(0.5 + 0.05));
  c.range_bias = -0.05;
  out = encodeOnce(c, resultWithRanges({4.0, 0.52}));
  EXPECT_EQ(out.ranges[0], static_cast<float>(4.0 - 0.05));
  EXPECT_EQ(out.ranges[1], 0.5f);  // 0.47 clamped
  // 2.0 + 0.006 = 2.006 -> 2.01; quantising first would give 2.0 + 0.006.
  c.range_bias = 0.006;
  c.range_resolution = 0.01;
  out = encodeOnce(c, resultWithRanges({2.0}));
  EXPECT_EQ(out.ranges[0], static_cast<float>(201 * 0.01));
}

// p = 0.3 over 10^5 valid beams (seeded): 30% +- 1% lost (the binomial standard deviation is
// 0.14%). Lost beams report +Inf, label -1 and intensity 0; the others are untouched. A quarter of
// the beams are invalid and are never lost or changed.
TEST(MeasurementModelRealism, DropoutStatistics) {
  const int n = 133336;
  ScanResult r = uniformResult(n, 4.0, true);
  for (int i = 3; i < n; i += 4) {
    r.range[i] = i % 8 == 3 ? kInf : 0.2;  // no return, or too close
    if (r.range[i] == kInf) r.body[i] = -1;
  }
  MeasurementConfig c = measurementConfig(0.5, 10.0);
  c.intensity = true;
  c.dropout_probability = 0.3;
  c.noise_seed = 12345;
  const MeasuredScan out = encodeOnce(c, r);
  int valid = 0, lost = 0;
  for (int i = 0; i < n; ++i) {
    if (i % 4 == 3) {
      ASSERT_EQ(out.ranges[i], i % 8 == 3 ? kInfF : -kInfF) << i;
      ASSERT_EQ(out.labels[i], i % 8 == 3 ? -1 : 0) << i;
      continue;
    }
    ++valid;
    if (out.ranges[i] == kInfF) {
      ++lost;
      ASSERT_EQ(out.labels[i], -1) << i;
      ASSERT_EQ(out.intensities[i], 0.0f) << i;
    } else {
      ASSERT_EQ(out.ranges[i], 4.0f) << i;
      ASSERT_EQ(out.labels[i], 0) << i;
      ASSERT_EQ(out.intensities[i], 1.0f) << i;
    }
  }
  EXPECT_EQ(valid, 100002);
  EXPECT_NEAR(static_cast<double>(lost) / valid, 0.3, 0.01) << lost;
}

TEST(MeasurementModelRealism, DropoutZeroAndOne) {
  const ScanResult r = uniformResult(1000, 4.0);
  MeasurementConfig c = measurementConfig(0.5, 10.0);
  c.dropout_probability = 1.0;
  for (const float x : encodeOnce(c, r).ranges) ASSERT_EQ(x, kInfF);
  c.dropout_probability = 0.0;
  for (const float x : encodeOnce(c, r).ranges) ASSERT_EQ(x, 4.0f);
}

// A seed fixes both sequences; the noise of the beams that remain does not depend on dropout.
TEST(MeasurementModelRealism, DeterministicAndDropoutKeepsTheNoise) {
  const ScanResult r = uniformResult(5000, 4.0);
  MeasurementConfig c = measurementConfig(0.5, 10.0);
  c.noise_stddev = 0.02;
  c.noise_seed = 99;
  const MeasuredScan noise_only = encodeOnce(c, r);
  c.dropout_probability = 0.5;
  const MeasuredScan both = encodeOnce(c, r);
  EXPECT_EQ(both.ranges, encodeOnce(c, r).ranges);  // same seed, same scan
  int lost = 0;
  for (int i = 0; i < 5000; ++i) {
    if (both.ranges[i] == kInfF) {
      ++lost;
    } else {
      ASSERT_EQ(both.ranges[i], noise_only.ranges[i]) << i;
    }
  }
  EXPECT_GT(lost, 2000);
  EXPECT_LT(lost, 3000);
  c.noise_seed = 100;
  const MeasuredScan other = encodeOnce(c, r);
  EXPECT_NE(other.ranges, both.ranges);
}

// +Inf, -Inf and NaN readings get no bias, noise, quantisation or dropout, under every option.
TEST(MeasurementModelRealism, InvalidReadingsGetNone) {
  ScanResult r = uniformResult(3000, 0.0);
  for (int i = 0; i < 3000; ++i) {
    r.range[i] = i % 3 == 0 ? kInf : i % 3 == 1 ? 0.2 : kNan;
    if (i % 3 != 1) r.body[i] = -1;
  }
  for (const MinRangePolicy policy : {MinRangePolicy::kNegInf, MinRangePolicy::kNan}) {
    MeasurementConfig c = measurementConfig(0.5, 10.0, policy);
    c.range_bias = 0.7;  // would carry the too-close 0.2 m past range_min
    c.range_resolution = 0.25;
    c.noise_stddev = 0.5;
    c.dropout_probability = 0.5;
    const MeasuredScan out = encodeOnce(c, r);
    for (int i = 0; i < 3000; ++i) {
      if (i % 3 == 0) {
        ASSERT_EQ(out.ranges[i], kInfF) << i;
      } else if (i % 3 == 1) {
        ASSERT_TRUE(policy == MinRangePolicy::kNan ? std::isnan(out.ranges[i])
                                                   : out.ranges[i] == -kInfF)
            << i;
        ASSERT_EQ(out.labels[i], 0) << i;  // the too-close hit keeps its label
      } else {
        ASSERT_TRUE(std::isnan(out.ranges[i])) << i;
      }
    }
  }
}

// setConfig: the same seed continues both sequences, a new seed restarts them, a bad config is
// refused and the old one kept.
TEST(MeasurementModelRealism, SetConfig) {
  const laser_raycast::core::Scene scene = labelledScene();
  const ScanResult r = uniformResult(500, 4.0);
  MeasurementConfig c = measurementConfig(0.5, 10.0);
  c.noise_stddev = 0.02;
  c.dropout_probability = 0.2;
  c.noise_seed = 5;
  MeasurementModel reference(c), changed(c);
  MeasuredScan first, expected, out;
  reference.measure(scene, r, {}, &first);
  reference.measure(scene, r, {}, &expected);
  changed.measure(scene, r, {}, &out);
  changed.setConfig(c);
  changed.measure(scene, r, {}, &out);
  EXPECT_EQ(out.ranges, expected.ranges);  // continued
  c.noise_seed = 6;
  changed.setConfig(c);
  changed.measure(scene, r, {}, &out);
  EXPECT_EQ(out.ranges, encodeOnce(c, r).ranges);  // restarted from seed 6
  c.noise_seed = 5;
  changed.setConfig(c);
  changed.measure(scene, r, {}, &out);
  EXPECT_EQ(out.ranges, first.ranges);  // back to seed 5 from its start
  MeasurementConfig bad = c;
  bad.dropout_probability = 2;
  EXPECT_THROW(changed.setConfig(bad), std::invalid_argument);
  changed.measure(scene, r, {}, &out);
  EXPECT_EQ(out.ranges, expected.ranges);  // seed 5's second scan: the old config, continued
}

}  // namespace
}  // namespace laser_raycast_test
