// REP 117 encoding: classifyRange and MeasurementModel. Out of range is +Inf, too close -Inf (or NaN by
// policy), erroneous NaN, valid iff range_min <= r <= range_max; noise is seeded, clamped and only
// on valid beams; intensity is reflectivity x cos(incidence); one rounding to float.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "measurement_inputs.h"
#include "expect_invalid.h"
#include "laser_raycast/core/measurement_model.h"
#include "laser_raycast/core/scan_spec.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

bool sameFloat(float a, float b) { return a == b || (std::isnan(a) && std::isnan(b)); }

// -------------------------------------------------------------------------------------------------
// classifyRange

// Hits inside [range_min, range_max] are themselves, both bounds included; no hit or a hit past
// range_max is +Inf; NaN stays NaN whatever the policy.
TEST(ClassifyRange, ValidOutOfRangeAndNan) {
  for (const MinRangePolicy policy :
       {MinRangePolicy::kNegInf, MinRangePolicy::kPassThrough, MinRangePolicy::kNan}) {
    const MeasurementConfig c = measurementConfig(0.5, 10.0, policy);
    EXPECT_EQ(classifyRange(5.25, c), 5.25);
    EXPECT_EQ(classifyRange(0.5, c), 0.5);    // exactly range_min: valid
    EXPECT_EQ(classifyRange(10.0, c), 10.0);  // exactly range_max: valid
    EXPECT_EQ(classifyRange(std::nextafter(10.0, kInf), c), kInf);
    EXPECT_EQ(classifyRange(kInf, c), kInf);
    EXPECT_TRUE(std::isnan(classifyRange(kNan, c)));
  }
  // range_min 0: a zero range is valid.
  EXPECT_EQ(classifyRange(0.0, measurementConfig(0.0, 1.0)), 0.0);
}

// A hit closer than range_min: -Inf by default (REP 117: too close), NaN with "nan". With
// "pass_through" the cast should have started at range_min (ScanSpec::castConfig), so such a hit
// means the caller cast from 0; it is reported as +Inf, never as a valid range.
TEST(ClassifyRange, TooClosePolicies) {
  EXPECT_EQ(classifyRange(0.3, measurementConfig(0.5, 10.0)), -kInf);
  EXPECT_EQ(classifyRange(std::nextafter(0.5, 0.0), measurementConfig(0.5, 10.0)), -kInf);
  EXPECT_EQ(classifyRange(0.0, measurementConfig(0.5, 10.0)), -kInf);
  EXPECT_TRUE(std::isnan(classifyRange(0.3, measurementConfig(0.5, 10.0, MinRangePolicy::kNan))));
  EXPECT_EQ(classifyRange(0.3, measurementConfig(0.5, 10.0, MinRangePolicy::kPassThrough)), kInf);
  EXPECT_EQ(MeasurementConfig{}.min_range_policy, MinRangePolicy::kNegInf);  // the default
}

TEST(MinRangePolicy, StringRoundTrip) {
  for (const MinRangePolicy p :
       {MinRangePolicy::kNegInf, MinRangePolicy::kPassThrough, MinRangePolicy::kNan}) {
    MinRangePolicy parsed =
        p == MinRangePolicy::kNan ? MinRangePolicy::kNegInf : MinRangePolicy::kNan;
    EXPECT_TRUE(kMinRangePolicyNames.parse(toString(p), &parsed)) << toString(p);
    EXPECT_EQ(parsed, p);
  }
  EXPECT_STREQ(toString(MinRangePolicy::kNegInf), "-inf");
  EXPECT_STREQ(toString(MinRangePolicy::kPassThrough), "pass_through");
  EXPECT_STREQ(toString(MinRangePolicy::kNan), "nan");
  MinRangePolicy untouched = MinRangePolicy::kPassThrough;
  for (const char* bad : {"", "inf", "NaN", "pass-through", "-Inf", " nan"}) {
    EXPECT_FALSE(kMinRangePolicyNames.parse(bad, &untouched)) << bad;
    EXPECT_EQ(untouched, MinRangePolicy::kPassThrough);
  }
}

