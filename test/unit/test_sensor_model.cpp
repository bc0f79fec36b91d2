// Sensor presets: each name finds its preset, the values are the datasheet's (worked out here in
// degrees, independently of the table), the patterns are valid ScanSpecs with the published beam
// counts, and apply() sets only what a preset owns.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "laser_raycast/core/measurement_model.h"
#include "laser_raycast/core/sensor_model.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast::core;

constexpr double kDeg = M_PI / 180;

ScanPattern patternOf(const SensorModel& model) {
  ScanSpec spec;
  double rate = 0;
  model.apply(&spec, &rate);
  return spec.pattern();  // validates
}

TEST(SensorModel, EveryNameFindsItsPreset) {
  std::set<std::string> names;
  for (const auto& [id, name] : kSensorModelNames.entries()) {
    const auto model = findSensorModel(name);
    ASSERT_TRUE(model) << name;
    EXPECT_EQ(model->id, id);
    EXPECT_EQ(model->name(), name);
    names.insert(name);
  }
  EXPECT_EQ(names,
            (std::set<std::string>{"VLP-16", "HDL-32E", "OS1-64", "UTM-30LX", "TiM571", "LDS-01"}));
  for (const char* bad : {"", "vlp-16", "VLP16", "VLP-16 ", "OS1-128", "HDL-64E"}) {
    EXPECT_FALSE(findSensorModel(bad)) << bad;
  }
  const std::string message = sensorModelProblem("VLP16");
  for (const char* name : {"'VLP16'", "VLP-16", "HDL-32E", "OS1-64", "UTM-30LX", "TiM571", "LDS-01",
                           "OS1-64-realistic"}) {
    EXPECT_NE(message.find(name), std::string::npos) << message;
  }
}

// The realistic variant of a preset whose datasheet gives the detection pair, the divergence and
// the return: OS1-64's (the first-generation OS1 datasheet: 40 m at 10% reflectivity, 0.13 deg,
// 1.2 cm range resolution, the strongest return); the same pattern, range limits and rate. The
// presets without them have no variant, and say why.
TEST(SensorModel, RealisticVariants) {
  const auto os1 = findSensorModel("OS1-64-realistic");
  ASSERT_TRUE(os1);
  EXPECT_TRUE(os1->realistic);
  EXPECT_EQ(os1->id, SensorModelId::kOs1_64);
  EXPECT_EQ(os1->name(), "OS1-64-realistic");
  ScanSpec spec, base_spec;
  double rate = 0, base_rate = 0;
  os1->apply(&spec, &rate);
  findSensorModel("OS1-64")->apply(&base_spec, &base_rate);
  EXPECT_EQ(spec.pattern().size(), base_spec.pattern().size());
  EXPECT_EQ(rate, base_rate);
  EXPECT_EQ(spec.output.range_max, 120.0);
  EXPECT_EQ(spec.output.detection_range, 40.0);
  EXPECT_EQ(spec.output.detection_reflectivity, 0.1);
  EXPECT_EQ(base_spec.output.detection_range, 0.0);  // the plain preset detects every hit
  // A 10% target head-on is seen to 40 m and no farther; an 80% one to sqrt(8) x 40 = 113 m (the
  // datasheet's 80% pair says 120 m: its threshold rho / R^2 is within 12% of the 10% pair's).
  EXPECT_TRUE(detected(0.1, 1.0, 39.99, spec.output));
  EXPECT_FALSE(detected(0.1, 1.0, 40.01, spec.output));
  EXPECT_TRUE(detected(0.8, 1.0, 113.1, spec.output));
  EXPECT_FALSE(detected(0.8, 1.0, 113.2, spec.output));
  EXPECT_FALSE(detected(0.1, 0.5, 30.0, spec.output));  // grazing at 60 degrees: 28.3 m at most
  EXPECT_NEAR((0.8 / (120.0 * 120.0)) / (0.1 / (40.0 * 40.0)), 1.0, 0.12);
  ReturnsConfig returns, base_returns;
  os1->applyReturns(&returns);
  findSensorModel("OS1-64")->applyReturns(&base_returns);
  EXPECT_NEAR(returns.beam_divergence, 0.13 * kDeg, 1e-15);
  EXPECT_EQ(returns.beam_samples, 7);
  EXPECT_EQ(returns.return_mode, ReturnMode::kStrongest);
  EXPECT_EQ(returns.min_return_separation, 0.012);
  EXPECT_NO_THROW(returns.validate());
  EXPECT_EQ(base_returns.beam_samples, 1);  // untouched
  for (const char* name : {"VLP-16", "HDL-32E", "UTM-30LX", "TiM571", "LDS-01"}) {
    const std::string variant = std::string(name) + "-realistic";
    EXPECT_FALSE(findSensorModel(variant)) << variant;
    const std::string why = sensorModelProblem(variant);
    EXPECT_NE(why.find("no realistic variant"), std::string::npos) << why;
    EXPECT_NE(why.find(name), std::string::npos) << why;
  }
  EXPECT_FALSE(findSensorModel("OS1-64-Realistic"));
  EXPECT_FALSE(findSensorModel("-realistic"));
}

