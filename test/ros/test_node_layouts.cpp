// rostest node_layouts.test (nodelet_layouts.test: the nodelet): one sensor per ~point_layout
// (test/data/layouts_sensors.yaml), each publishing its driver's fields (names, offsets, types,
// point_step as written out in driver_layouts.h) with values that agree with the room they see
// (test/data/sensors_room.urdf, inner faces x = +-5, y = +-4, z = 0 and 4) and with the sweep's
// timing: every point on the room's faces at its ring's elevation and its column's azimuth, the
// times of its column in each layout's unit, range in mm and reflectivity as the intensity rounded
// where the layout has them.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "driver_layouts.h"
#include "sensors_rig.h"

namespace laser_raycast_test {
namespace {

using laser_raycast::PointLayout;

// The pattern of layouts_sensors.yaml: rings at -0.2, 0 and 0.2 rad, 37 azimuths every 10 deg from
// -pi, the head turning once in 0.1 s: column c taken c * 0.1 / 36 s after the stamp.
constexpr double kElevations[3] = {-0.2, 0.0, 0.2};
constexpr int kAzimuths = 37;
constexpr double kTimeIncrement = 0.1 / 36;  // s
const Eigen::Vector3d kSensor(0, 0, 1);      // every sensor's frame "lidar", not turned

// The first cloud of each sensor, by its name (= its layout's).
class Clouds {
 public:
  Clouds() {
    statics_.sendTransform(transform(ros::Time::now(), "lidar", kSensor, 0));
    for (const auto& [layout, name] : laser_raycast::kPointLayoutNames.entries()) {
      const std::string topic = "/" + std::string(name) + "/points";
      subs_.push_back(nh_.subscribe<sensor_msgs::PointCloud2>(
          topic, 1, [this, n = std::string(name)](const sensor_msgs::PointCloud2::ConstPtr& m) {
            std::lock_guard<std::mutex> lock(mutex_);
            first_.emplace(n, m);
          }));
    }
  }

  // The first cloud of sensor `name`, waiting up to 30 s (wall time); nullptr if none came.
  sensor_msgs::PointCloud2::ConstPtr first(const std::string& name) {
    const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(30.0);
    while (ros::ok() && ros::WallTime::now() < give_up) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        const auto it = first_.find(name);
        if (it != first_.end()) return it->second;
      }
      ros::WallDuration(0.01).sleep();
    }
    return nullptr;
  }

 private:
  ros::NodeHandle nh_;
  tf2_ros::StaticTransformBroadcaster statics_;
  std::vector<ros::Subscriber> subs_;
  std::mutex mutex_;
  std::map<std::string, sensor_msgs::PointCloud2::ConstPtr> first_;
};

Clouds* clouds = nullptr;

// Point i of a dense cloud in which every beam returns: ring i / kAzimuths, column i % kAzimuths.
// Its x y z must lie on the room's faces along that beam; `ring_field` is the layout's name for the
// ring. Returns the point's range.
double expectOnTheRoom(const sensor_msgs::PointCloud2& cloud, std::size_t i, const char* ring_field,
                       bool uint8_ring) {
  const int ring = static_cast<int>(i) / kAzimuths, column = static_cast<int>(i) % kAzimuths;
  const double el = kElevations[ring], az = -M_PI + column * M_PI / 18;
  const Eigen::Vector3d dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  const Eigen::Vector3d p = pointAt(cloud, i);
  EXPECT_LT((p - roomDistance(kSensor, dir) * dir).norm(), kTolerance) << "point " << i;
  const int ring_value = uint8_ring ? fieldValue<std::uint8_t>(cloud, i, ring_field)
                                    : fieldValue<std::uint16_t>(cloud, i, ring_field);
  EXPECT_EQ(ring_value, ring) << "point " << i;
  return p.norm();
}

double columnTime(std::size_t i) { return static_cast<int>(i) % kAzimuths * kTimeIncrement; }

// The calibrated reflectivity the drivers report for point i: 100 x its surface's reflectivity 0.9
// x the cosine of the beam's incidence on the room's face, rounded (so within half a unit).
double reflectivityOf(std::size_t i) {
  const int ring = static_cast<int>(i) / kAzimuths, column = static_cast<int>(i) % kAzimuths;
  const double el = kElevations[ring], az = -M_PI + column * M_PI / 18;
  const Eigen::Vector3d dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  return 90 * std::abs(dir[roomFaceAxis(kSensor, dir)]);
}

// The cloud of sensor `name`, checked against its driver's layout, dense with every beam.
sensor_msgs::PointCloud2::ConstPtr cloudOf(const std::string& name, PointLayout layout) {
  const auto cloud = clouds->first(name);
  if (!cloud) {
    ADD_FAILURE() << "no cloud from sensor " << name;
    return nullptr;
  }
  EXPECT_EQ(cloud->header.frame_id, "lidar");
  expectDriverLayout(*cloud, layout);
  EXPECT_EQ(cloud->width * cloud->height, 3u * kAzimuths) << name;
  return cloud;
}

