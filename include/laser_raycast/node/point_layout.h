// The point layouts of real lidar drivers' PointCloud2 messages: each field's name, offset and type
// as the driver publishes it, and what the simulation puts in it. Consumers (lidar SLAM packages)
// read points by field name and type through PCL, so a layout is what lets them take the
// simulated cloud for their driver's.
#pragma once

#include <sensor_msgs/PointField.h>

#include <array>
#include <cstdint>
#include <string>

#include "laser_raycast/core/enum_names.h"

namespace laser_raycast {

// ~point_layout: whose driver's PointCloud2 the cloud is laid out as.
enum class PointLayout {
  kVelodyne,      // velodyne_pointcloud >= 1.6 (XYZIRT): packed, time in s after the stamp
  kOuster,        // ouster-ros's ouster_ros::Point: ring uint16, t in ns after the stamp
  kOusterLegacy,  // the ouster_ros driver before ouster-ros: ring uint8, both noise and ambient
  kLivox,         // livox_ros_driver2's PointCloud2: tag, line, timestamp in absolute ns
  kHesai,         // hesai_ros_driver's PointCloud2: ring, timestamp in absolute s
};
inline const core::EnumNames<PointLayout, 5> kPointLayoutNames{{{
    {PointLayout::kVelodyne, "velodyne"},
    {PointLayout::kOuster, "ouster"},
    {PointLayout::kOusterLegacy, "ouster_legacy"},
    {PointLayout::kLivox, "livox"},
    {PointLayout::kHesai, "hesai"},
}}};

// What a field of a point holds.
enum class PointValue {
  kX,
  kY,
  kZ,          // m, in the sensor frame; NaN for a beam without a return (organized clouds)
  kIntensity,  // the scan's intensity as is (0 without intensities); NaN without a return
  // Calibrated reflectivity as Velodyne, Hesai and Ouster report it: 0-100 for diffuse targets (a
  // percent of a white Lambertian target seen head-on), above for retro-reflectors, at most 255:
  // 100 x the scan's intensity (rho cos(theta)), rounded and clamped to 0..255. NaN without a
  // return (0 in an integer field).
  kReflectivity,
  // Ouster's signal, the received light, which falls with the square of the range: the
  // reflectivity value times (10 m / range)^2 (the same at 10 m), rounded and clamped to 0..65535
  // (the packet's 16 bits). NaN without a return.
  kSignal,
  kRing,              // the ring, 0 lowest
  kTimeSeconds,       // the point's time, s after header.stamp
  kTimeNanoseconds,   // the same in ns, rounded
  kStampSeconds,      // absolute time: header.stamp plus the point's time, s
  kStampNanoseconds,  // the same in ns
  kRangeMillimetres,  // the range, mm, rounded; 0 without a return
  kZero,              // what drivers fill and the simulation does not model (ambient, noise, tag)
};

struct PointLayoutField {
  const char* name;
  std::uint32_t offset;   // bytes from the start of the point
  std::uint8_t datatype;  // sensor_msgs::PointField::FLOAT32, UINT16, ...
  PointValue value;
};

// A layout's fields as a constant table (below, one per layout), so that the cloud builder writes
// each layout's points with its fields known at compile time.
template <std::size_t N>
struct PointLayoutTable {
  std::uint32_t point_step;                // bytes a point, padding included
  std::array<PointLayoutField, N> fields;  // in offset order
};

namespace point_layouts {

using F = sensor_msgs::PointField;
using V = PointValue;

// velodyne_pointcloud's PointcloudXYZIRT lays its fields out one after the other with
// PointCloud2Modifier, without padding: 22 bytes a point.
inline constexpr PointLayoutTable<6> kVelodyne = {
    22,
    {{
        {"x", 0, F::FLOAT32, V::kX},
        {"y", 4, F::FLOAT32, V::kY},
        {"z", 8, F::FLOAT32, V::kZ},
        {"intensity", 12, F::FLOAT32, V::kReflectivity},
        {"ring", 16, F::UINT16, V::kRing},
        {"time", 18, F::FLOAT32, V::kTimeSeconds},
    }},
};

// ouster-ros publishes its ouster_ros::Point with pcl::toROSMsg, at the struct's offsets: x y z
// in PCL_ADD_POINT4D's 16 bytes, then intensity, t, reflectivity, ring, ambient, 2 bytes of
// padding before range, and the struct padded to EIGEN_ALIGN16's 48 bytes.
inline constexpr PointLayoutTable<9> kOuster = {
    48,
    {{
        {"x", 0, F::FLOAT32, V::kX},
        {"y", 4, F::FLOAT32, V::kY},
        {"z", 8, F::FLOAT32, V::kZ},
        {"intensity", 16, F::FLOAT32, V::kSignal},
        {"t", 20, F::UINT32, V::kTimeNanoseconds},
        {"reflectivity", 24, F::UINT16, V::kReflectivity},
        {"ring", 26, F::UINT16, V::kRing},
        {"ambient", 28, F::UINT16, V::kZero},
        {"range", 32, F::UINT32, V::kRangeMillimetres},
    }},
};

// The older ouster_ros driver's point had a uint8 ring and, at 28, a uint16 noise in its first
// versions and ambient in later ones: LIO-SAM declares the first, FAST-LIO the second. PCL matches
// fields by name and type and copies them from the message's offsets, so one layout with both
// serves both: noise at 28, as in the first, ambient in the 2 bytes of padding before range.
inline constexpr PointLayoutTable<10> kOusterLegacy = {
    48,
    {{
        {"x", 0, F::FLOAT32, V::kX},
        {"y", 4, F::FLOAT32, V::kY},
        {"z", 8, F::FLOAT32, V::kZ},
        {"intensity", 16, F::FLOAT32, V::kSignal},
        {"t", 20, F::UINT32, V::kTimeNanoseconds},
        {"reflectivity", 24, F::UINT16, V::kReflectivity},
        {"ring", 26, F::UINT8, V::kRing},
        {"noise", 28, F::UINT16, V::kZero},
        {"ambient", 30, F::UINT16, V::kZero},
        {"range", 32, F::UINT32, V::kRangeMillimetres},
    }},
};

// livox_ros_driver2 (xfer_format 0) copies its packed LivoxPointXyzrtlt into the message: 26
// bytes, timestamp the point's absolute time in ns as a double.
inline constexpr PointLayoutTable<7> kLivox = {
    26,
    {{
        {"x", 0, F::FLOAT32, V::kX},
        {"y", 4, F::FLOAT32, V::kY},
        {"z", 8, F::FLOAT32, V::kZ},
        {"intensity", 12, F::FLOAT32, V::kIntensity},
        {"tag", 16, F::UINT8, V::kZero},
        {"line", 17, F::UINT8, V::kRing},
        {"timestamp", 18, F::FLOAT64, V::kStampNanoseconds},
    }},
};

// hesai_ros_driver (HesaiLidar_ROS_2.0) adds its fields one after the other, without padding:
// 26 bytes, timestamp the point's absolute time in s. (The older HesaiLidar_General_ROS published
// its PCL struct, with padding, in the same names and types.)
inline constexpr PointLayoutTable<6> kHesai = {
    26,
    {{
        {"x", 0, F::FLOAT32, V::kX},
        {"y", 4, F::FLOAT32, V::kY},
        {"z", 8, F::FLOAT32, V::kZ},
        {"intensity", 12, F::FLOAT32, V::kReflectivity},
        {"ring", 16, F::UINT16, V::kRing},
        {"timestamp", 18, F::FLOAT64, V::kStampSeconds},
    }},
};

}  // namespace point_layouts

// A layout's table as a type, for code generic over the layouts: its fields are constants there.
template <const auto& kTable>
struct PointLayoutRef {
  static constexpr const auto& table = kTable;
};

// f(PointLayoutRef<the table of layout>{}): what f returns, the same type for every table.
template <class F>
decltype(auto) withPointLayout(PointLayout layout, F&& f) {
  switch (layout) {
    case PointLayout::kOuster:
      return f(PointLayoutRef<point_layouts::kOuster>{});
    case PointLayout::kOusterLegacy:
      return f(PointLayoutRef<point_layouts::kOusterLegacy>{});
    case PointLayout::kLivox:
      return f(PointLayoutRef<point_layouts::kLivox>{});
    case PointLayout::kHesai:
      return f(PointLayoutRef<point_layouts::kHesai>{});
    case PointLayout::kVelodyne:
    default:
      return f(PointLayoutRef<point_layouts::kVelodyne>{});
  }
}

// Why `layout` cannot hold the points of a scan of `rings` rings whose last beam column is taken
// `sweep_duration` s after the stamp, or "" if it can: a ring number in uint8 (ouster_legacy's
// ring, livox's line) allows 256 rings, a time in uint32 nanoseconds (the ouster layouts' t)
// 4.294967295 s.
std::string pointLayoutLimit(PointLayout layout, int rings, double sweep_duration);

}  // namespace laser_raycast