// Beams per ring, rings, rate and range limits as the datasheets give them.
TEST(SensorModel, PublishedCountsRatesAndRanges) {
  struct Expected {
    const char* name;
    int rings, azimuths;
    double rate, range_min, range_max;
  };
  for (const Expected& e :
       {Expected{"VLP-16", 16, 1800, 10, 0.4, 100}, Expected{"HDL-32E", 32, 2170, 10, 0.4, 100},
        Expected{"OS1-64", 64, 1024, 10, 0.8, 120}, Expected{"UTM-30LX", 1, 1081, 40, 0.1, 30},
        Expected{"TiM571", 1, 811, 15, 0.05, 25}, Expected{"LDS-01", 1, 360, 5, 0.12, 3.5}}) {
    const SensorModel model = *findSensorModel(e.name);
    const ScanPattern pattern = patternOf(model);
    EXPECT_EQ(pattern.ringCount(), e.rings) << e.name;
    EXPECT_EQ(pattern.azimuthCount(), e.azimuths) << e.name;
    EXPECT_EQ(pattern.planar(), e.rings == 1) << e.name;
    EXPECT_EQ(model.rate, e.rate) << e.name;
    EXPECT_EQ(model.range_min, e.range_min) << e.name;
    EXPECT_EQ(model.range_max, e.range_max) << e.name;
  }
}

// The 360 degree lidars cover a full turn once: from -pi, spaced 2 pi / N, the last azimuth one
// increment short of +pi.
TEST(SensorModel, FullTurnsCastEachAzimuthOnce) {
  for (const char* name : {"VLP-16", "HDL-32E", "OS1-64"}) {
    const ScanPattern p = patternOf(*findSensorModel(name));
    const int n = p.azimuthCount();
    EXPECT_DOUBLE_EQ(p.angleMin(), -M_PI) << name;
    EXPECT_NEAR(p.angleIncrement(), 2 * M_PI / n, 1e-15) << name;
    EXPECT_NEAR(p.angleMax() + p.angleIncrement(), M_PI, 1e-12) << name;
  }
  // VLP-16: 0.2 deg at 600 rpm; HDL-32E: 0.1 s / 46.08 us cycles, about 0.166 deg.
  EXPECT_NEAR(patternOf(sensorModel(SensorModelId::kVlp16)).angleIncrement(), 0.2 * kDeg, 1e-15);
  EXPECT_NEAR(patternOf(sensorModel(SensorModelId::kHdl32e)).angleIncrement() / kDeg,
              360 * 10 * 46.08e-6, 2e-4);
}

TEST(SensorModel, PlanarSectors) {
  const ScanPattern utm = patternOf(sensorModel(SensorModelId::kUtm30lx));
  EXPECT_NEAR(utm.angleMin(), -135 * kDeg, 1e-15);
  EXPECT_NEAR(utm.angleMax(), 135 * kDeg, 1e-12);
  EXPECT_NEAR(utm.angleIncrement(), 0.25 * kDeg, 1e-15);
  const ScanPattern tim = patternOf(sensorModel(SensorModelId::kTim571));
  EXPECT_NEAR(tim.angleMin(), -135 * kDeg, 1e-15);
  EXPECT_NEAR(tim.angleMax(), 135 * kDeg, 1e-12);
  EXPECT_NEAR(tim.angleIncrement() / kDeg, 0.33, 0.004);
  const ScanPattern lds = patternOf(sensorModel(SensorModelId::kLds01));
  EXPECT_EQ(lds.angleMin(), 0.0);
  EXPECT_NEAR(lds.angleMax(), 359 * kDeg, 1e-12);
  EXPECT_NEAR(lds.angleIncrement(), 1 * kDeg, 1e-15);
}

// Ring elevations, ring 0 lowest: VLP-16 -15..15 by 2 deg; HDL-32E +10.67..-30.67 by 1.33 deg
// with a ring at 0; OS1-64 -16.6..16.6 by 33.2 / 63 deg.
TEST(SensorModel, RingElevations) {
  const ScanPattern vlp = patternOf(sensorModel(SensorModelId::kVlp16));
  for (int r = 0; r < 16; ++r) EXPECT_NEAR(vlp.elevations()[r], (-15 + 2 * r) * kDeg, 1e-15) << r;
  const ScanPattern hdl = patternOf(sensorModel(SensorModelId::kHdl32e));
  EXPECT_NEAR(hdl.elevations().front() / kDeg, -30.67, 0.005);
  EXPECT_NEAR(hdl.elevations().back() / kDeg, 10.67, 0.005);
  EXPECT_NEAR(hdl.elevations()[23], 0.0, 1e-15);
  for (int r = 1; r < 32; ++r) {
    EXPECT_NEAR((hdl.elevations()[r] - hdl.elevations()[r - 1]) / kDeg, 1.33, 0.004) << r;
  }
  const ScanPattern os1 = patternOf(sensorModel(SensorModelId::kOs1_64));
  EXPECT_NEAR(os1.elevations().front(), -16.6 * kDeg, 1e-15);
  EXPECT_NEAR(os1.elevations().back(), 16.6 * kDeg, 1e-15);
  for (int r = 1; r < 64; ++r) {
    EXPECT_NEAR(os1.elevations()[r] - os1.elevations()[r - 1], 33.2 / 63 * kDeg, 1e-15) << r;
  }
}

