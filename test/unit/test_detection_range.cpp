// The radiometric range limit (measurement_model.h, detected()): walls of known reflectivity
// against the datasheet pair's analytic range, rho cos(theta) / r^2 >= rho_d / R^2.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/measurement_model.h"

namespace laser_raycast {
namespace {

// A wall (a thin box) whose face x = distance faces the sensor at the origin.
core::Scene wallAt(double distance) {
  core::Scene scene;
  core::Body body;
  body.shape = core::Box{Eigen::Vector3d(0.1, 400, 400)};
  body.frame = scene.addFrame("world");
  body.label = scene.addLabel("wall");
  body.frame_from_body.translation() = Eigen::Vector3d(distance + 0.05, 0, 0);
  scene.addBody(body);
  return scene;
}

core::MeasuredScan measure(const core::Scene& scene, const core::ScanPattern& pattern,
                           const core::MeasurementConfig& config, double reflectivity) {
  core::CastConfig cast;
  cast.tmax = config.range_max;
  cast.compute_incidence = config.needsIncidence();
  core::Caster caster;
  const core::ScanResult& result = caster.cast(scene, core::FramePoses::identity(scene),
                                               Eigen::Isometry3d::Identity(), pattern, cast);
  core::MeasurementModel model(config);
  core::MeasuredScan out;
  model.measure(scene, result, {reflectivity}, &out);
  return out;
}

core::MeasurementConfig datasheet(double range, double reflectivity) {
  core::MeasurementConfig config;
  config.range_max = 1000;
  config.detection_range = range;
  config.detection_reflectivity = reflectivity;
  return config;
}

core::ScanPattern straightAhead() {
  core::FanSpec fan;
  fan.angle_min = 0;
  fan.angle_max = 1e-6;
  fan.samples = 2;
  return core::ScanPattern(fan);
}

TEST(DetectionRange, AWallOfTheDatasheetsReflectivityIsSeenUpToItsRangeAndNotBeyond) {
  const core::MeasurementConfig config = datasheet(100, 0.1);
  for (const double d : {1.0, 50.0, 99.9, 99.999}) {
    const core::MeasuredScan m = measure(wallAt(d), straightAhead(), config, 0.1);
    EXPECT_NEAR(m.ranges[0], d, 1e-4) << "wall at " << d << " m";
    EXPECT_EQ(m.labels[0], 0);
  }
  for (const double d : {100.001, 100.1, 150.0}) {
    const core::MeasuredScan m = measure(wallAt(d), straightAhead(), config, 0.1);
    EXPECT_EQ(m.ranges[0], INFINITY) << "wall at " << d << " m";
    EXPECT_EQ(m.labels[0], -1);
  }
  // Four times the reflectivity: twice the range.
  EXPECT_NEAR(measure(wallAt(199.9), straightAhead(), config, 0.4).ranges[0], 199.9, 1e-3);
  EXPECT_EQ(measure(wallAt(200.1), straightAhead(), config, 0.4).ranges[0], INFINITY);
  // Off (detection_range 0): seen at any range.
  EXPECT_NEAR(measure(wallAt(500), straightAhead(), datasheet(0, 0.1), 0.01).ranges[0], 500, 1e-3);
}

TEST(DetectionRange, GrazingBeamsDropOutWhereCosineOverRangeSquaredFallsBelowTheThreshold) {
  // A wall 60 m ahead, reflectivity 0.1, datasheet 100 m at 10%: the beam at azimuth phi meets it
  // at r = 60 / cos(phi) with cos(theta) = cos(phi), detected iff cos(phi)^3 >= (60 / 100)^2.
  const double d = 60, R = 100;
  core::FanSpec fan;
  fan.angle_min = -1.2;
  fan.angle_max = 1.2;
  fan.samples = 2401;
  const core::ScanPattern pattern(fan);
  const core::MeasuredScan m = measure(wallAt(d), pattern, datasheet(R, 0.1), 0.1);
  int seen = 0, unseen = 0;
  for (int i = 0; i < pattern.size(); ++i) {
    const double phi = std::atan2(pattern.directions()[i].y(), pattern.directions()[i].x());
    const double margin = std::pow(std::cos(phi), 3) - (d / R) * (d / R);
    if (std::abs(margin) < 1e-9) continue;
    if (margin > 0) {
      EXPECT_NEAR(m.ranges[i], d / std::cos(phi), 1e-3 * d / std::cos(phi)) << "phi " << phi;
      ++seen;
    } else {
      EXPECT_EQ(m.ranges[i], INFINITY) << "phi " << phi;
      ++unseen;
    }
  }
  EXPECT_GT(seen, 100);
  EXPECT_GT(unseen, 100);
}

TEST(DetectionRange, BadDatasheetValuesAreRefusedNamingTheField) {
  core::MeasurementConfig config;
  config.detection_range = -1;
  EXPECT_THROW(config.validate(), std::invalid_argument);
  config.detection_range = 100;
  config.detection_reflectivity = 0;
  try {
    config.validate();
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("detection_reflectivity"), std::string::npos);
  }
}

}  // namespace
}  // namespace laser_raycast