TEST(MeasurementConfig, ValidateNamesFieldAndValue) {
  auto message = [](const MeasurementConfig& c) { return invalidMessage([&] { c.validate(); }); };
  EXPECT_NO_THROW(MeasurementConfig{}.validate());
  EXPECT_NO_THROW(measurementConfig(0, 0.001).validate());
  MeasurementConfig c;
  c.range_min = -0.25;
  expectMentions(message(c), {"range_min", "-0.25"});
  c.range_min = kNan;
  expectMentions(message(c), {"range_min", "nan"});
  c.range_min = kInf;
  expectMentions(message(c), {"range_min", "inf"});
  c = measurementConfig(2.5, 2.5);
  expectMentions(message(c), {"range_max", "2.5", "range_min"});
  c = measurementConfig(2.5, 1.5);
  expectMentions(message(c), {"range_max", "1.5", "range_min", "2.5"});
  c = measurementConfig(0, kInf);  // REP 117 ranges need a finite maximum
  expectMentions(message(c), {"range_max", "inf"});
  c = measurementConfig(0, kNan);
  expectMentions(message(c), {"range_max", "nan"});
  // Finite in double but +Inf as a float: a valid reading would be published as "no return".
  c = measurementConfig(0, 1e39);
  expectMentions(message(c), {"range_max", "1e+39", "float"});
  EXPECT_NO_THROW(measurementConfig(0, std::numeric_limits<float>::max()).validate());
  c = MeasurementConfig{};
  c.noise_stddev = -0.01;
  expectMentions(message(c), {"noise_stddev", "-0.01"});
  c.noise_stddev = kNan;
  expectMentions(message(c), {"noise_stddev", "nan"});
  c.noise_stddev = kInf;
  expectMentions(message(c), {"noise_stddev", "inf"});
  // The measurement model validates its config.
  EXPECT_THROW(MeasurementModel{c}, std::invalid_argument);
}

// -------------------------------------------------------------------------------------------------
// MeasurementModel

// Each beam kind once (for range_min 0.5, range_max 10): valid, both bounds, no hit, too close,
// NaN; bodies of four labels and none.
ScanResult rep117Result() {
  ScanResult r;
  r.range = {1.2345678901234567, 0.5, 10.0, kInf, 0.25, kNan, 3.0, 7.777777777777777};
  r.body = {0, 1, 2, -1, 3, -1, 3, 1};
  r.triangle.assign(r.range.size(), -1);
  return r;
}

// Each beam kind by hand: valid ranges rounded once to float, +Inf, -Inf, NaN; labels from the
// body's label (also for too-close hits), -1 where nothing was hit.
TEST(MeasurementModel, Rep117AndLabels) {
  const Scene scene = labelledScene();
  const ScanResult r = rep117Result();
  for (const MinRangePolicy policy :
       {MinRangePolicy::kNegInf, MinRangePolicy::kNan, MinRangePolicy::kPassThrough}) {
    MeasurementModel model(measurementConfig(0.5, 10.0, policy));
    MeasuredScan out;
    model.measure(scene, r, {}, &out);
    ASSERT_EQ(out.ranges.size(), r.range.size());
    ASSERT_EQ(out.labels.size(), r.range.size());
    EXPECT_TRUE(out.intensities.empty());
    // Rounded once: the float of the double range, not of some intermediate.
    EXPECT_EQ(out.ranges[0], static_cast<float>(1.2345678901234567));
    EXPECT_EQ(out.ranges[1], 0.5f);
    EXPECT_EQ(out.ranges[2], 10.0f);
    EXPECT_EQ(out.ranges[3], std::numeric_limits<float>::infinity());
    const float too_close =
        policy == MinRangePolicy::kNegInf ? -std::numeric_limits<float>::infinity()
        : policy == MinRangePolicy::kNan  ? std::numeric_limits<float>::quiet_NaN()
                                          : std::numeric_limits<float>::infinity();
    EXPECT_TRUE(sameFloat(out.ranges[4], too_close)) << toString(policy) << " " << out.ranges[4];
    EXPECT_TRUE(std::isnan(out.ranges[5]));
    EXPECT_EQ(out.ranges[6], 3.0f);
    EXPECT_EQ(out.ranges[7], static_cast<float>(7.777777777777777));
    EXPECT_EQ(out.labels, (std::vector<int>{0, 1, 2, -1, 1, -1, 1, 1}));
  }
}