// apply() sets the pattern, the range limits and the rate, and nothing else; explicit settings
// made afterwards win.
TEST(SensorModel, ApplySetsOnlyWhatAPresetOwns) {
  ScanSpec spec;
  spec.output.noise_stddev = 0.01;
  spec.output.noise_seed = 7;
  spec.output.min_range_policy = MinRangePolicy::kNan;
  spec.output.intensity = true;
  spec.method = TriangleMethod::kMollerTrumbore;
  spec.cull_backfaces = true;
  spec.fan.samples = 99;
  double rate = 1;
  sensorModel(SensorModelId::kVlp16).apply(&spec, &rate);
  EXPECT_EQ(rate, 10.0);
  EXPECT_EQ(spec.fan.samples, 0);  // the preset's fan replaces the whole FanSpec
  EXPECT_EQ(spec.elevations.size(), 16u);
  EXPECT_EQ(spec.output.range_max, 100.0);
  EXPECT_EQ(spec.output.noise_stddev, 0.01);
  EXPECT_EQ(spec.output.noise_seed, 7u);
  EXPECT_EQ(spec.output.min_range_policy, MinRangePolicy::kNan);
  EXPECT_TRUE(spec.output.intensity);
  EXPECT_EQ(spec.method, TriangleMethod::kMollerTrumbore);
  EXPECT_TRUE(spec.cull_backfaces);
  // An explicit range_max and a narrower sector over the preset.
  spec.output.range_max = 50;
  spec.fan.angle_min = -M_PI / 2;
  spec.fan.angle_max = M_PI / 2;
  const ScanPattern p = spec.pattern();
  EXPECT_EQ(p.azimuthCount(), 901);  // 180 deg at 0.2 deg, both ends included
  EXPECT_EQ(p.ringCount(), 16);
  // A preset's sensor model with a bad id (a cast from a bad integer) is refused.
  EXPECT_THROW(sensorModel(static_cast<SensorModelId>(42)), std::invalid_argument);
}

// The Velodyne presets' heads are the lasers of their grids, by laser id as the manuals list them:
// sorted by elevation, the VLP-16's are its rings exactly, the HDL-32E's its rings as the table
// rounds them (to 0.01 deg). The OS1-64's comes from a metadata file; the planar ones have none.
TEST(SensorModel, TheVelodyneHeadsAreTheGridsLasers) {
  for (SensorModelId id : {SensorModelId::kVlp16, SensorModelId::kHdl32e}) {
    const SensorModel model = sensorModel(id);
    ASSERT_TRUE(model.head) << toString(id);
    std::vector<double> by_elevation;
    for (const VelodyneLaser& l : model.head->lasers) by_elevation.push_back(l.elevation);
    std::sort(by_elevation.begin(), by_elevation.end());
    const ScanPattern grid = patternOf(model);
    ASSERT_EQ(by_elevation.size(), grid.elevations().size()) << toString(id);
    const double tolerance = id == SensorModelId::kVlp16 ? 1e-15 : 0.005 * kDeg;
    for (std::size_t r = 0; r < by_elevation.size(); ++r) {
      EXPECT_NEAR(by_elevation[r], grid.elevations()[r], tolerance) << toString(id) << " " << r;
    }
    const BeamList turn = model.beams(1 / model.rate);
    EXPECT_NO_THROW(turn.validate());
    // As many firing sequences as fit in a turn: about the grid's azimuths (1808 against 1800 for
    // the VLP-16, whose grid is the datasheet's 0.2 deg; 2170 for the HDL-32E).
    const int sequences = turn.size() / static_cast<int>(by_elevation.size());
    EXPECT_EQ(sequences, static_cast<int>(1 / model.rate / model.head->timing.sequence_period));
    EXPECT_NEAR(sequences, grid.azimuthCount(), 8) << toString(id);
  }
  EXPECT_EQ(sensorModel(SensorModelId::kVlp16).head->timing.laser_period, 2.304e-6);
  EXPECT_EQ(sensorModel(SensorModelId::kHdl32e).head->timing.laser_period, 1.152e-6);
  for (SensorModelId id : {SensorModelId::kOs1_64, SensorModelId::kUtm30lx, SensorModelId::kTim571,
                           SensorModelId::kLds01}) {
    EXPECT_FALSE(sensorModel(id).head) << toString(id);
  }
  // The OS1-64's beams come from the nominal metadata file in the package (the loader reads it).
  EXPECT_EQ(sensorModel(SensorModelId::kOs1_64).head_file,
            "package://laser_raycast/config/ouster/os1_64_nominal.json");
  for (SensorModelId id : {SensorModelId::kVlp16, SensorModelId::kHdl32e, SensorModelId::kUtm30lx,
                           SensorModelId::kTim571, SensorModelId::kLds01}) {
    EXPECT_EQ(sensorModel(id).head_file, "") << toString(id);
  }
}

}  // namespace
}  // namespace laser_raycast_test
