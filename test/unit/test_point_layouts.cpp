// The point layouts read as lidar SLAM packages read them: each cloud converted to PCL's
// PCLPointCloud2 (what pcl_conversions does, field by field) and read with
// pcl::fromPCLPointCloud2 into the consumers' own point structs, declared here as those packages
// declare them. PCL matches a struct's fields to the message's by name, type and count and copies
// them from the message's offsets; a field it does not find stays unset with only a warning on
// stderr, so each struct's fields are matched here one by one. The offsets are those of the
// drivers, written out by hand in driver_layouts.h (and, for ouster-ros, also taken from its struct
// through PCL's offsetof).
#include <gtest/gtest.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/register_point_struct.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "cloud_scan.h"
#include "driver_layouts.h"
#include "laser_raycast/core/scan_spec.h"
#include "laser_raycast/node/point_cloud.h"

// --- The consumers' point structs, each as its package declares it ----------------------------
// clang-format off

// LIO-SAM (imageProjection.cpp): sensor: velodyne (and livox) reads VelodynePointXYZIRT...
struct VelodynePointXYZIRT {
  PCL_ADD_POINT4D
  PCL_ADD_INTENSITY;
  uint16_t ring;
  float time;
  EIGEN_MAKE_ALIGNED_OPERATOR_NEW
} EIGEN_ALIGN16;
POINT_CLOUD_REGISTER_POINT_STRUCT(VelodynePointXYZIRT,
    (float, x, x)
    (float, y, y)
    (float, z, z)
    (float, intensity, intensity)
    (uint16_t, ring, ring)
    (float, time, time))

// ... and sensor: ouster OusterPointXYZIRT (the older ouster_ros driver's point, with noise).
struct OusterPointXYZIRT {
  PCL_ADD_POINT4D;
  float intensity;
  uint32_t t;
  uint16_t reflectivity;
  uint8_t ring;
  uint16_t noise;
  uint32_t range;
  EIGEN_MAKE_ALIGNED_OPERATOR_NEW
} EIGEN_ALIGN16;
POINT_CLOUD_REGISTER_POINT_STRUCT(OusterPointXYZIRT,
    (float, x, x)
    (float, y, y)
    (float, z, z)
    (float, intensity, intensity)
    (std::uint32_t, t, t)
    (std::uint16_t, reflectivity, reflectivity)
    (std::uint8_t, ring, ring)
    (std::uint16_t, noise, noise)
    (std::uint32_t, range, range))

// FAST-LIO (preprocess.h): lidar_type 2 reads velodyne_ros::Point, 3 ouster_ros::Point (the older
// driver's, with ambient).
namespace fast_lio {
namespace velodyne_ros {
struct EIGEN_ALIGN16 Point {
  PCL_ADD_POINT4D;
  float intensity;
  float time;
  uint16_t ring;
  EIGEN_MAKE_ALIGNED_OPERATOR_NEW
};
}  // namespace velodyne_ros
namespace ouster_ros {
struct EIGEN_ALIGN16 Point {
  PCL_ADD_POINT4D;
  float intensity;
  uint32_t t;
  uint16_t reflectivity;
  uint8_t ring;
  uint16_t ambient;
  uint32_t range;
  EIGEN_MAKE_ALIGNED_OPERATOR_NEW
};
}  // namespace ouster_ros
}  // namespace fast_lio
POINT_CLOUD_REGISTER_POINT_STRUCT(fast_lio::velodyne_ros::Point,
    (float, x, x)
    (float, y, y)
    (float, z, z)
    (float, intensity, intensity)
    (float, time, time)
    (std::uint16_t, ring, ring))
POINT_CLOUD_REGISTER_POINT_STRUCT(fast_lio::ouster_ros::Point,
    (float, x, x)
    (float, y, y)
    (float, z, z)
    (float, intensity, intensity)
    (std::uint32_t, t, t)
    (std::uint16_t, reflectivity, reflectivity)
    (std::uint8_t, ring, ring)
    (std::uint16_t, ambient, ambient)
    (std::uint32_t, range, range))