// "velodyne" sets no point_layout: the default, velodyne_pointcloud's, time in s.
TEST(NodeLayouts, VelodyneByDefault) {
  const auto cloud = cloudOf("velodyne", PointLayout::kVelodyne);
  ASSERT_TRUE(cloud);
  for (std::size_t i = 0; i < 3 * kAzimuths; ++i) {
    expectOnTheRoom(*cloud, i, "ring", false);
    EXPECT_NEAR(fieldValue<float>(*cloud, i, "time"), columnTime(i), 1e-7) << i;
    // velodyne_pointcloud's intensity: the calibrated reflectivity, a whole number.
    const float intensity = fieldValue<float>(*cloud, i, "intensity");
    EXPECT_NEAR(intensity, reflectivityOf(i), 0.5 + 1e-3) << i;
    EXPECT_EQ(intensity, std::round(intensity)) << i;
  }
}

// The ouster layouts: t in ns after the stamp, range in mm, reflectivity the calibrated
// reflectivity, intensity the signal (the reflectivity times (10 m / range)^2, rounded), ambient
// and noise 0.
void expectOusterValues(const sensor_msgs::PointCloud2& cloud, bool legacy) {
  for (std::size_t i = 0; i < 3 * kAzimuths; ++i) {
    const double range = expectOnTheRoom(cloud, i, "ring", legacy);
    EXPECT_NEAR(fieldValue<std::uint32_t>(cloud, i, "t"), columnTime(i) * 1e9, 1.0) << i;
    EXPECT_NEAR(fieldValue<std::uint32_t>(cloud, i, "range"), range * 1000, 1.0) << i;
    const int reflectivity = fieldValue<std::uint16_t>(cloud, i, "reflectivity");
    EXPECT_NEAR(reflectivity, reflectivityOf(i), 0.5 + 1e-3) << i;
    EXPECT_NEAR(fieldValue<float>(cloud, i, "intensity"), reflectivity * 100 / (range * range),
                0.5 + 1e-3)
        << i;
    EXPECT_EQ(fieldValue<std::uint16_t>(cloud, i, "ambient"), 0) << i;
    if (legacy) {
      EXPECT_EQ(fieldValue<std::uint16_t>(cloud, i, "noise"), 0) << i;
    }
  }
}

TEST(NodeLayouts, Ouster) {
  const auto cloud = cloudOf("ouster", PointLayout::kOuster);
  ASSERT_TRUE(cloud);
  expectOusterValues(*cloud, false);
}

TEST(NodeLayouts, OusterLegacy) {
  const auto cloud = cloudOf("ouster_legacy", PointLayout::kOusterLegacy);
  ASSERT_TRUE(cloud);
  expectOusterValues(*cloud, true);
}

// livox: timestamp the absolute time in ns (a double, 256 ns apart at today's stamps), line the
// ring, tag 0.
TEST(NodeLayouts, Livox) {
  const auto cloud = cloudOf("livox", PointLayout::kLivox);
  ASSERT_TRUE(cloud);
  const double stamp_ns = static_cast<double>(cloud->header.stamp.toNSec());
  for (std::size_t i = 0; i < 3 * kAzimuths; ++i) {
    expectOnTheRoom(*cloud, i, "line", true);
    EXPECT_NEAR(fieldValue<double>(*cloud, i, "timestamp"), stamp_ns + columnTime(i) * 1e9, 512)
        << i;
    EXPECT_EQ(fieldValue<std::uint8_t>(*cloud, i, "tag"), 0) << i;
    // livox_ros_driver2's scale is not modelled: the intensity as cast, 0.9 cos incidence.
    EXPECT_NEAR(fieldValue<float>(*cloud, i, "intensity"), reflectivityOf(i) / 100, 1e-5) << i;
  }
}

// hesai, organized (a row per ring): timestamp the absolute time in s.
TEST(NodeLayouts, HesaiOrganized) {
  const auto cloud = cloudOf("hesai", PointLayout::kHesai);
  ASSERT_TRUE(cloud);
  EXPECT_EQ(cloud->height, 3u);
  EXPECT_EQ(cloud->width, static_cast<std::uint32_t>(kAzimuths));
  EXPECT_TRUE(cloud->is_dense);  // every beam returns
  for (std::size_t i = 0; i < 3 * kAzimuths; ++i) {
    expectOnTheRoom(*cloud, i, "ring", false);
    EXPECT_NEAR(fieldValue<double>(*cloud, i, "timestamp"),
                cloud->header.stamp.toSec() + columnTime(i), 1e-6)
        << i;
    // Hesai's reflectivity: linear in percent, as the calibrated reflectivity.
    EXPECT_NEAR(fieldValue<float>(*cloud, i, "intensity"), reflectivityOf(i), 0.5 + 1e-3) << i;
  }
}

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_layouts");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  laser_raycast_test::Clouds shared;
  laser_raycast_test::clouds = &shared;
  return RUN_ALL_TESTS();
}
