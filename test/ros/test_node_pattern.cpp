// rostest node_pattern.test: a sensor whose beams come from a scan pattern file (the repository's
// rosette, read here by core::PatternFile) publishes, scan after scan, the file's next 1000 rows:
// point k of a scan along row (first + k)'s direction (azimuth and zenith worked out here) on the
// room's faces, its line the row's, its timestamp the stamp plus k / 100 kHz, in
// livox_ros_driver2's fields; the next scan starts where the previous one ended. A calibrated
// VLP-16 and an Ouster OS1-64 from its metadata JSON: every (sampled) point where the driver's
// formulas put that beam, with its ring and time.
#include <gtest/gtest.h>
#include <ros/package.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <vector>

#include "driver_layouts.h"
#include "first_message.h"
#include "laser_raycast/core/pattern_file.h"
#include "laser_raycast/loader/ouster_metadata.h"
#include "laser_raycast/loader/velodyne_calibration.h"
#include "sensors_rig.h"
#include "sensors_room.h"

namespace laser_raycast_test {
namespace {

namespace core = laser_raycast::core;

constexpr int kPointsPerScan = 1000;
constexpr double kPointRate = 100000.0;  // Hz
const Eigen::Vector3d kSensor(0, 0, 1);  // frame "lidar", not turned

// A row's direction from its azimuth and zenith, worked out here.
Eigen::Vector3d rowDirection(const core::PatternFile::Row& row) {
  const double s = std::sin(row.zenith);
  return Eigen::Vector3d(s * std::cos(row.azimuth), s * std::sin(row.azimuth),
                         std::cos(row.zenith));
}

// The row a cloud starts at: the row whose direction its first point lies along.
int firstRow(const sensor_msgs::PointCloud2& cloud, const core::PatternFile& file) {
  const Eigen::Vector3d p = pointAt(cloud, 0);
  for (int r = 0; r < file.size(); r += kPointsPerScan) {
    const Eigen::Vector3d d = rowDirection(file.rows()[r]);
    if ((p - roomDistance(kSensor, d) * d).norm() < kTolerance) return r;
  }
  return -1;
}

TEST(NodePattern, EachScanIsTheFilesNextRowsOnTheRoom) {
  const core::PatternFile file = core::PatternFile::load(ros::package::getPath("laser_raycast") +
                                                         "/config/patterns/rosette_4line.csv");
  ros::NodeHandle nh;
  tf2_ros::StaticTransformBroadcaster statics;
  statics.sendTransform(transform(ros::Time::now(), "lidar", kSensor, 0));
  std::mutex mutex;
  std::vector<sensor_msgs::PointCloud2::ConstPtr> clouds;
  const ros::Subscriber sub = nh.subscribe<sensor_msgs::PointCloud2>(
      "points", 10, [&](const sensor_msgs::PointCloud2::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        clouds.push_back(m);
      });
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(30.0);
  while (ros::ok() && ros::WallTime::now() < give_up) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (clouds.size() >= 3) break;
    }
    ros::WallDuration(0.01).sleep();
  }
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_GE(clouds.size(), 3u);
  int previous_end = -1;
  for (const auto& cloud : clouds) {
    expectDriverLayout(*cloud, laser_raycast::PointLayout::kLivox);
    ASSERT_EQ(cloud->width * cloud->height, static_cast<std::uint32_t>(kPointsPerScan));
    const int first = firstRow(*cloud, file);
    ASSERT_GE(first, 0) << "the first point lies along no scan's first row";
    if (previous_end >= 0) {
      EXPECT_EQ(first, previous_end % file.size());
    }
    previous_end = first + kPointsPerScan;
    const double stamp_ns = static_cast<double>(cloud->header.stamp.toNSec());
    for (int k = 0; k < kPointsPerScan; ++k) {
      const auto& row = file.rows()[(first + k) % file.size()];
      const Eigen::Vector3d d = rowDirection(row);
      const Eigen::Vector3d p = pointAt(*cloud, k);
      EXPECT_LT((p - roomDistance(kSensor, d) * d).norm(), kTolerance) << "point " << k;
      EXPECT_EQ(fieldValue<std::uint8_t>(*cloud, k, "line"), row.line) << "point " << k;
      EXPECT_NEAR(fieldValue<double>(*cloud, k, "timestamp"), stamp_ns + k / kPointRate * 1e9, 512)
          << "point " << k;
    }
  }
}