// ouster-ros (os_point.h): its "original" point, which its driver publishes with pcl::toROSMsg.
namespace ouster_ros {
struct EIGEN_ALIGN16 Point {
  PCL_ADD_POINT4D;
  float intensity;
  uint32_t t;
  uint16_t reflectivity;
  uint16_t ring;
  uint16_t ambient;
  uint32_t range;
  EIGEN_MAKE_ALIGNED_OPERATOR_NEW
};
}  // namespace ouster_ros
POINT_CLOUD_REGISTER_POINT_STRUCT(ouster_ros::Point,
    (float, x, x)
    (float, y, y)
    (float, z, z)
    (float, intensity, intensity)
    (std::uint32_t, t, t)
    (std::uint16_t, reflectivity, reflectivity)
    (std::uint16_t, ring, ring)
    (std::uint16_t, ambient, ambient)
    (std::uint32_t, range, range))

// livox_ros_driver2's packed LivoxPointXyzrtlt as a PCL point, the fields of its PointCloud2 by
// their message names (as e.g. the Livox simulation plugin declares it).
namespace livox {
struct EIGEN_ALIGN16 PointXyzrtlt {
  PCL_ADD_POINT4D;
  float intensity;
  std::uint8_t tag;
  std::uint8_t line;
  double timestamp;
  EIGEN_MAKE_ALIGNED_OPERATOR_NEW
};
}  // namespace livox
POINT_CLOUD_REGISTER_POINT_STRUCT(livox::PointXyzrtlt,
    (float, x, x)
    (float, y, y)
    (float, z, z)
    (float, intensity, intensity)
    (std::uint8_t, tag, tag)
    (std::uint8_t, line, line)
    (double, timestamp, timestamp))

// HesaiLidar_General_ROS's PointXYZIT (what LIO-SAM forks for Pandar lidars declare too).
namespace hesai {
struct PointXYZIT {
  PCL_ADD_POINT4D
  float intensity;
  double timestamp;
  uint16_t ring;
  EIGEN_MAKE_ALIGNED_OPERATOR_NEW
} EIGEN_ALIGN16;
}  // namespace hesai
POINT_CLOUD_REGISTER_POINT_STRUCT(hesai::PointXYZIT,
    (float, x, x)
    (float, y, y)
    (float, z, z)
    (float, intensity, intensity)
    (double, timestamp, timestamp)
    (std::uint16_t, ring, ring))
// clang-format on

