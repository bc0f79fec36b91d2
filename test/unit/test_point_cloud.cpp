// buildPointCloud in its default layout (velodyne_pointcloud's): the fields, dense and organized
// clouds against hand-computed points (read back with sensor_msgs' PointCloud2ConstIterator),
// times, intensities, and a cloud from a real cast whose points lie on the wall that was cast
// against. The other layouts, read by PCL as SLAM packages read them: test_point_layouts.cpp.
#include <gtest/gtest.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "cloud_scan.h"
#include "laser_raycast/core/beam_list.h"
#include "laser_raycast/core/caster.h"
#include "laser_raycast/core/scan_spec.h"
#include "laser_raycast/node/point_cloud.h"

namespace laser_raycast_test {
namespace {

using laser_raycast::buildPointCloud;
using laser_raycast::CloudOptions;
using laser_raycast::rotatingColumnTimes;
using namespace laser_raycast::core;
using sensor_msgs::PointField;

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

std_msgs::Header header() {
  std_msgs::Header h;
  h.stamp = ros::Time(12, 345);
  h.frame_id = "velodyne";
  h.seq = 3;
  return h;
}

struct ReadPoint {
  float x, y, z, intensity;
  std::uint16_t ring;
  float time;
};

// Every point, read by field name.
std::vector<ReadPoint> readAll(const sensor_msgs::PointCloud2& cloud) {
  std::vector<ReadPoint> points;
  sensor_msgs::PointCloud2ConstIterator<float> x(cloud, "x"), y(cloud, "y"), z(cloud, "z"),
      intensity(cloud, "intensity"), time(cloud, "time");
  sensor_msgs::PointCloud2ConstIterator<std::uint16_t> ring(cloud, "ring");
  for (; x != x.end(); ++x, ++y, ++z, ++intensity, ++ring, ++time) {
    points.push_back({*x, *y, *z, *intensity, *ring, *time});
  }
  return points;
}

// The point at range r, elevation el, azimuth az, by hand.
void expectPoint(const ReadPoint& p, double r, double el, double az) {
  EXPECT_NEAR(p.x, r * std::cos(el) * std::cos(az), 1e-6);
  EXPECT_NEAR(p.y, r * std::cos(el) * std::sin(az), 1e-6);
  EXPECT_NEAR(p.z, r * std::sin(el), 1e-6);
}

TEST(PointCloud, FieldsAsVelodynePointcloudNamesThem) {
  sensor_msgs::PointCloud2 cloud;
  buildPointCloud(twoRings(), sixBeams(), {}, header(), CloudOptions{}, &cloud);
  ASSERT_EQ(cloud.fields.size(), 6u);
  const std::vector<std::string> names = {"x", "y", "z", "intensity", "ring", "time"};
  // Packed, as velodyne_pointcloud >= 1.6 lays them out: 22 bytes a point.
  const std::vector<std::uint32_t> offsets = {0, 4, 8, 12, 16, 18};
  for (int f = 0; f < 6; ++f) {
    EXPECT_EQ(cloud.fields[f].name, names[f]);
    EXPECT_EQ(cloud.fields[f].offset, offsets[f]) << names[f];
    EXPECT_EQ(cloud.fields[f].datatype,
              names[f] == "ring" ? PointField::UINT16 : PointField::FLOAT32)
        << names[f];
    EXPECT_EQ(cloud.fields[f].count, 1u) << names[f];
  }
  EXPECT_EQ(cloud.point_step, 22u);
  EXPECT_FALSE(cloud.is_bigendian);  // the test machines are little-endian
  EXPECT_EQ(cloud.header.frame_id, "velodyne");
  EXPECT_EQ(cloud.header.stamp, ros::Time(12, 345));
  EXPECT_EQ(cloud.header.seq, 3u);
}

// Only the three valid returns, in beam order, one row.
TEST(PointCloud, DenseHoldsTheValidReturns) {
  sensor_msgs::PointCloud2 cloud;
  buildPointCloud(twoRings(), sixBeams(), {0.0, 0.01, 0.02}, header(), CloudOptions{}, &cloud);
  EXPECT_EQ(cloud.height, 1u);
  EXPECT_EQ(cloud.width, 3u);
  EXPECT_EQ(cloud.row_step, 66u);
  EXPECT_EQ(cloud.data.size(), 66u);
  EXPECT_TRUE(cloud.is_dense);
  const auto p = readAll(cloud);
  ASSERT_EQ(p.size(), 3u);
  // Ring 0 (-0.3 rad), azimuth -pi/2 at 2 m: (0, -2 cos 0.3, -2 sin 0.3).
  expectPoint(p[0], 2.0, -0.3, -M_PI / 2);
  EXPECT_NEAR(p[0].y, -2 * std::cos(0.3), 1e-6);
  EXPECT_EQ(p[0].ring, 0);
  EXPECT_EQ(p[0].time, 0.0f);
  // velodyne_pointcloud's intensity is the sensor's calibrated reflectivity, 0-100 for diffuse
  // targets: 100 x the scan's intensity (rho cos(theta)) 0.5, rounded.
  EXPECT_EQ(p[0].intensity, 50.0f);
  // Ring 0, azimuth pi/2 at 1.5 m, taken 0.02 s after the stamp.
  expectPoint(p[1], 1.5, -0.3, M_PI / 2);
  EXPECT_EQ(p[1].ring, 0);
  EXPECT_EQ(p[1].time, 0.02f);
  EXPECT_EQ(p[1].intensity, 25.0f);
  // Ring 1 (0.2 rad), azimuth 0 at 3 m: (3 cos 0.2, 0, 3 sin 0.2).
  expectPoint(p[2], 3.0, 0.2, 0.0);
  EXPECT_NEAR(p[2].x, 3 * std::cos(0.2), 1e-6);
  EXPECT_EQ(p[2].ring, 1);
  EXPECT_EQ(p[2].time, 0.01f);
  EXPECT_EQ(p[2].intensity, 75.0f);
}

// Every beam: rows are rings, columns azimuths; no return is a NaN point that keeps ring and time.
TEST(PointCloud, OrganizedHoldsEveryBeam) {
  sensor_msgs::PointCloud2 cloud;
  CloudOptions organized;
  organized.organized = true;
  buildPointCloud(twoRings(), sixBeams(), rotatingColumnTimes(3, 0.005), header(), organized,
                  &cloud);
  EXPECT_EQ(cloud.height, 2u);
  EXPECT_EQ(cloud.width, 3u);
  EXPECT_EQ(cloud.row_step, 66u);
  EXPECT_EQ(cloud.data.size(), 132u);
  EXPECT_FALSE(cloud.is_dense);
  const auto p = readAll(cloud);
  ASSERT_EQ(p.size(), 6u);
  const double el[2] = {-0.3, 0.2}, az[3] = {-M_PI / 2, 0, M_PI / 2};
  const float range[6] = {2.0f, kNan, 1.5f, kNan, 3.0f, kNan};
  for (int b = 0; b < 6; ++b) {
    const int ring = b / 3, column = b % 3;
    EXPECT_EQ(p[b].ring, ring) << b;
    EXPECT_EQ(p[b].time, static_cast<float>(column * 0.005)) << b;
    if (std::isnan(range[b])) {
      EXPECT_TRUE(std::isnan(p[b].x) && std::isnan(p[b].y) && std::isnan(p[b].z)) << b;
      EXPECT_TRUE(std::isnan(p[b].intensity)) << b;
    } else {
      expectPoint(p[b], range[b], el[ring], az[column]);
    }
  }
  // With a return on every beam, an organized cloud is dense.
  MeasuredScan all = sixBeams();
  all.ranges = {1, 2, 3, 4, 5, 6};
  buildPointCloud(twoRings(), all, {}, header(), organized, &cloud);
  EXPECT_TRUE(cloud.is_dense);
  EXPECT_EQ(readAll(cloud)[5].time, 0.0f);  // instantaneous: every point at the stamp
}

// Dual returns: each beam's last return (where it has one of its own) follows its strongest, and a
// uint8 field `return` after the layout's says which (1 strongest, 2 last).
TEST(PointCloud, DualReturnsFollowEachBeamsStrongest) {
  MeasuredScan last = sixBeams();  // strongest: 2 m, inf, 1.5 m / inf, 3 m, inf
  last.ranges = {2.5f, kNan, kNan, 4.0f, 3.5f, kNan};
  last.intensities = {0.125f, 0, 0, 0.375f, 0.0625f, 0};
  sensor_msgs::PointCloud2 cloud;
  buildPointCloud(twoRings(), sixBeams(), {0.0, 0.01, 0.02}, header(), CloudOptions{}, &cloud,
                  &last);
  ASSERT_EQ(cloud.fields.size(), 7u);
  EXPECT_EQ(cloud.fields[6].name, "return");
  EXPECT_EQ(cloud.fields[6].offset, 22u);
  EXPECT_EQ(cloud.fields[6].datatype, PointField::UINT8);
  EXPECT_EQ(cloud.point_step, 23u);
  EXPECT_EQ(cloud.width, 6u);  // three strongest, and three last of their own
  EXPECT_EQ(cloud.data.size(), 6u * 23u);
  const auto p = readAll(cloud);
  std::vector<int> which;
  for (sensor_msgs::PointCloud2ConstIterator<std::uint8_t> r(cloud, "return"); r != r.end(); ++r) {
    which.push_back(*r);
  }
  ASSERT_EQ(p.size(), 6u);
  EXPECT_EQ(which, (std::vector<int>{1, 2, 1, 2, 1, 2}));
  // Beam 0: 2 m then 2.5 m; beam 2: 1.5 m (no last of its own); beam 3: only a last return, 4 m;
  // beam 4: 3 m then 3.5 m.
  expectPoint(p[0], 2.0, -0.3, -M_PI / 2);
  expectPoint(p[1], 2.5, -0.3, -M_PI / 2);
  EXPECT_EQ(p[1].intensity, 13.0f);  // 12.5 rounded half away from zero
  expectPoint(p[2], 1.5, -0.3, M_PI / 2);
  expectPoint(p[3], 4.0, 0.2, -M_PI / 2);
  EXPECT_EQ(p[3].ring, 1);
  expectPoint(p[4], 3.0, 0.2, 0.0);
  expectPoint(p[5], 3.5, 0.2, 0.0);
  EXPECT_EQ(p[5].time, 0.01f);

  // Organized: rows twice as wide, beam column c's returns at 2c and 2c + 1.
  CloudOptions organized;
  organized.organized = true;
  buildPointCloud(twoRings(), sixBeams(), {}, header(), organized, &cloud, &last);
  EXPECT_EQ(cloud.height, 2u);
  EXPECT_EQ(cloud.width, 6u);
  EXPECT_EQ(cloud.row_step, 6u * 23u);
  EXPECT_FALSE(cloud.is_dense);
  const auto q = readAll(cloud);
  ASSERT_EQ(q.size(), 12u);
  expectPoint(q[1], 2.5, -0.3, -M_PI / 2);
  EXPECT_TRUE(std::isnan(q[5].x));  // beam 2's last: none of its own
  EXPECT_TRUE(std::isnan(q[6].x));  // beam 3's strongest: too close
  expectPoint(q[7], 4.0, 0.2, -M_PI / 2);
  EXPECT_EQ(q[7].ring, 1);
}

TEST(PointCloud, NoIntensitiesGiveZero) {
  MeasuredScan scan = sixBeams();
  scan.intensities.clear();
  sensor_msgs::PointCloud2 cloud;
  buildPointCloud(twoRings(), scan, {}, header(), CloudOptions{}, &cloud);
  for (const ReadPoint& p : readAll(cloud)) EXPECT_EQ(p.intensity, 0.0f);
}

TEST(PointCloud, MismatchedSizesThrow) {
  sensor_msgs::PointCloud2 cloud;
  MeasuredScan scan = sixBeams();
  scan.ranges.pop_back();
  EXPECT_THROW(buildPointCloud(twoRings(), scan, {}, header(), CloudOptions{}, &cloud),
               std::invalid_argument);
  scan = sixBeams();
  scan.intensities.resize(4);
  EXPECT_THROW(buildPointCloud(twoRings(), scan, {}, header(), CloudOptions{}, &cloud),
               std::invalid_argument);
  try {
    buildPointCloud(twoRings(), sixBeams(), {0.0, 0.1}, header(), CloudOptions{}, &cloud);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("2 column times"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("2 rings x 3 azimuths"), std::string::npos) << e.what();
  }
}

// Beams off a grid, three lines of two beams, listed column by column as the calibration and
// metadata readers list them (line 0, 1, 2 of the first firing, then of the second), from their own
// origins: organized, the cloud is the drivers' image, row r line r's beams in firing order; with
// lines of unequal counts (a pattern file's), one row of every beam in list order.
TEST(PointCloud, BeamCloudRowsAreLines) {
  BeamList beams;
  for (int column = 0; column < 2; ++column) {
    for (int line = 0; line < 3; ++line) {
      beams.directions.push_back(beamDirection(0.1 * column, 0.05 * line));
      beams.origins.push_back(Eigen::Vector3d(0.01 * line, 0.02 * column, 0.03));
      beams.times.push_back(1e-4 * column + 1e-6 * line);
      beams.lines.push_back(line);
    }
  }
  MeasuredScan scan;
  scan.ranges = {1.0f, 2.0f, kNan, 4.0f, 5.0f, 6.0f};
  scan.intensities = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f};
  CloudOptions organized;
  organized.organized = true;
  sensor_msgs::PointCloud2 cloud;
  laser_raycast::buildBeamCloud(beams, scan, header(), organized, &cloud);
  EXPECT_EQ(cloud.height, 3u);
  EXPECT_EQ(cloud.width, 2u);
  EXPECT_FALSE(cloud.is_dense);
  const std::vector<ReadPoint> points = readAll(cloud);
  ASSERT_EQ(points.size(), 6u);
  const int beam_of[6] = {0, 3, 1, 4, 2, 5};  // row-major: (line 0: beams 0, 3), (line 1: 1, 4), ...
  for (int p = 0; p < 6; ++p) {
    const int b = beam_of[p];
    EXPECT_EQ(points[p].ring, beams.lines[b]) << p;
    EXPECT_FLOAT_EQ(points[p].time, static_cast<float>(beams.times[b])) << p;
    if (std::isnan(scan.ranges[b])) {
      EXPECT_TRUE(std::isnan(points[p].x)) << p;
      continue;
    }
    const Eigen::Vector3d at = beams.origins[b] + beams.directions[b] * scan.ranges[b];
    EXPECT_NEAR(points[p].x, at.x(), 1e-6) << p;
    EXPECT_NEAR(points[p].y, at.y(), 1e-6) << p;
    EXPECT_NEAR(points[p].z, at.z(), 1e-6) << p;
    EXPECT_EQ(points[p].intensity, 10.0f * (b + 1)) << p;  // 100 x the intensity
  }
  // A line with one beam more: one row of every beam, in the list's order.
  beams.append(beams, 0);
  scan.ranges.push_back(7.0f);
  scan.intensities.push_back(0.7f);
  laser_raycast::buildBeamCloud(beams, scan, header(), organized, &cloud);
  EXPECT_EQ(cloud.height, 1u);
  EXPECT_EQ(cloud.width, 7u);
  const std::vector<ReadPoint> row = readAll(cloud);
  ASSERT_EQ(row.size(), 7u);
  for (int b = 0; b < 7; ++b) EXPECT_EQ(row[b].ring, beams.lines[b]) << b;
  // Dense: the valid returns in list order.
  laser_raycast::buildBeamCloud(beams, scan, header(), CloudOptions{}, &cloud);
  EXPECT_EQ(cloud.height, 1u);
  EXPECT_EQ(cloud.width, 6u);
}

// End to end with the caster: a wall 4 m ahead (a box whose near face is x = 4) seen by 5 rings of
// 21 azimuths over +-0.5 rad: every point lies on x = 4, at range 4 / (cos el cos az).
TEST(PointCloud, PointsOfACastLieOnTheWall) {
  Scene scene;
  scene.addFrame("world");
  scene.addLabel("wall");
  Body wall;
  wall.shape = Box{Eigen::Vector3d(0.2, 20, 20)};
  wall.frame_from_body = Eigen::Translation3d(4.1, 0, 0);
  scene.addBody(wall);
  ScanSpec spec;
  spec.fan.angle_min = -0.5;
  spec.fan.angle_max = 0.5;
  spec.fan.samples = 21;
  spec.elevations = {-0.2, -0.1, 0, 0.1, 0.2};
  const ScanPattern pattern = spec.pattern();
  Caster caster;
  const ScanResult& result = caster.cast(scene, FramePoses::identity(scene),
                                         Eigen::Isometry3d::Identity(), pattern, spec.castConfig());
  MeasurementModel model(spec.output);
  MeasuredScan scan;
  model.measure(scene, result, {}, &scan);
  sensor_msgs::PointCloud2 cloud;
  buildPointCloud(pattern, scan, {}, header(), CloudOptions{}, &cloud);
  const auto points = readAll(cloud);
  ASSERT_EQ(points.size(), 105u);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double el = spec.elevations[points[i].ring], az = -0.5 + 0.05 * (i % 21);
    EXPECT_NEAR(points[i].x, 4.0, 2e-6) << i;
    expectPoint(points[i], 4.0 / (std::cos(el) * std::cos(az)), el, az);
  }
}

}  // namespace
}  // namespace laser_raycast_test
