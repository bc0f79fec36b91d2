// rostest intensity_example.test: the OS1-64 of launch/intensity_example.launch, 3 m in front of
// worlds/intensity_wall.urdf's checkerboard wall. Each point on the wall (x = 3 in the lidar's
// frame, |y|, |z| < 1) has the intensity of its texel (checker.png: 8 x 8 cells, white where
// column + row is even, u = (y + 1) / 2, v = (z + 1) / 2, row 0 at the top) times the cosine of
// its incidence, the x of its beam's direction (from the beam's origin to the point); each point
// on the pillar its URDF colour's luminance times its incidence on the cylinder; each point on
// the dark box the launch file's reflectivity 0.08 times its incidence on the face it meets.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>

#include <Eigen/Core>
#include <cmath>

#include "driver_layouts.h"
#include "first_message.h"

namespace laser_raycast_test {
namespace {

// Where the OS1-64 preset's beam of a point leaves from, by hand from the nominal metadata file it
// is cast from (config/ouster/os1_64_nominal.json, as ouster-sdk places its beams): the point's
// column c (its time t = c x 0.1 s / 1024) at encoder angle 2 pi (1 - c / 1024), its beam origin
// 12.163 mm out along that angle in the lidar frame, which the file's lidar_to_sensor_transform
// turns half a turn about z and raises 36.18 mm.
Eigen::Vector3d beamOrigin(std::uint32_t t_ns) {
  const double column = std::round(t_ns / (1e8 / 1024));
  const double encoder = 2 * M_PI * (1 - column / 1024);
  return Eigen::Vector3d(-0.012163 * std::cos(encoder), -0.012163 * std::sin(encoder), 0.03618);
}

TEST(IntensityExample, TheCloudShowsTheWorldsSurfaces) {
  const auto cloud = firstMessage<sensor_msgs::PointCloud2>("/points", 40.0);
  ASSERT_TRUE(cloud);
  const double kLuminanceRed = 0.2126 * 0.8 + 0.7152 * 0.15 + 0.0722 * 0.1;
  int wall = 0, white = 0, pillar = 0, box = 0;
  for (std::size_t i = 0; i < std::size_t{cloud->width} * cloud->height; ++i) {
    const Eigen::Vector3d p = pointAt(*cloud, i);
    if (!std::isfinite(p.x())) continue;
    // ouster-ros's reflectivity: the calibrated reflectivity, 100 x rho cos(theta), rounded; its
    // intensity the signal, that times (10 m / range)^2.
    const double reflectivity = fieldValue<std::uint16_t>(*cloud, i, "reflectivity");
    const double range = fieldValue<std::uint32_t>(*cloud, i, "range") / 1000.0;
    EXPECT_NEAR(fieldValue<float>(*cloud, i, "intensity"), reflectivity * 100 / (range * range),
                0.5 + 0.01 * reflectivity)
        << "point " << i;
    const double intensity = reflectivity / 100;
    constexpr double kRounding = 0.005 + 1e-5;  // half a unit of the reflectivity, over 100
    // The beam's direction, from its origin to the point.
    const Eigen::Vector3d d =
        (p - beamOrigin(fieldValue<std::uint32_t>(*cloud, i, "t"))).normalized();
    if (std::abs(p.x() - 3) < 1e-3 && std::abs(p.y()) < 0.999 && std::abs(p.z()) < 0.999) {
      const double column = (p.y() + 1) / 2 * 8, row = (1 - (p.z() + 1) / 2) * 8;
      // Points within float rounding of a cell's edge could be on either side.
      if (std::abs(column - std::round(column)) < 1e-3 || std::abs(row - std::round(row)) < 1e-3) {
        continue;
      }
      const bool is_white = (static_cast<int>(column) + static_cast<int>(row)) % 2 == 0;
      EXPECT_NEAR(intensity, is_white ? std::abs(d.x()) : 0.0, kRounding) << "wall point " << i;
      ++wall;
      white += is_white;
    } else if (std::hypot(p.x() - 2.2, p.y() + 1.8) < 0.2 + 1e-3 && p.z() > -1.2 + 1e-3 &&
               p.z() < 1.2 - 1e-3) {
      // The pillar's side (radius 0.2 m about x = 2.2, y = -1.8): its outward normal there.
      const Eigen::Vector3d n = Eigen::Vector3d(p.x() - 2.2, p.y() + 1.8, 0).normalized();
      EXPECT_NEAR(intensity, kLuminanceRed * std::abs(d.dot(n)), kRounding) << "pillar point " << i;
      ++pillar;
    } else if (std::abs(p.x() - 1.9) < 1e-3 && std::abs(p.y() - 1.8) < 0.3 - 1e-3 &&
               p.z() < -0.4 - 1e-3) {
      // The dark box's face x = 1.9 (a 0.6 m cube-ish box about x = 2.2, y = 1.8, z 0 to 0.8 in
      // the world: z below -0.4 in the lidar's frame), points within 1 mm of its edges left out.
      EXPECT_NEAR(intensity, 0.08 * std::abs(d.x()), kRounding) << "box point " << i;
      ++box;
    }
  }
  EXPECT_GT(wall, 1000);
  EXPECT_GT(white, wall / 3);
  EXPECT_LT(white, 2 * wall / 3);
  EXPECT_GT(pillar, 50);
  EXPECT_GT(box, 50);
}

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_intensity_example");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