// The policy end to end with the caster: a panel at 0.3 m in front of a wall at 3 m, range_min 0.5.
// -inf and nan cast from 0 and report the panel as too close; pass_through casts from range_min
// (ScanSpec::castConfig) and reports the wall behind it.
TEST(MeasurementModel, PassThroughShowsTheSurfaceBeyond) {
  Scene scene;
  scene.addFrame("world");
  scene.addLabel("wall");
  scene.addLabel("panel");
  auto quad = [](double x, double half) {
    const std::vector<Eigen::Vector3d> v = {
        Eigen::Vector3d(x, -half, -half), Eigen::Vector3d(x, half, -half),
        Eigen::Vector3d(x, half, half), Eigen::Vector3d(x, -half, half)};
    return std::make_shared<const Mesh>(v, std::vector<TriangleIndices>{{0, 1, 2}, {0, 2, 3}});
  };
  Body wall;
  wall.shape = quad(3.0, 5.0);
  wall.label = 0;
  scene.addBody(wall);
  Body panel;
  panel.shape = quad(0.3, 0.05);  // only the middle three beams cross it
  panel.label = 1;
  scene.addBody(panel);
  FanSpec fan;
  fan.angle_min = -0.5;
  fan.angle_max = 0.5;
  fan.samples = 11;
  const ScanPattern pattern(fan);
  const int mid = 5;  // azimuth 0: through the panel's centre
  for (const bool fast : {true, false}) {
    for (const MinRangePolicy policy :
         {MinRangePolicy::kNegInf, MinRangePolicy::kNan, MinRangePolicy::kPassThrough}) {
      ScanSpec spec;
      spec.output = measurementConfig(0.5, 10.0, policy);
      const MeasurementConfig& ec = spec.output;
      CastConfig cc = spec.castConfig();
      cc.planar_fast_path = fast;
      Caster caster;
      const ScanResult& r = caster.cast(scene, FramePoses::identity(scene),
                                        Eigen::Isometry3d::Identity(), pattern, cc);
      MeasurementModel model(ec);
      MeasuredScan out;
      model.measure(scene, r, {}, &out);
      if (policy == MinRangePolicy::kPassThrough) {
        EXPECT_EQ(out.ranges[mid], 3.0f);
        EXPECT_EQ(out.labels[mid], 0);
      } else {
        EXPECT_TRUE(policy == MinRangePolicy::kNan
                        ? std::isnan(out.ranges[mid])
                        : out.ranges[mid] == -std::numeric_limits<float>::infinity())
            << out.ranges[mid];
        EXPECT_EQ(out.labels[mid], 1);  // the label of what was too close
      }
      // The outer beams miss the panel and see the wall at 3 / cos a under every policy.
      EXPECT_EQ(out.ranges[0], static_cast<float>(r.range[0]));
      EXPECT_NEAR(r.range[0], 3 / std::cos(0.5), 1e-12);
    }
  }
}

// Noise is seeded: equal seeds give equal scans, different seeds different ones, and every call
// draws afresh (a second encode of the same result differs).
TEST(MeasurementModel, NoiseIsSeededAndFresh) {
  const Scene scene = labelledScene();
  const ScanResult r = uniformResult(200, 4.0);
  MeasurementConfig c = measurementConfig(0.1, 20.0);
  c.noise_stddev = 0.02;
  c.noise_seed = 42;
  MeasurementModel a(c), b(c);
  c.noise_seed = 43;
  MeasurementModel other(c);
  MeasuredScan ea, eb, eo, ea2;
  a.measure(scene, r, {}, &ea);
  b.measure(scene, r, {}, &eb);
  other.measure(scene, r, {}, &eo);
  a.measure(scene, r, {}, &ea2);
  EXPECT_EQ(ea.ranges, eb.ranges);
  EXPECT_NE(ea.ranges, eo.ranges);
  EXPECT_NE(ea.ranges, ea2.ranges);
  int changed = 0;
  for (const float x : ea.ranges) changed += x != 4.0f;
  EXPECT_GT(changed, 190);
  // The second call of a continues the same sequence as b's second call.
  MeasuredScan eb2;
  b.measure(scene, r, {}, &eb2);
  EXPECT_EQ(ea2.ranges, eb2.ranges);
}

// Zero-mean Gaussian with the configured standard deviation: 10^4 samples, mean within 4 standard
// errors, sample standard deviation within 5% (its own standard error is about 0.7%).
TEST(MeasurementModel, NoiseStatistics) {
  const Scene scene = labelledScene();
  const int n = 10000;
  const double range = 5.0, sigma = 0.01;
  const ScanResult r = uniformResult(n, range);
  MeasurementConfig c = measurementConfig(0.0, 10.0);
  c.noise_stddev = sigma;
  c.noise_seed = 2024;
  MeasurementModel model(c);
  MeasuredScan out;
  model.measure(scene, r, {}, &out);
  double sum = 0, sum2 = 0;
  for (const float x : out.ranges) {
    const double e = static_cast<double>(x) - range;
    sum += e;
    sum2 += e * e;
  }
  const double mean = sum / n;
  const double stddev = std::sqrt(sum2 / n - mean * mean);
  EXPECT_LT(std::abs(mean), 4 * sigma / std::sqrt(n));
  EXPECT_NEAR(stddev, sigma, 0.05 * sigma);
}

