// Calibrated Velodyne heads (core::VelodyneHead, loadVelodyneCalibration): every beam's origin plus
// a range along its direction is the point velodyne_pointcloud's formulas give for that laser,
// azimuth and distance (written out here from the driver's unpacking: the distance in the xy
// plane, the horizontal offset across it, the vertical offset along the elevation's normal, and
// the driver's turn into the ROS frame, x = its y and y = minus its x); rings ascend with
// elevation; lasers fire at the user manual's times.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "laser_raycast/core/velodyne_beams.h"
#include "laser_raycast/loader/velodyne_calibration.h"

namespace laser_raycast_test {
namespace {

namespace core = laser_raycast::core;

constexpr double kDeg = M_PI / 180;
const std::string kCalibration = LASER_RAYCAST_SOURCE_DIR "/test/data/vlp16_calibration.yaml";

// The driver's point for a laser at its head azimuth psi (clockwise, the packet's) and distance d.
Eigen::Vector3d driverPoint(const core::VelodyneLaser& l, double psi, double d) {
  const double a = psi - l.rot_correction;
  const double ct = std::cos(l.elevation), st = std::sin(l.elevation);
  const double xy = d * ct - l.vert_offset * st;
  const double xv = xy * std::sin(a) - l.horiz_offset * std::cos(a);
  const double yv = xy * std::cos(a) + l.horiz_offset * std::sin(a);
  const double z = d * st + l.vert_offset * ct;
  return Eigen::Vector3d(yv, -xv, z);
}

TEST(VelodyneCalibration, ReadsTheDriversYaml) {
  const core::VelodyneHead head = laser_raycast::loadVelodyneCalibration(kCalibration);
  ASSERT_EQ(head.lasers.size(), 16u);
  EXPECT_EQ(head.timing.laser_period, 2.304e-6);
  EXPECT_EQ(head.timing.sequence_period, 55.296e-6);
  const double published[16] = {-15, 1, -13, 3, -11, 5, -9, 7, -7, 9, -5, 11, -3, 13, -1, 15};
  for (int i = 0; i < 16; ++i) {
    const core::VelodyneLaser& l = head.lasers[i];
    EXPECT_EQ(l.id, i);
    EXPECT_NEAR(l.elevation, published[i] * kDeg, 1e-15);
    EXPECT_NEAR(l.rot_correction, (i % 3 - 1) * 0.01, 1e-15);
    EXPECT_NEAR(l.vert_offset, 0.01 * (i % 2), 1e-15);
    EXPECT_NEAR(l.horiz_offset, i % 2 ? 0.0 : -0.02, 1e-15);
  }
}

// Every beam of a turn: the driver's point at 7.5 m, rings, times.
TEST(VelodyneCalibration, BeamsAreWhereTheDriverPutsThePoints) {
  const core::VelodyneHead head = laser_raycast::loadVelodyneCalibration(kCalibration);
  const double scan_time = 0.1;
  const core::BeamList beams = head.scan(scan_time);
  ASSERT_EQ(beams.size(), 1808 * 16);  // floor(0.1 s / 55.296 us) sequences
  EXPECT_NO_THROW(beams.validate());
  // Rings by ascending elevation: -15 (id 0) is ring 0, -13 (id 2) ring 1, ... 15 (id 15) ring 15.
  const int rings[16] = {0, 8, 1, 9, 2, 10, 3, 11, 4, 12, 5, 13, 6, 14, 7, 15};
  for (int b = 0; b < beams.size(); b += 37) {
    const int s = b / 16, i = b % 16;
    const double t = s * 55.296e-6 + i * 2.304e-6;
    EXPECT_NEAR(beams.times[b], t, 1e-15) << b;
    EXPECT_EQ(beams.lines[b], rings[i]) << b;
    // The head starts at the back (azimuth pi, counter-clockwise) and turns clockwise: the
    // driver's (clockwise) azimuth is minus the head's.
    const double psi = -(M_PI - 2 * M_PI * t / scan_time);
    const Eigen::Vector3d expected = driverPoint(head.lasers[i], psi, 7.5);
    EXPECT_LT((beams.origins[b] + 7.5 * beams.directions[b] - expected).norm(), 1e-12) << b;
  }
}

TEST(VelodyneCalibration, NominalHeads) {
  const core::VelodyneHead vlp = core::nominalVlp16();
  EXPECT_NEAR(vlp.lasers[1].elevation, 1 * kDeg, 1e-15);
  EXPECT_NEAR(vlp.lasers[2].elevation, -13 * kDeg, 1e-15);
  const core::VelodyneHead hdl = core::nominalHdl32e();
  ASSERT_EQ(hdl.lasers.size(), 32u);
  const std::vector<int> rings = hdl.rings();
  EXPECT_EQ(rings[0], 0);    // -30.67
  EXPECT_EQ(rings[31], 31);  // +10.67
  EXPECT_EQ(rings[15], 23);  // 0: above the 23 lasers below the horizon
  const core::BeamList beams = hdl.scan(0.1);
  EXPECT_EQ(beams.size(), 2170 * 32);  // floor(0.1 s / 46.08 us) sequences
  EXPECT_NEAR(beams.times[33], 46.08e-6 + 1.152e-6, 1e-15);
}

TEST(VelodyneCalibration, BadFilesAreRefused) {
  const std::string path = testing::TempDir() + "/bad_velodyne.yaml";
  auto message = [&](const std::string& text) {
    std::ofstream(path) << text;
    try {
      laser_raycast::loadVelodyneCalibration(path);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("<no exception>");
  };
  EXPECT_NE(message("num_lasers: 16\n").find("no `lasers` list"), std::string::npos);
  EXPECT_NE(message("lasers:\n- {laser_id: 0}\n").find("no vert_correction"), std::string::npos);
  EXPECT_NE(message("lasers:\n- {laser_id: 0, vert_correction: x}\n").find("not a number"),
            std::string::npos);
  EXPECT_NE(message("lasers:\n- {laser_id: 0, vert_correction: 0.1}\n").find("1 lasers"),
            std::string::npos);
  EXPECT_NE(message("lasers: [").find(path), std::string::npos);
}

}  // namespace
}  // namespace laser_raycast_test
