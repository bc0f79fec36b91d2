// A pulse's returns from a divergent beam (returns.h): a beam straddling a box edge 2 m in front of
// a wall 3 m away, against the sub-rays' ranges and powers computed here from the documented
// footprint pattern and the two planes.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "laser_raycast/core/returns.h"

namespace laser_raycast {
namespace {

// A wall whose face is the plane x = 3, and a box whose face x = 2 covers y < 0 (its edge on
// y = 0), both reflectivity 1 (label entries missing).
core::Scene boxBeforeWall() {
  core::Scene scene;
  const int frame = scene.addFrame("world");
  core::Body wall;
  wall.shape = core::Box{Eigen::Vector3d(0.2, 20, 20)};
  wall.frame = frame;
  wall.label = scene.addLabel("wall");
  wall.frame_from_body.translation() = Eigen::Vector3d(3.1, 0, 0);
  scene.addBody(wall);
  core::Body box;
  box.shape = core::Box{Eigen::Vector3d(0.4, 2, 2)};
  box.frame = frame;
  box.label = scene.addLabel("box");
  box.frame_from_body.translation() = Eigen::Vector3d(2.2, -1, 0);
  scene.addBody(box);
  return scene;
}

constexpr double kAzimuth = 0.002;  // the beam's centre, just past the edge (y = 0.004 at 2 m)

core::PulseReturns castOne(const core::ReturnsConfig& config) {
  const core::Scene scene = boxBeforeWall();
  core::FanSpec fan;
  fan.angle_min = kAzimuth;
  fan.angle_max = kAzimuth + 3.0;  // a second beam, backwards (misses everything)
  fan.samples = 2;
  core::Caster caster;
  core::PulseReturns out;
  core::castReturns(&caster, scene, core::FramePoses::identity(scene),
                    Eigen::Isometry3d::Identity(), fan, {0.0}, core::CastConfig{}, config, {}, {},
                    1.0, true, &out);
  return out;
}

// The sub-rays' hits computed from the planes: on the box (x = 2) if the sub-ray's y there is
// negative, else on the wall (x = 3); range d / (cos(az) cos(el)), cos(incidence) the same
// product, power share 1 / samples.
struct Expected {
  double box_range = 0, box_power = 0, wall_range = 0, wall_power = 0;
  double wall_rho_cos = 0;  // the wall's share of the footprint x cos(incidence)
  int box_hits = 0, wall_hits = 0;
};
Expected expected(const core::ReturnsConfig& config) {
  Expected e;
  for (int k = 0; k < config.beam_samples; ++k) {
    const Eigen::Vector2d o = config.offset(k);
    const double az = kAzimuth + o.x(), el = o.y();
    const double c = std::cos(az) * std::cos(el);
    const bool box = std::tan(az) < 0;
    const double d = box ? 2.0 : 3.0;
    const double r = d / c;
    const double power = c / config.beam_samples / (r * r);
    (box ? e.box_range : e.wall_range) += power * r;
    (box ? e.box_power : e.wall_power) += power;
    (box ? e.box_hits : e.wall_hits) += 1;
    if (!box) e.wall_rho_cos += c / config.beam_samples;
  }
  return e;
}

core::ReturnsConfig sevenSubRays(core::ReturnMode mode, double separation) {
  core::ReturnsConfig config;
  config.beam_divergence = 0.03;
  config.beam_samples = 7;
  config.return_mode = mode;
  config.min_return_separation = separation;
  return config;
}

TEST(Returns, ABeamStraddlingABoxEdgeGivesTwoReturnsInDualMode) {
  const core::ReturnsConfig config = sevenSubRays(core::ReturnMode::kDual, 0.5);
  const Expected e = expected(config);
  ASSERT_GT(e.box_hits, 0);
  ASSERT_GT(e.wall_hits, 0);
  const core::PulseReturns r = castOne(config);
  // The box's return is the stronger (nearer, and 3 of 7 sub-rays against 4 at 9/4 the r^2).
  ASSERT_GT(e.box_power, e.wall_power);
  EXPECT_NEAR(r.first.range[0], e.box_range / e.box_power, 1e-9);
  EXPECT_NEAR(r.second.range[0], e.wall_range / e.wall_power, 1e-9);
  EXPECT_EQ(r.first.body[0], 1);
  EXPECT_EQ(r.second.body[0], 0);
  EXPECT_NEAR(r.first.range[0], 2.0, 1e-3);
  EXPECT_NEAR(r.second.range[0], 3.0, 1e-3);
  // The beam that meets nothing has no return.
  EXPECT_EQ(r.first.range[1], INFINITY);
  EXPECT_EQ(r.second.range[1], INFINITY);
}

TEST(Returns, CloserThanTheSeparationTheSurfacesMergeIntoOneMixedRange) {
  const core::ReturnsConfig config = sevenSubRays(core::ReturnMode::kDual, 1.5);
  const Expected e = expected(config);
  const core::PulseReturns r = castOne(config);
  const double mixed = (e.box_range + e.wall_range) / (e.box_power + e.wall_power);
  EXPECT_NEAR(r.first.range[0], mixed, 1e-9);
  EXPECT_GT(r.first.range[0], 2.1);
  EXPECT_LT(r.first.range[0], 2.9);
  EXPECT_EQ(r.second.range[0], INFINITY);  // one return only
}

TEST(Returns, TheSingleReturnModesPickTheirReturn) {
  const Expected e = expected(sevenSubRays(core::ReturnMode::kFirst, 0.5));
  EXPECT_NEAR(castOne(sevenSubRays(core::ReturnMode::kFirst, 0.5)).first.range[0],
              e.box_range / e.box_power, 1e-9);
  EXPECT_NEAR(castOne(sevenSubRays(core::ReturnMode::kLast, 0.5)).first.range[0],
              e.wall_range / e.wall_power, 1e-9);
  EXPECT_NEAR(castOne(sevenSubRays(core::ReturnMode::kStrongest, 0.5)).first.range[0],
              e.box_range / e.box_power, 1e-9);
  // The return's reflectance is its share of the footprint times rho cos(theta).
  EXPECT_NEAR(castOne(sevenSubRays(core::ReturnMode::kLast, 0.5)).first_surface.reflectance[0],
              e.wall_rho_cos, 1e-12);
}

TEST(Returns, OneSampleIsTheIdealRayBitForBit) {
  core::ReturnsConfig config;
  config.beam_samples = 1;
  config.beam_divergence = 0.03;
  const core::PulseReturns r = castOne(config);
  const core::Scene scene = boxBeforeWall();
  core::FanSpec fan;
  fan.angle_min = kAzimuth;
  fan.angle_max = kAzimuth + 3.0;
  fan.samples = 2;
  core::Caster caster;
  const core::ScanResult& ideal =
      caster.cast(scene, core::FramePoses::identity(scene), Eigen::Isometry3d::Identity(),
                  core::ScanPattern(fan, {0.0}), core::CastConfig{});
  EXPECT_EQ(r.first.range, ideal.range);
  EXPECT_EQ(r.first.body, ideal.body);
}

TEST(Returns, BadSettingsAreRefusedNamingTheField) {
  core::ReturnsConfig config;
  config.beam_samples = 0;
  EXPECT_THROW(config.validate(), std::invalid_argument);
  config.beam_samples = 7;
  config.min_return_separation = -1;
  try {
    config.validate();
    ADD_FAILURE() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("min_return_separation"), std::string::npos);
  }
}

}  // namespace
}  // namespace laser_raycast
