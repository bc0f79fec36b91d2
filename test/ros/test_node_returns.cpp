// rostest node_returns.test: with ~return_mode dual, a beam that straddles the box's edge is two
// points of the cloud, the box's face at 2 m (return 1, the strongest: the box's share of the
// footprint is nearer, so stronger) and the wall at 3 m (return 2, the last), and a beam on the
// wall alone is one point; the `return` field says which, each point lies along its beam at the
// range worked out here, and every point has an intensity in (0, 1].
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <map>
#include <utility>

#include "driver_layouts.h"
#include "first_message.h"

namespace laser_raycast_test {
namespace {

TEST(NodeReturns, AStraddlingBeamIsTwoPoints) {
  tf2_ros::StaticTransformBroadcaster statics;
  geometry_msgs::TransformStamped t;
  t.header.stamp = ros::Time::now();
  t.header.frame_id = "base";
  t.child_frame_id = "lidar";
  t.transform.rotation.w = 1;
  statics.sendTransform(t);
  const auto cloud = firstMessage<sensor_msgs::PointCloud2>("/points", 30.0);
  ASSERT_TRUE(cloud);
  ASSERT_FALSE(cloud->fields.empty());
  EXPECT_EQ(cloud->fields.back().name, "return");
  EXPECT_EQ(cloud->fields.back().datatype, sensor_msgs::PointField::UINT8);
  // Two rings x (two returns on the straddling beam + one on the wall's).
  ASSERT_EQ(cloud->width * cloud->height, 6u);
  // By (ring, azimuth column), the returns found, each its range.
  std::map<std::pair<int, int>, std::map<int, double>> found;
  for (std::size_t i = 0; i < 6; ++i) {
    const Eigen::Vector3d p = pointAt(*cloud, i);
    const int ring = fieldValue<std::uint16_t>(*cloud, i, "ring");
    const int which = fieldValue<std::uint8_t>(*cloud, i, "return");
    const double azimuth = std::atan2(p.y(), p.x()), elevation = std::asin(p.z() / p.norm());
    const int column = azimuth < 0.1 ? 0 : 1;
    EXPECT_NEAR(azimuth, column == 0 ? 0.002 : 0.202, 1e-5) << i;
    EXPECT_NEAR(elevation, ring == 0 ? -0.01 : 0.01, 1e-5) << i;
    // The calibrated reflectivity of a return's share of the footprint: 0-100.
    const float intensity = fieldValue<float>(*cloud, i, "intensity");
    EXPECT_GT(intensity, 0.0f) << i;
    EXPECT_LE(intensity, 100.0f) << i;
    found[{ring, column}][which] = p.norm();
  }
  for (int ring = 0; ring < 2; ++ring) {
    SCOPED_TRACE(ring);
    const double cos_el = std::cos(ring == 0 ? -0.01 : 0.01);
    const auto& straddling = found[{ring, 0}];
    ASSERT_EQ(straddling.size(), 2u);
    // The box's face x = 2 and the wall's x = 3 along the beam's centre, to the footprint's
    // spread in range (sub-rays 0.01 rad off the centre).
    EXPECT_NEAR(straddling.at(1), 2 / (cos_el * std::cos(0.002)), 1e-3);
    EXPECT_NEAR(straddling.at(2), 3 / (cos_el * std::cos(0.002)), 1e-3);
    const auto& wall = found[{ring, 1}];
    ASSERT_EQ(wall.size(), 1u);
    EXPECT_NEAR(wall.at(1), 3 / (cos_el * std::cos(0.202)), 1e-3);
  }
}

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_returns");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