// Noise keeps a valid return valid: results are clamped to [range_min, range_max] (hits right at
// the bounds with large noise pile up exactly there); invalid beams (+Inf, -Inf, NaN) get none.
TEST(MeasurementModel, NoiseIsClampedAndOnlyOnValidBeams) {
  const Scene scene = labelledScene();
  ScanResult r = uniformResult(4000, 0.0);
  for (int i = 0; i < 4000; ++i) {
    switch (i % 5) {
      case 0:
        r.range[i] = 0.5;
        break;  // at range_min
      case 1:
        r.range[i] = 10.0;
        break;  // at range_max
      case 2:
        r.range[i] = kInf;
        r.body[i] = -1;
        break;
      case 3:
        r.range[i] = 0.2;
        break;  // too close
      default:
        r.range[i] = kNan;
        r.body[i] = -1;
    }
  }
  MeasurementConfig c = measurementConfig(0.5, 10.0);
  c.noise_stddev = 1.0;
  MeasurementModel model(c);
  MeasuredScan out;
  model.measure(scene, r, {}, &out);
  int at_min = 0, at_max = 0, moved_min = 0, moved_max = 0;
  for (int i = 0; i < 4000; ++i) {
    const float x = out.ranges[i];
    switch (i % 5) {
      case 0:
      case 1:
        ASSERT_GE(x, 0.5f) << i;
        ASSERT_LE(x, 10.0f) << i;
        if (i % 5 == 0) (x == 0.5f ? at_min : moved_min)++;
        if (i % 5 == 1) (x == 10.0f ? at_max : moved_max)++;
        break;
      case 2:
        ASSERT_EQ(x, std::numeric_limits<float>::infinity()) << i;
        break;
      case 3:
        ASSERT_EQ(x, -std::numeric_limits<float>::infinity()) << i;
        break;
      default:
        ASSERT_TRUE(std::isnan(x)) << i;
    }
  }
  // About half of each bound's beams are pushed outward and clamped back, half move inward.
  EXPECT_GT(at_min, 300);
  EXPECT_GT(moved_min, 300);
  EXPECT_GT(at_max, 300);
  EXPECT_GT(moved_max, 300);
}

// Without noise the output is the range itself (to float), every call.
TEST(MeasurementModel, NoNoiseIsExact) {
  const Scene scene = labelledScene();
  ScanResult r = uniformResult(50, 0.0);
  for (int i = 0; i < 50; ++i) r.range[i] = 0.5 + 0.1234567891234 * i;
  MeasurementModel model(measurementConfig(0.5, 10.0));
  for (int call = 0; call < 2; ++call) {
    MeasuredScan out;
    model.measure(scene, r, {}, &out);
    for (int i = 0; i < 50; ++i) EXPECT_EQ(out.ranges[i], static_cast<float>(r.range[i])) << i;
  }
}

// With nothing configured to degrade or detect, measure() takes a path of its own per beam; it must
// give what the general path gives. The general one is forced by a dropout of 1e-300 (a draw below
// it would have to be exactly 0: none of these 8 seeded draws is).
TEST(MeasurementModel, IdealPathIsTheGeneralOne) {
  const Scene scene = labelledScene();
  const ScanResult r = rep117Result();
  for (const MinRangePolicy policy :
       {MinRangePolicy::kNegInf, MinRangePolicy::kNan, MinRangePolicy::kPassThrough}) {
    MeasurementConfig ideal = measurementConfig(0.5, 10.0, policy);
    ASSERT_TRUE(ideal.isIdeal());
    MeasurementConfig general = ideal;
    general.dropout_probability = 1e-300;
    ASSERT_FALSE(general.isIdeal());
    MeasuredScan a, b;
    MeasurementModel(ideal).measure(scene, r, {}, &a);
    MeasurementModel(general).measure(scene, r, {}, &b);
    ASSERT_EQ(a.ranges.size(), b.ranges.size());
    for (std::size_t i = 0; i < a.ranges.size(); ++i) {
      EXPECT_TRUE(sameFloat(a.ranges[i], b.ranges[i])) << toString(policy) << " beam " << i;
    }
    EXPECT_EQ(a.labels, b.labels) << toString(policy);
  }
}