namespace laser_raycast_test {
namespace {

using laser_raycast::buildPointCloud;
using laser_raycast::CloudOptions;
using laser_raycast::PointLayout;
using laser_raycast::rotatingColumnTimes;
using namespace laser_raycast::core;
using sensor_msgs::PointField;

// sixBeams() with intensities (rho cos(theta)) that test the rounding of the drivers' calibrated
// reflectivity, 100 x the intensity (a half away from zero: 12.5 -> 13; 0.75 -> 1), and its
// clamping (300 -> 255).
MeasuredScan sixBeamsBright() {
  MeasuredScan scan = sixBeams();
  scan.intensities = {0.125f, 0.0f, 3.0f, 0.0f, 0.0075f, 0.0f};
  return scan;
}

// A stamp of our time, where a double of absolute nanoseconds is 256 ns apart.
constexpr std::uint64_t kStampNs = 1700000000123456789ull;
// Column c is taken 5 ms after column c - 1 (a rotating scan).
constexpr double kColumnTime = 0.005;
constexpr std::uint64_t kColumnTimeNs = 5000000;

std_msgs::Header header() {
  std_msgs::Header h;
  h.stamp.fromNSec(kStampNs);
  h.frame_id = "lidar";
  return h;
}

sensor_msgs::PointCloud2 cloudOf(PointLayout layout, bool organized = false) {
  CloudOptions options;
  options.layout = layout;
  options.organized = organized;
  sensor_msgs::PointCloud2 cloud;
  buildPointCloud(twoRings(), sixBeamsBright(), rotatingColumnTimes(3, kColumnTime), header(),
                  options, &cloud);
  return cloud;
}

// The message as PCL's own type, field for field (pcl_conversions' toPCL).
pcl::PCLPointCloud2 toPcl(const sensor_msgs::PointCloud2& m) {
  pcl::PCLPointCloud2 p;
  p.header.frame_id = m.header.frame_id;
  p.header.stamp = m.header.stamp.toNSec() / 1000;  // PCL stamps in microseconds
  p.height = m.height;
  p.width = m.width;
  for (const PointField& f : m.fields) {
    pcl::PCLPointField pf;
    pf.name = f.name;
    pf.offset = f.offset;
    pf.datatype = f.datatype;
    pf.count = f.count;
    p.fields.push_back(pf);
  }
  p.is_bigendian = m.is_bigendian;
  p.point_step = m.point_step;
  p.row_step = m.row_step;
  p.data = m.data;
  p.is_dense = m.is_dense;
  return p;
}

// The fields of PointT that no field of the message matches by name, type and count, as PCL's
// FieldMapper looks for them.
template <typename PointT>
struct FindMatch {
  const std::vector<pcl::PCLPointField>& fields;
  std::vector<std::string>* missing;
  template <typename Tag>
  void operator()() {
    if (std::none_of(fields.begin(), fields.end(), pcl::FieldMatches<PointT, Tag>())) {
      missing->push_back(pcl::traits::name<PointT, Tag>::value);
    }
  }
};
template <typename PointT>
std::vector<std::string> unmatched(const pcl::PCLPointCloud2& msg) {
  std::vector<std::string> missing;
  pcl::for_each_type<typename pcl::traits::fieldList<PointT>::type>(
      FindMatch<PointT>{msg.fields, &missing});
  return missing;
}

// The cloud read into PointT, after checking that every field of PointT is found.
template <typename PointT>
pcl::PointCloud<PointT> readAs(const sensor_msgs::PointCloud2& cloud) {
  const pcl::PCLPointCloud2 msg = toPcl(cloud);
  EXPECT_EQ(unmatched<PointT>(msg), std::vector<std::string>{});
  pcl::PointCloud<PointT> points;
  pcl::fromPCLPointCloud2(msg, points);
  return points;
}

// The three valid returns in beam order: (ring, column, range, intensity as cast, the drivers'
// calibrated reflectivity of it, Ouster's signal: the reflectivity times (10 m / range)^2, rounded:
// 13 x 25, 255 x 44.4, 1 x 11.1).
struct Return {
  int ring, column;
  double range;
  float intensity;
  float reflectivity;
  float signal;
};
const Return kReturns[3] = {{0, 0, 2.0, 0.125f, 13, 325},
                            {0, 2, 1.5, 3.0f, 255, 11333},
                            {1, 1, 3.0, 0.0075f, 1, 11}};

// x y z of return r, by hand: r (cos el cos az, cos el sin az, sin el).
template <typename PointT>
void expectPosition(const PointT& p, const Return& r) {
  const double el = r.ring == 0 ? -0.3 : 0.2, az = -M_PI / 2 + r.column * M_PI / 2;
  EXPECT_NEAR(p.x, r.range * std::cos(el) * std::cos(az), 1e-6);
  EXPECT_NEAR(p.y, r.range * std::cos(el) * std::sin(az), 1e-6);
  EXPECT_NEAR(p.z, r.range * std::sin(el), 1e-6);
}

// velodyne_pointcloud >= 1.6 (PointcloudXYZIRT): six fields packed one after the other, time in s
// after the stamp.
TEST(PointLayouts, VelodyneIsReadByLioSamAndFastLio) {
  const auto cloud = cloudOf(PointLayout::kVelodyne);
  expectDriverLayout(cloud, PointLayout::kVelodyne);
  const auto lio_sam = readAs<VelodynePointXYZIRT>(cloud);
  const auto fast_lio = readAs<fast_lio::velodyne_ros::Point>(cloud);
  ASSERT_EQ(lio_sam.size(), 3u);
  ASSERT_EQ(fast_lio.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const Return& r = kReturns[i];
    const float time = static_cast<float>(r.column * kColumnTime);  // s after the stamp
    expectPosition(lio_sam[i], r);
    EXPECT_EQ(lio_sam[i].intensity, r.reflectivity);
    EXPECT_EQ(lio_sam[i].ring, r.ring);
    EXPECT_EQ(lio_sam[i].time, time);
    expectPosition(fast_lio[i], r);
    EXPECT_EQ(fast_lio[i].intensity, r.reflectivity);
    EXPECT_EQ(fast_lio[i].ring, r.ring);
    EXPECT_EQ(fast_lio[i].time, time);
  }
}

// ouster-ros: the offsets PCL gives its ouster_ros::Point (offsetof, as pcl::toROSMsg publishes
// it), which are those written out by hand.
TEST(PointLayouts, OusterAsOusterRosPublishesItsPoint) {
  const auto cloud = cloudOf(PointLayout::kOuster);
  expectDriverLayout(cloud, PointLayout::kOuster);
  std::vector<pcl::PCLPointField> theirs;
  pcl::for_each_type<pcl::traits::fieldList<ouster_ros::Point>::type>(
      pcl::detail::FieldAdder<ouster_ros::Point>(theirs));
  ASSERT_EQ(theirs.size(), cloud.fields.size());
  for (std::size_t i = 0; i < theirs.size(); ++i) {
    EXPECT_EQ(cloud.fields[i].name, theirs[i].name);
    EXPECT_EQ(cloud.fields[i].offset, theirs[i].offset) << theirs[i].name;
    EXPECT_EQ(cloud.fields[i].datatype, theirs[i].datatype) << theirs[i].name;
  }
  EXPECT_EQ(cloud.point_step, sizeof(ouster_ros::Point));
}

// What the ouster layouts hold: intensity the signal, t in ns after the stamp, reflectivity the
// calibrated reflectivity, range in mm, ambient (and noise) 0.
template <typename PointT>
void expectOusterValues(const pcl::PointCloud<PointT>& points) {
  ASSERT_EQ(points.size(), 3u);
  const std::uint32_t range_mm[3] = {2000, 1500, 3000};
  for (int i = 0; i < 3; ++i) {
    const Return& r = kReturns[i];
    expectPosition(points[i], r);
    EXPECT_EQ(points[i].intensity, r.signal);
    EXPECT_EQ(points[i].ring, r.ring);
    EXPECT_EQ(points[i].t, r.column * kColumnTimeNs);
    EXPECT_EQ(points[i].reflectivity, r.reflectivity);
    EXPECT_EQ(points[i].range, range_mm[i]);
  }
}

TEST(PointLayouts, OusterIsReadAsOusterRosPoint) {
  const auto points = readAs<ouster_ros::Point>(cloudOf(PointLayout::kOuster));
  expectOusterValues(points);
  for (const auto& p : points) EXPECT_EQ(p.ambient, 0);
}

// The older driver's ring was uint8: LIO-SAM's and FAST-LIO's structs do not find it in
// ouster-ros's layout (nor LIO-SAM its noise), which is why ouster_legacy exists.
TEST(PointLayouts, OusterRosLayoutMissesTheOlderDriversFields) {
  const pcl::PCLPointCloud2 msg = toPcl(cloudOf(PointLayout::kOuster));
  EXPECT_EQ(unmatched<OusterPointXYZIRT>(msg), (std::vector<std::string>{"ring", "noise"}));
  EXPECT_EQ(unmatched<fast_lio::ouster_ros::Point>(msg), std::vector<std::string>{"ring"});
}

// ouster_legacy: ouster-ros's offsets with a uint8 ring, noise where the narrower ring leaves
// room, ambient in the padding before range; LIO-SAM's struct (noise) and FAST-LIO's (ambient)
// both find every field.
TEST(PointLayouts, OusterLegacyIsReadByLioSamAndFastLio) {
  const auto cloud = cloudOf(PointLayout::kOusterLegacy);
  expectDriverLayout(cloud, PointLayout::kOusterLegacy);
  const auto lio_sam = readAs<OusterPointXYZIRT>(cloud);
  expectOusterValues(lio_sam);
  for (const auto& p : lio_sam) EXPECT_EQ(p.noise, 0);
  const auto fast_lio = readAs<fast_lio::ouster_ros::Point>(cloud);
  expectOusterValues(fast_lio);
  for (const auto& p : fast_lio) EXPECT_EQ(p.ambient, 0);
}

// livox_ros_driver2's PointCloud2: its packed 26-byte point, timestamp the absolute time in ns.
TEST(PointLayouts, LivoxAsLivoxRosDriver2PublishesIt) {
  const auto cloud = cloudOf(PointLayout::kLivox);
  expectDriverLayout(cloud, PointLayout::kLivox);
  const auto points = readAs<livox::PointXyzrtlt>(cloud);
  ASSERT_EQ(points.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const Return& r = kReturns[i];
    expectPosition(points[i], r);
    EXPECT_EQ(points[i].intensity, r.intensity);
    EXPECT_EQ(points[i].tag, 0);
    EXPECT_EQ(points[i].line, r.ring);
    // The exact sum in ns, rounded once to a double (256 ns apart at this stamp).
    EXPECT_EQ(points[i].timestamp, static_cast<double>(kStampNs + r.column * kColumnTimeNs));
  }
}

// hesai_ros_driver's PointCloud2: six fields packed, timestamp the absolute time in s. Read into
// HesaiLidar_General_ROS's struct, whose offsets differ (PCL copies from the message's).
TEST(PointLayouts, HesaiAsHesaiRosDriverPublishesIt) {
  const auto cloud = cloudOf(PointLayout::kHesai);
  expectDriverLayout(cloud, PointLayout::kHesai);
  const auto points = readAs<hesai::PointXYZIT>(cloud);
  ASSERT_EQ(points.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const Return& r = kReturns[i];
    expectPosition(points[i], r);
    EXPECT_EQ(points[i].intensity, r.reflectivity);
    EXPECT_EQ(points[i].ring, r.ring);
    // 1700000000.123456789 s + 5 ms per column; a double holds it to 2.4e-7 s.
    EXPECT_NEAR(points[i].timestamp, 1700000000.123456789 + r.column * kColumnTime, 3e-7);
  }
}

// Organized clouds in every layout: a point per beam, the beams without a return NaN in x y z and
// intensity, their ring and times kept, reflectivity and range 0.
TEST(PointLayouts, OrganizedCloudsInEveryLayout) {
  const bool has_return[6] = {true, false, true, false, true, false};
  for (const auto& [layout, name] : laser_raycast::kPointLayoutNames.entries()) {
    SCOPED_TRACE(name);
    const auto cloud = cloudOf(layout, true);
    EXPECT_EQ(cloud.height, 2u);
    EXPECT_EQ(cloud.width, 3u);
    EXPECT_FALSE(cloud.is_dense);
    EXPECT_EQ(cloud.data.size(), 6u * cloud.point_step);
  }
  const auto velodyne = readAs<VelodynePointXYZIRT>(cloudOf(PointLayout::kVelodyne, true));
  const auto ouster = readAs<ouster_ros::Point>(cloudOf(PointLayout::kOuster, true));
  const auto legacy = readAs<OusterPointXYZIRT>(cloudOf(PointLayout::kOusterLegacy, true));
  const auto livox = readAs<livox::PointXyzrtlt>(cloudOf(PointLayout::kLivox, true));
  const auto hesai = readAs<hesai::PointXYZIT>(cloudOf(PointLayout::kHesai, true));
  ASSERT_EQ(velodyne.size(), 6u);
  ASSERT_EQ(ouster.size(), 6u);
  ASSERT_EQ(legacy.size(), 6u);
  ASSERT_EQ(livox.size(), 6u);
  ASSERT_EQ(hesai.size(), 6u);
  EXPECT_EQ(ouster.height, 2u);  // PCL keeps the rows
  for (int b = 0; b < 6; ++b) {
    const int ring = b / 3, column = b % 3;
    EXPECT_EQ(velodyne[b].ring, ring) << b;
    EXPECT_EQ(velodyne[b].time, static_cast<float>(column * kColumnTime)) << b;
    EXPECT_EQ(ouster[b].ring, ring) << b;
    EXPECT_EQ(ouster[b].t, column * kColumnTimeNs) << b;
    EXPECT_EQ(legacy[b].ring, ring) << b;
    EXPECT_EQ(legacy[b].t, column * kColumnTimeNs) << b;
    EXPECT_EQ(livox[b].line, ring) << b;
    EXPECT_EQ(livox[b].timestamp, static_cast<double>(kStampNs + column * kColumnTimeNs)) << b;
    EXPECT_EQ(hesai[b].ring, ring) << b;
    EXPECT_NEAR(hesai[b].timestamp, 1700000000.123456789 + column * kColumnTime, 3e-7) << b;
    if (has_return[b]) continue;
    EXPECT_TRUE(std::isnan(velodyne[b].x) && std::isnan(velodyne[b].intensity)) << b;
    EXPECT_TRUE(std::isnan(ouster[b].y) && std::isnan(ouster[b].intensity)) << b;
    EXPECT_TRUE(std::isnan(legacy[b].z) && std::isnan(legacy[b].intensity)) << b;
    EXPECT_TRUE(std::isnan(livox[b].x) && std::isnan(livox[b].intensity)) << b;
    EXPECT_TRUE(std::isnan(hesai[b].z) && std::isnan(hesai[b].intensity)) << b;
    EXPECT_EQ(ouster[b].range, 0u) << b;
    EXPECT_EQ(ouster[b].reflectivity, 0) << b;
    EXPECT_EQ(legacy[b].range, 0u) << b;
    EXPECT_EQ(legacy[b].reflectivity, 0) << b;
  }
}

// The integer fields bound what a layout can hold: 256 rings in a uint8 ring (ouster_legacy) or
// line (livox), a sweep of 4.294967295 s in uint32 ns (the ouster layouts' t).
TEST(PointLayouts, LimitsOfTheIntegerFields) {
  using laser_raycast::pointLayoutLimit;
  EXPECT_EQ(pointLayoutLimit(PointLayout::kOusterLegacy, 256, 0.1), "");
  EXPECT_NE(pointLayoutLimit(PointLayout::kOusterLegacy, 257, 0.1).find("at most 256"),
            std::string::npos);
  EXPECT_NE(pointLayoutLimit(PointLayout::kLivox, 257, 0.1).find("line"), std::string::npos);
  EXPECT_EQ(pointLayoutLimit(PointLayout::kVelodyne, 65536, 100.0), "");
  EXPECT_NE(pointLayoutLimit(PointLayout::kHesai, 65537, 0.1).find("at most 65536"),
            std::string::npos);
  EXPECT_EQ(pointLayoutLimit(PointLayout::kOuster, 128, 4.29), "");
  EXPECT_NE(pointLayoutLimit(PointLayout::kOuster, 128, 4.3).find("uint32 ns"), std::string::npos);

  // buildPointCloud refuses what its layout cannot hold: a rotating sweep of 5 s.
  CloudOptions options;
  options.layout = PointLayout::kOuster;
  sensor_msgs::PointCloud2 cloud;
  EXPECT_THROW(buildPointCloud(twoRings(), sixBeams(), {0.0, 2.5, 5.0}, header(), options, &cloud),
               std::invalid_argument);
}

}  // namespace
}  // namespace laser_raycast_test