// The VLP-16 of test/data/vlp16_calibration.yaml: one turn of 1808 firing sequences of 16 lasers,
// beam b the laser b % 16 of sequence b / 16, fired at the manual's time, its point where the
// calibration's laser puts it (core::VelodyneHead, checked against the driver's formulas in
// test_velodyne_calibration) on the room's faces, its ring the laser's by ascending elevation, its
// intensity the cosine of its incidence there.
TEST(NodePattern, CalibratedVelodyne) {
  const core::VelodyneHead head = laser_raycast::loadVelodyneCalibration(
      ros::package::getPath("laser_raycast") + "/test/data/vlp16_calibration.yaml");
  const core::BeamList beams = head.scan(0.1);
  tf2_ros::StaticTransformBroadcaster statics;
  statics.sendTransform(transform(ros::Time::now(), "lidar", kSensor, 0));
  const auto cloud = firstMessage<sensor_msgs::PointCloud2>("/velodyne/points", 30.0);
  ASSERT_TRUE(cloud);
  expectDriverLayout(*cloud, laser_raycast::PointLayout::kVelodyne);
  ASSERT_EQ(cloud->width * cloud->height, 1808u * 16u);
  const int rings[16] = {0, 8, 1, 9, 2, 10, 3, 11, 4, 12, 5, 13, 6, 14, 7, 15};
  for (int b = 0; b < beams.size(); ++b) {
    const int s = b / 16, i = b % 16;
    const Eigen::Vector3d o = kSensor + beams.origins[b], d = beams.directions[b];
    const Eigen::Vector3d expected = beams.origins[b] + roomDistance(o, d) * d;
    const Eigen::Vector3d p = pointAt(*cloud, b);
    EXPECT_LT((p - expected).norm(), kTolerance) << "point " << b;
    EXPECT_EQ(fieldValue<std::uint16_t>(*cloud, b, "ring"), rings[i]) << "point " << b;
    EXPECT_NEAR(fieldValue<float>(*cloud, b, "time"), s * 55.296e-6 + i * 2.304e-6, 1e-7)
        << "point " << b;
    // ~intensity: the default reflectivity 1 times the cosine of the incidence on the face hit,
    // the beam's own direction against the face's normal, as velodyne_pointcloud reports it: the
    // calibrated reflectivity, 100 x that, rounded.
    EXPECT_NEAR(fieldValue<float>(*cloud, b, "intensity"), 100 * std::abs(d[roomFaceAxis(o, d)]),
                0.5 + 1e-3)
        << "point " << b;
  }
}

// The OS1-64 of config/ouster/os1_64_nominal.json: 1024 columns of 64 rows, beam b row b % 64 of
// column b / 64, taken at column * 0.1 s / 1024; its direction and origin worked out here from the
// file's angles with Ouster's formulas (encoder angle 2 pi (1 - c / 1024) less the row's azimuth
// offset, the beam origin 12.163 mm out along the encoder angle, then the file's half turn about z
// and 36.18 mm up into os_sensor), its point on the room's faces, its ring the row, its range (mm)
// from its beam origin. Organized, the cloud is ouster-ros's image: 64 rows of 1024 columns, row r
// column c beam r of firing c.
TEST(NodePattern, OusterMetadata) {
  const core::OusterHead head = laser_raycast::loadOusterMetadata(
      ros::package::getPath("laser_raycast") + "/config/ouster/os1_64_nominal.json");
  ASSERT_EQ(head.rows(), 64);
  tf2_ros::StaticTransformBroadcaster statics;
  statics.sendTransform(transform(ros::Time::now(), "lidar", kSensor, 0));
  const auto cloud = firstMessage<sensor_msgs::PointCloud2>("/ouster/points", 30.0);
  ASSERT_TRUE(cloud);
  expectDriverLayout(*cloud, laser_raycast::PointLayout::kOuster);
  ASSERT_EQ(cloud->height, 64u);
  ASSERT_EQ(cloud->width, 1024u);
  for (int b = 0; b < 1024 * 64; b += 37) {
    const int c = b / 64, r = b % 64;
    const int pixel = r * 1024 + c;
    const double encoder = 2 * M_PI * (1 - c / 1024.0);
    const double azimuth = encoder - head.azimuths_deg[r] * M_PI / 180;
    const double altitude = head.altitudes_deg[r] * M_PI / 180;
    // Lidar frame to os_sensor: (x, y, z) -> (-x, -y, z + 36.18 mm).
    const Eigen::Vector3d d(-std::cos(azimuth) * std::cos(altitude),
                            -std::sin(azimuth) * std::cos(altitude), std::sin(altitude));
    const Eigen::Vector3d origin(-0.012163 * std::cos(encoder), -0.012163 * std::sin(encoder),
                                 0.03618);
    const double range = roomDistance(kSensor + origin, d);
    const Eigen::Vector3d expected = origin + range * d;
    const Eigen::Vector3d p = pointAt(*cloud, pixel);
    EXPECT_LT((p - expected).norm(), kTolerance) << "point " << b;
    EXPECT_EQ(fieldValue<std::uint16_t>(*cloud, pixel, "ring"), r) << "point " << b;
    EXPECT_EQ(fieldValue<std::uint32_t>(*cloud, pixel, "t"), std::llround(c * 0.1 / 1024 * 1e9))
        << "point " << b;
    EXPECT_NEAR(fieldValue<std::uint32_t>(*cloud, pixel, "range"), range * 1000, 1.0)
        << "point " << b;
  }
}

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_pattern");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}