// Intensity = reflectivity[label] * cos_incidence for valid hits, 0 for anything else; labels
// beyond the reflectivity table count as 1; asking for intensity without incidence throws.
TEST(MeasurementModel, Intensity) {
  const Scene scene = labelledScene();
  ScanResult r;
  r.range = {2.0, 3.0, 4.0, 5.0, kInf, 0.2, kNan, 6.0};
  r.body = {0, 1, 2, 3, -1, 0, -1, 2};
  r.triangle.assign(r.range.size(), -1);
  r.cos_incidence = {1.0, 0.5, 0.25, 0.8, 0.0, 0.9, 0.0, 0.3};
  const std::vector<double> reflectivity = {0.9, 0.4};  // wall, table; robot missing -> 1
  MeasurementConfig c = measurementConfig(0.5, 10.0);
  c.intensity = true;
  MeasurementModel model(c);
  MeasuredScan out;
  model.measure(scene, r, reflectivity, &out);
  ASSERT_EQ(out.intensities.size(), r.range.size());
  EXPECT_EQ(out.intensities[0], static_cast<float>(0.9 * 1.0));
  EXPECT_EQ(out.intensities[1], static_cast<float>(0.4 * 0.5));
  EXPECT_EQ(out.intensities[2], static_cast<float>(1.0 * 0.25));  // label 2 has no entry
  EXPECT_EQ(out.intensities[3], static_cast<float>(0.4 * 0.8));   // body 3 has label 1
  EXPECT_EQ(out.intensities[4], 0.0f);                            // no hit
  EXPECT_EQ(out.intensities[5], 0.0f);                            // too close: not a valid return
  EXPECT_EQ(out.intensities[6], 0.0f);                            // NaN
  EXPECT_EQ(out.intensities[7], static_cast<float>(1.0 * 0.3));
  // An empty table: every label counts as 1.
  model.measure(scene, r, {}, &out);
  EXPECT_EQ(out.intensities[1], 0.5f);
  // Intensity off: no intensities, even with incidence available.
  MeasurementModel plain(measurementConfig(0.5, 10.0));
  plain.measure(scene, r, reflectivity, &out);
  EXPECT_TRUE(out.intensities.empty());
  // Intensity on without incidence (or with the wrong count): an error, not garbage.
  ScanResult no_incidence = r;
  no_incidence.cos_incidence.clear();
  EXPECT_THROW(model.measure(scene, no_incidence, reflectivity, &out), std::invalid_argument);
  no_incidence.cos_incidence.assign(3, 1.0);
  EXPECT_THROW(model.measure(scene, no_incidence, reflectivity, &out), std::invalid_argument);
}

// Intensity end to end: a wall mesh hit head-on and at 60 degrees, reflectivity 0.8.
TEST(MeasurementModel, IntensityFromCaster) {
  Scene scene;
  scene.addFrame("world");
  scene.addLabel("wall");
  const std::vector<Eigen::Vector3d> v = {Eigen::Vector3d(3, -10, -10), Eigen::Vector3d(3, 10, -10),
                                          Eigen::Vector3d(3, 10, 10), Eigen::Vector3d(3, -10, 10)};
  Body wall;
  wall.shape = std::make_shared<const Mesh>(v, std::vector<TriangleIndices>{{0, 1, 2}, {0, 2, 3}});
  scene.addBody(wall);
  FanSpec fan;
  fan.angle_min = -M_PI / 3;
  fan.angle_max = M_PI / 3;
  fan.samples = 3;
  CastConfig cc;
  cc.compute_incidence = true;
  Caster caster;
  const ScanResult& r = caster.cast(scene, FramePoses::identity(scene),
                                    Eigen::Isometry3d::Identity(), ScanPattern(fan), cc);
  MeasurementConfig ec = measurementConfig(0.1, 30.0);
  ec.intensity = true;
  MeasurementModel model(ec);
  MeasuredScan out;
  model.measure(scene, r, {0.8}, &out);
  EXPECT_NEAR(out.intensities[1], 0.8, 1e-7);
  EXPECT_NEAR(out.intensities[0], 0.4, 1e-7);
  EXPECT_NEAR(out.intensities[2], 0.4, 1e-7);
  EXPECT_NEAR(out.ranges[0], 6.0, 1e-6);
}

}  // namespace
}  // namespace laser_raycast_test
