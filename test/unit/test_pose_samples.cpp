// PoseSamples and interpolatePose: linear in position, slerp in rotation, clamped outside the
// samples, validity carried through, and bad samples named.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "cast_reference.h"
#include "expect_invalid.h"
#include "laser_raycast/core/pose.h"
#include "laser_raycast/core/pose_samples.h"

namespace laser_raycast_test {
namespace {

using core::PoseSamples;

double angleBetween(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

TEST(InterpolatePose, EndsAreTheSamplesAndTheMiddleIsHalfWay) {
  const Eigen::Isometry3d a = pose({1, 2, 3}, rpy(0.1, -0.2, 0.3));
  const Eigen::Isometry3d b = pose({-4, 6, 3.5}, rpy(0.4, 0.1, -1.2));
  // At a sample: its pose bit for bit, as an instant cast from it takes it (no quaternion and back).
  EXPECT_EQ(core::interpolatePose(a, b, 0).matrix(), a.matrix());
  EXPECT_TRUE(core::interpolatePose(a, b, 1).isApprox(b, 1e-14));
  const Eigen::Isometry3d m = core::interpolatePose(a, b, 0.25);
  EXPECT_TRUE(m.translation().isApprox(Eigen::Vector3d(-0.25, 3, 3.125), 1e-14));
  // A quarter of the way along the arc: a quarter of the angle from a, three quarters to b.
  const double whole = angleBetween(a.linear(), b.linear());
  EXPECT_NEAR(angleBetween(a.linear(), m.linear()), whole / 4, 1e-12);
  EXPECT_NEAR(angleBetween(m.linear(), b.linear()), 3 * whole / 4, 1e-12);
  EXPECT_NEAR((m.linear().transpose() * m.linear() - Eigen::Matrix3d::Identity()).norm(), 0, 1e-14);
}

TEST(InterpolatePose, TakesTheShorterArcAndKeepsFarPosesExact) {
  const Eigen::Isometry3d a = pose({1e6, -2e6, 10}, yaw(3.0));
  const Eigen::Isometry3d b = pose({1e6 + 2, -2e6, 10}, yaw(-3.0));  // 0.283 rad apart via pi
  const Eigen::Isometry3d m = core::interpolatePose(a, b, 0.5);
  EXPECT_NEAR(angleBetween(m.linear(), yaw(M_PI)), 0, 1e-12);
  EXPECT_EQ(m.translation().x(), 1e6 + 1);  // exact: the difference of nearby doubles
  EXPECT_EQ(m.translation().y(), -2e6);
}

PoseSamples twoSamples(const core::Scene& scene) {
  PoseSamples s;
  s.times = {0.0, 0.1};
  s.world_from_sensor = {pose({0, 0, 0}), pose({0.2, 0, 0})};
  s.frames = {core::FramePoses::identity(scene), core::FramePoses::identity(scene)};
  s.frames[1].pose[0] = pose({0, 1, 0});
  return s;
}

TEST(PoseSamples, BetweenSamplesInterpolatesOutsideClamps) {
  const core::Scene scene = sceneWithFrame();
  const PoseSamples s = twoSamples(scene);
  EXPECT_NO_THROW(s.validate(scene));
  EXPECT_NEAR(s.sensorAt(0.05).translation().x(), 0.1, 1e-15);
  EXPECT_NEAR(s.sensorAt(0.075).translation().x(), 0.15, 1e-15);
  EXPECT_EQ(s.sensorAt(-1).translation().x(), 0.0);
  EXPECT_EQ(s.sensorAt(7).translation().x(), 0.2);
  core::FramePoses f;
  s.framesAt(0.025, &f);
  ASSERT_EQ(f.valid.size(), 1u);
  EXPECT_TRUE(f.valid[0]);
  EXPECT_NEAR(f.pose[0].translation().y(), 0.25, 1e-15);
}

TEST(PoseSamples, AnInvalidNeighbourMakesThePoseInvalid) {
  const core::Scene scene = sceneWithFrame();
  PoseSamples s = twoSamples(scene);
  s.frames[1].valid[0] = 0;
  core::FramePoses f;
  s.framesAt(0.05, &f);
  EXPECT_FALSE(f.valid[0]);
  s.framesAt(-1, &f);  // clamped to the first sample, which is valid
  EXPECT_TRUE(f.valid[0]);
  s.world_from_sensor[1].translation().x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(core::isValidPose(s.sensorAt(0.05)));
  EXPECT_TRUE(core::isValidPose(s.sensorAt(0.0)));
}

TEST(PoseSamples, ValidateNamesTheProblem) {
  const core::Scene scene = sceneWithFrame();
  PoseSamples s;
  expectMentions(invalidMessage([&] { s.validate(scene); }), {"no samples"});
  s = twoSamples(scene);
  s.times = {0.0, 0.0};
  expectMentions(invalidMessage([&] { s.validate(scene); }), {"strictly ascending"});
  s = twoSamples(scene);
  s.times[1] = std::numeric_limits<double>::infinity();
  expectMentions(invalidMessage([&] { s.validate(scene); }), {"time 1", "not finite"});
  s = twoSamples(scene);
  s.world_from_sensor.pop_back();
  expectMentions(invalidMessage([&] { s.validate(scene); }), {"2 times", "1 sensor poses"});
  s = twoSamples(scene);
  s.frames[0].pose.push_back(pose({0, 0, 0}));
  expectMentions(invalidMessage([&] { s.validate(scene); }), {"sample 0", "2 frame poses"});
}

}  // namespace
}  // namespace laser_raycast_test
