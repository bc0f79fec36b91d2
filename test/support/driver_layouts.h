// The point fields of the real drivers' PointCloud2 messages, written out by hand from their
// sources (not from the package's tables), and a check of a cloud against them: names, offsets,
// types, counts and point_step. Used by test_point_layouts (PCL) and the node_layouts rostest.
#pragma once

#include <gtest/gtest.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/PointField.h>

#include <Eigen/Core>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "laser_raycast/node/point_layout.h"

namespace laser_raycast_test {

struct DriverField {
  std::string name;
  std::uint32_t offset;
  std::uint8_t datatype;
};

struct DriverLayout {
  std::vector<DriverField> fields;
  std::uint32_t point_step;
};

inline DriverLayout driverLayout(laser_raycast::PointLayout layout) {
  using laser_raycast::PointLayout;
  using F = sensor_msgs::PointField;
  switch (layout) {
    case PointLayout::kVelodyne:
      // velodyne_pointcloud >= 1.6, PointcloudXYZIRT: the fields one after the other.
      return {{{"x", 0, F::FLOAT32},
               {"y", 4, F::FLOAT32},
               {"z", 8, F::FLOAT32},
               {"intensity", 12, F::FLOAT32},
               {"ring", 16, F::UINT16},
               {"time", 18, F::FLOAT32}},
              22};
    case PointLayout::kOuster:
      // ouster-ros: its ouster_ros::Point through pcl::toROSMsg (16-byte x y z, EIGEN_ALIGN16).
      return {{{"x", 0, F::FLOAT32},
               {"y", 4, F::FLOAT32},
               {"z", 8, F::FLOAT32},
               {"intensity", 16, F::FLOAT32},
               {"t", 20, F::UINT32},
               {"reflectivity", 24, F::UINT16},
               {"ring", 26, F::UINT16},
               {"ambient", 28, F::UINT16},
               {"range", 32, F::UINT32}},
              48};
    case PointLayout::kOusterLegacy:
      // The older ouster_ros point (uint8 ring) with both of its versions' uint16 fields, noise
      // and ambient, in its padding.
      return {{{"x", 0, F::FLOAT32},
               {"y", 4, F::FLOAT32},
               {"z", 8, F::FLOAT32},
               {"intensity", 16, F::FLOAT32},
               {"t", 20, F::UINT32},
               {"reflectivity", 24, F::UINT16},
               {"ring", 26, F::UINT8},
               {"noise", 28, F::UINT16},
               {"ambient", 30, F::UINT16},
               {"range", 32, F::UINT32}},
              48};
    case PointLayout::kLivox:
      // livox_ros_driver2 (xfer_format 0): its packed LivoxPointXyzrtlt.
      return {{{"x", 0, F::FLOAT32},
               {"y", 4, F::FLOAT32},
               {"z", 8, F::FLOAT32},
               {"intensity", 12, F::FLOAT32},
               {"tag", 16, F::UINT8},
               {"line", 17, F::UINT8},
               {"timestamp", 18, F::FLOAT64}},
              26};
    case PointLayout::kHesai:
    default:
      // hesai_ros_driver (HesaiLidar_ROS_2.0): the fields one after the other.
      return {{{"x", 0, F::FLOAT32},
               {"y", 4, F::FLOAT32},
               {"z", 8, F::FLOAT32},
               {"intensity", 12, F::FLOAT32},
               {"ring", 16, F::UINT16},
               {"timestamp", 18, F::FLOAT64}},
              26};
  }
}

// The cloud's fields, point_step, row_step and data size are those of the driver's layout.
inline void expectDriverLayout(const sensor_msgs::PointCloud2& cloud,
                               laser_raycast::PointLayout layout) {
  const DriverLayout expected = driverLayout(layout);
  ASSERT_EQ(cloud.fields.size(), expected.fields.size());
  for (std::size_t i = 0; i < expected.fields.size(); ++i) {
    const DriverField& f = expected.fields[i];
    EXPECT_EQ(cloud.fields[i].name, f.name) << i;
    EXPECT_EQ(cloud.fields[i].offset, f.offset) << f.name;
    EXPECT_EQ(cloud.fields[i].datatype, f.datatype) << f.name;
    EXPECT_EQ(cloud.fields[i].count, 1u) << f.name;
  }
  EXPECT_EQ(cloud.point_step, expected.point_step);
  EXPECT_EQ(cloud.row_step, cloud.width * expected.point_step);
  EXPECT_EQ(cloud.data.size(), std::size_t{cloud.row_step} * cloud.height);
}

// Field `name` of point `i`, read at the offset the message gives (no alignment assumed); a
// missing field fails the test and reads as 0.
template <typename T>
T fieldValue(const sensor_msgs::PointCloud2& cloud, std::size_t i, const std::string& name) {
  for (const sensor_msgs::PointField& f : cloud.fields) {
    if (f.name != name) continue;
    T value;
    std::memcpy(&value, &cloud.data.at(i * cloud.point_step + f.offset), sizeof value);
    return value;
  }
  ADD_FAILURE() << "no field " << name;
  return T{};
}

// Point i's x, y, z (float fields, as every layout has them).
inline Eigen::Vector3d pointAt(const sensor_msgs::PointCloud2& cloud, std::size_t i) {
  return Eigen::Vector3d(fieldValue<float>(cloud, i, "x"), fieldValue<float>(cloud, i, "y"),
                         fieldValue<float>(cloud, i, "z"));
}

}  // namespace laser_raycast_test
