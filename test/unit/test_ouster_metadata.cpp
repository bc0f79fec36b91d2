// Ouster heads (core::OusterHead, loadOusterMetadata): for a few rows and columns of metadata files
// in both layouts, a beam's origin plus the range measured from it along its direction is the point
// Ouster's "range to XYZ" formulas give (written out here: the encoder angle 2 pi (1 - c / W), the
// row's azimuth offset subtracted, its altitude, the beam origin n out along the encoder angle,
// the range less n along the beam, then lidar_to_sensor_transform in mm); rows are rings; column c
// is at its own time; bad files are refused naming the file and the key.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <fstream>
#include <string>

#include "laser_raycast/core/ouster_beams.h"
#include "laser_raycast/loader/ouster_metadata.h"

namespace laser_raycast_test {
namespace {

namespace core = laser_raycast::core;

constexpr double kDeg = M_PI / 180;

// Four rows; a lidar_to_sensor of a quarter turn about z and (10, 20, 30) mm.
const char* kAltitudes = "[20.5, 7.25, -3.0, -21.75]";
const char* kAzimuths = "[4.0, 1.5, -1.25, -3.5]";
const double kAlt[4] = {20.5, 7.25, -3.0, -21.75};
const double kAz[4] = {4.0, 1.5, -1.25, -3.5};
const char* kTransform = "[0, -1, 0, 10, 1, 0, 0, 20, 0, 0, 1, 30, 0, 0, 0, 1]";

std::string write(const std::string& name, const std::string& text) {
  const std::string path = testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

// Ouster's point for row r, column c of W and range R (mm), in the sensor frame, m: beam origin
// (nx cos te, nx sin te, nz) plus (R - |(nx, nz)|) along the beam, then the transform M.
Eigen::Vector3d ousterPoint(double alt_deg, double az_deg, int c, int w, double range_mm, double nx,
                            double nz, const Eigen::Matrix4d& m) {
  const double te = 2 * M_PI * (1 - static_cast<double>(c) / w);
  const double ta = -az_deg * kDeg, phi = alt_deg * kDeg;
  const double n = std::sqrt(nx * nx + nz * nz);
  const Eigen::Vector4d lidar(
      (range_mm - n) * std::cos(te + ta) * std::cos(phi) + nx * std::cos(te),
      (range_mm - n) * std::sin(te + ta) * std::cos(phi) + nx * std::sin(te),
      (range_mm - n) * std::sin(phi) + nz, 1);
  return (m * lidar).head<3>() / 1000;
}

Eigen::Matrix4d quarterTurn() {
  Eigen::Matrix4d m;
  m << 0, -1, 0, 10, 1, 0, 0, 20, 0, 0, 1, 30, 0, 0, 0, 1;
  return m;
}

// Every listed (row, column): origin and origin + (R - n) mm along the beam are Ouster's points for
// ranges n and R.
void expectOusterBeams(const core::BeamList& beams, int w, int first_column, double scan_time,
                       double nx, double nz, const Eigen::Matrix4d& m) {
  const int window = beams.size() / 4;
  const double n = std::sqrt(nx * nx + nz * nz);
  for (int k : {0, 1, window / 2, window - 1}) {
    const int c = (first_column + k) % w;
    for (int r = 0; r < 4; ++r) {
      const int i = k * 4 + r;
      SCOPED_TRACE("column " + std::to_string(c) + " row " + std::to_string(r));
      EXPECT_LT((beams.origin(i) - ousterPoint(kAlt[r], kAz[r], c, w, n, nx, nz, m)).norm(), 1e-12);
      const double range_mm = 5000;
      const Eigen::Vector3d at = beams.origin(i) + (range_mm - n) / 1000 * beams.directions[i];
      EXPECT_LT((at - ousterPoint(kAlt[r], kAz[r], c, w, range_mm, nx, nz, m)).norm(), 1e-12);
      EXPECT_EQ(beams.line(i), r);
      EXPECT_NEAR(beams.time(i), k * scan_time / w, 1e-15);
    }
  }
}

TEST(OusterMetadata, LegacyLayout) {
  const std::string path =
      write("legacy.json", std::string("{\"beam_altitude_angles\": ") + kAltitudes +
                               ", \"beam_azimuth_angles\": " + kAzimuths +
                               ", \"lidar_origin_to_beam_origin_mm\": 15.806,"
                               " \"lidar_mode\": \"512x20\", "
                               "\"lidar_to_sensor_transform\": " +
                               kTransform +
                               ", \"data_format\": {\"columns_per_frame\": 512,"
                               " \"pixels_per_column\": 4, "
                               "\"pixel_shift_by_row\": [9, 3, -3, -9]},"
                               " \"prod_line\": \"OS-1-16\"}");
  const core::OusterHead head = laser_raycast::loadOusterMetadata(path);
  EXPECT_EQ(head.columns, 512);
  EXPECT_EQ(head.fps, 20);
  EXPECT_EQ(head.first_column, 0);
  EXPECT_EQ(head.last_column, 511);
  const core::BeamList beams = head.scan(0.05);
  ASSERT_EQ(beams.size(), 512 * 4);
  EXPECT_NO_THROW(beams.validate());
  expectOusterBeams(beams, 512, 0, 0.05, 15.806, 0, quarterTurn());
}

// The nested layout, with a beam_to_lidar_transform whose z offset moves the origin up and counts
// in n, and a column window that wraps round the end of the turn.
TEST(OusterMetadata, NestedLayoutWithWindowAndBeamTransform) {
  const std::string path = write(
      "nested.json",
      std::string("{\"sensor_info\": {\"prod_line\": \"OS-2-32\"},\n"
                  "\"config_params\": {\"lidar_mode\": \"512x10\"},\n"
                  "\"lidar_data_format\": {\"columns_per_frame\": 512, \"pixels_per_column\": 4,"
                  " \"column_window\": [500, 10], \"pixel_shift_by_row\": [1, 2, 3, 4]},\n"
                  "\"beam_intrinsics\": {\"beam_altitude_angles\": ") +
          kAltitudes + ", \"beam_azimuth_angles\": " + kAzimuths +
          ", \"lidar_origin_to_beam_origin_mm\": 27.67,"
          " \"beam_to_lidar_transform\": [1, 0, 0, 27.116, 0, 1, 0, 0, 0, 0, 1, -5.5, 0, 0, 0, 1]},"
          "\n\"lidar_intrinsics\": {\"lidar_to_sensor_transform\": " +
          kTransform +
          "},\n\"imu_intrinsics\": {}, \"calibration_status\": {\"reflectivity\": {\"valid\": "
          "true}}}");
  const core::OusterHead head = laser_raycast::loadOusterMetadata(path);
  EXPECT_EQ(head.first_column, 500);
  EXPECT_EQ(head.last_column, 10);
  const core::BeamList beams = head.scan(0.1);
  ASSERT_EQ(beams.size(), (12 + 11) * 4);  // columns 500 .. 511 and 0 .. 10
  expectOusterBeams(beams, 512, 500, 0.1, 27.116, -5.5, quarterTurn());
}

// Without beam_to_lidar_transform, lidar_origin_to_beam_origin_mm or lidar_to_sensor_transform,
// ouster-sdk's defaults: the product line's beam origin, and a half turn about z 36.18 mm up. The
// columns come from columns_per_frame alone.
TEST(OusterMetadata, Defaults) {
  const std::string path =
      write("defaults.json", std::string("{\"beam_altitude_angles\": ") + kAltitudes +
                                 ", \"beam_azimuth_angles\": " + kAzimuths +
                                 ", \"prod_line\": \"OS-0-32\","
                                 " \"data_format\": {\"columns_per_frame\": 512}}");
  const core::OusterHead head = laser_raycast::loadOusterMetadata(path);
  EXPECT_EQ(head.beam_origin_x_mm, 27.67);
  Eigen::Matrix4d m;
  m << -1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 36.18, 0, 0, 0, 1;
  EXPECT_EQ(head.lidar_to_sensor, m);
  expectOusterBeams(head.scan(0.1), 512, 0, 0.1, 27.67, 0, m);
}

// config/ouster/os1_64_nominal.json: 64 rows spread uniformly over +16.6 to -16.6 deg, the
// stagger +9, +3, -3, -9 ticks of 360 / 1024 deg, 1024 columns at 10 Hz.
TEST(OusterMetadata, NominalOs1_64) {
  const core::OusterHead head = laser_raycast::loadOusterMetadata(
      LASER_RAYCAST_SOURCE_DIR "/config/ouster/os1_64_nominal.json");
  ASSERT_EQ(head.rows(), 64);
  EXPECT_EQ(head.columns, 1024);
  EXPECT_EQ(head.fps, 10);
  EXPECT_EQ(head.beam_origin_x_mm, 12.163);
  const double ticks[4] = {9, 3, -3, -9};
  for (int r = 0; r < 64; ++r) {
    EXPECT_NEAR(head.altitudes_deg[r], 16.6 - r * 33.2 / 63, 5e-5) << r;
    EXPECT_NEAR(head.azimuths_deg[r], ticks[r % 4] * 360 / 1024, 5e-5) << r;
  }
  const core::BeamList beams = head.scan(0.1);
  EXPECT_EQ(beams.size(), 64 * 1024);
  EXPECT_NO_THROW(beams.validate());
}

TEST(OusterMetadata, BadFilesAreRefused) {
  auto message = [](const std::string& text) {
    const std::string path = write("bad_ouster.json", text);
    try {
      laser_raycast::loadOusterMetadata(path);
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path), std::string::npos) << what;
      return what;
    }
    return std::string("<no exception>");
  };
  auto contains = [](const std::string& text, const std::string& part) {
    return text.find(part) != std::string::npos;
  };
  const std::string beams =
      std::string("\"beam_altitude_angles\": ") + kAltitudes + ", \"beam_azimuth_angles\": ";
  const std::string mode = ", \"lidar_mode\": \"1024x10\"";
  EXPECT_PRED2(contains, message("{\"beam_altitude_angles\": [1, 2"), "ouster metadata");
  EXPECT_PRED2(contains, message("[1, 2]"), "not an object");
  EXPECT_PRED2(contains, message("{\"lidar_mode\": \"1024x10\"}"),
               "beam_altitude_angles is missing");
  EXPECT_PRED2(
      contains,
      message("{\"beam_intrinsics\": {\"beam_azimuth_angles\": [1]}, \"config_params\": {}}"),
      "beam_intrinsics.beam_altitude_angles is missing");
  EXPECT_PRED2(contains, message("{" + beams + "[1, \"2\", 3, 4]" + mode + "}"),
               "beam_azimuth_angles[1] is not a number");
  EXPECT_PRED2(contains, message("{" + beams + "[1, 2, 3]" + mode + "}"),
               "4 beam_altitude_angles but 3 beam_azimuth_angles");
  EXPECT_PRED2(contains, message("{" + beams + "[[1, 2], [3, 4]]" + mode + "}"),
               "beam_azimuth_angles holds arrays");
  EXPECT_PRED2(contains, message("{" + beams + kAzimuths + "}"),
               "lidar_mode is missing, and so is data_format.columns_per_frame");
  EXPECT_PRED2(contains, message("{" + beams + kAzimuths + ", \"lidar_mode\": \"1024\"}"),
               "lidar_mode '1024' is not of the form COLUMNSxFPS");
  EXPECT_PRED2(
      contains,
      message("{" + beams + kAzimuths + mode + ", \"data_format\": {\"columns_per_frame\": 2048}}"),
      "data_format.columns_per_frame 2048 does not match lidar_mode (1024 columns)");
  EXPECT_PRED2(
      contains,
      message("{" + beams + kAzimuths + mode + ", \"data_format\": {\"pixels_per_column\": 16}}"),
      "data_format.pixels_per_column is not the number of beam_altitude_angles (4)");
  EXPECT_PRED2(contains,
               message("{" + beams + kAzimuths + mode +
                       ", \"data_format\": {\"column_window\": [0, 1024]}}"),
               "column_window [0, 1024] is not within [0, 1023]");
  EXPECT_PRED2(contains,
               message("{" + beams + kAzimuths + mode + ", \"data_format\": {\"fps\": 0}}"),
               "fps 0 is not > 0");
  EXPECT_PRED2(contains,
               message("{" + beams + kAzimuths + mode +
                       ", \"lidar_to_sensor_transform\": [2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, "
                       "0, 0, 1]}"),
               "lidar_to_sensor_transform is not a rotation and a translation");
  EXPECT_PRED2(contains,
               message("{" + beams + kAzimuths + mode + ", \"lidar_to_sensor_transform\": [1]}"),
               "lidar_to_sensor_transform has 1 numbers, not 16");
  EXPECT_PRED2(contains,
               message("{\"beam_altitude_angles\": [91, 0, 1, 2], \"beam_azimuth_angles\": " +
                       std::string(kAzimuths) + mode + "}"),
               "beam_altitude_angles[0] 91 deg is outside [-90, 90]");
}

}  // namespace
}  // namespace laser_raycast_test
