// cast_scan with beams off any grid: --pattern-file (each pose's scan the file's next rows, point k
// at k / HZ s, on the closed room of test/data/sensors_room.urdf at distances worked out here) and
// --calibration (a Velodyne calibration YAML: its turn's beams, rings and firing times) and
// --ouster-metadata (an Ouster metadata JSON: its rows' beams and origins, its columns' times).
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <string>

#include "cast_scan_cli.h"
#include "sensors_room.h"
#include "temp_files.h"

namespace laser_raycast_test {
namespace {

const std::string kData = std::string(LASER_RAYCAST_SOURCE_DIR) + "/test/data/";
const std::string kRoom = "--urdf " + kData + "sensors_room.urdf";
const std::string kHeader = "pose,index,line,azimuth,elevation,time,range,link";
constexpr double kDeg = M_PI / 180;

// Rows (azimuth, zenith, line) of the pattern below, deg.
constexpr double kRows[4][3] = {{0, 90, 2}, {90, 60, 0}, {-135, 100, 1}, {30, 180, 3}};

TEST(CastScanBeams, PatternFileScansTakeTheNextRows) {
  const std::string pattern = writeFile("pattern.csv",
                                        "Time/s,Azimuth/deg,Zenith/deg,Line\n"
                                        "0,0,90,2\n0.1,90,60,0\n0.2,-135,100,1\n0.3,30,180,3\n");
  const std::string poses = writeFile("poses.txt", "0,0,1,0,0,0\n1,-1,2,0,0,0\n");
  const CliRun run = runCli(kRoom + " --poses " + poses + " --pattern-file " + pattern +
                            " --point-rate 1000 --points-per-scan 3");
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = csvRows(run.out, kHeader);
  ASSERT_EQ(rows.size(), 6u);
  const Eigen::Vector3d sensors[2] = {{0, 0, 1}, {1, -1, 2}};
  for (int r = 0; r < 6; ++r) {
    const int pose = r / 3, k = r % 3, row = (pose * 3 + k) % 4;  // the file a loop
    const double az = kRows[row][0] * kDeg, zen = kRows[row][1] * kDeg;
    const Eigen::Vector3d d(std::sin(zen) * std::cos(az), std::sin(zen) * std::sin(az),
                            std::cos(zen));
    EXPECT_EQ(std::stoi(rows[r][0]), pose);
    EXPECT_EQ(std::stoi(rows[r][1]), k);
    EXPECT_EQ(std::stoi(rows[r][2]), static_cast<int>(kRows[row][2]));
    EXPECT_NEAR(std::stod(rows[r][4]), M_PI / 2 - zen, 1e-8) << r;
    EXPECT_NEAR(std::stod(rows[r][5]), k / 1000.0, 1e-12) << r;
    EXPECT_NEAR(std::stod(rows[r][6]), roomDistance(sensors[pose], d), 1e-7) << r;
    if (zen > 0) {
      EXPECT_NEAR(std::stod(rows[r][3]), az, 1e-8) << r;
    }
  }
}

// --intensity for beams off the grid: each pattern row's incidence on the room's face it meets
// (the default reflectivity 1), from its own direction.
TEST(CastScanBeams, PatternFileIntensities) {
  const std::string pattern = writeFile("pattern_i.csv",
                                        "Time/s,Azimuth/deg,Zenith/deg,Line\n"
                                        "0,0,90,2\n0.1,90,60,0\n0.2,-135,100,1\n0.3,30,180,3\n");
  const CliRun run = runCli(kRoom + " --sensor 0.5,-1,1,0,0,0 --pattern-file " + pattern +
                            " --point-rate 1000 --intensity");
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = csvRows(run.out, "index,line,azimuth,elevation,time,range,link,intensity");
  ASSERT_EQ(rows.size(), 4u);
  const Eigen::Vector3d sensor(0.5, -1, 1);
  for (int r = 0; r < 4; ++r) {
    const double az = kRows[r][0] * kDeg, zen = kRows[r][1] * kDeg;
    const Eigen::Vector3d d(std::sin(zen) * std::cos(az), std::sin(zen) * std::sin(az),
                            std::cos(zen));
    EXPECT_NEAR(std::stod(rows[r][7]), std::abs(d[roomFaceAxis(sensor, d)]), 1e-6) << r;
  }
}

// VLP-16 laser 0 (-15 deg, no vertical offset) from 1 m up meets the floor 1 / sin(15 deg) m
// along its beam, whatever its azimuth; laser i of sequence s fires at s * 55.296 + i * 2.304 us.
TEST(CastScanBeams, CalibrationGivesTheHeadsBeams) {
  const CliRun run =
      runCli(kRoom + " --sensor 0,0,1,0,0,0 --calibration " + kData + "vlp16_calibration.yaml");
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = csvRows(run.out, "index,line,azimuth,elevation,time,range,link");
  ASSERT_EQ(rows.size(), 1808u * 16u);
  const int rings[16] = {0, 8, 1, 9, 2, 10, 3, 11, 4, 12, 5, 13, 6, 14, 7, 15};
  for (std::size_t b = 0; b < rows.size(); b += 7) {
    const int s = static_cast<int>(b) / 16, i = static_cast<int>(b) % 16;
    EXPECT_EQ(std::stoi(rows[b][1]), rings[i]) << b;
    EXPECT_NEAR(std::stod(rows[b][4]), s * 55.296e-6 + i * 2.304e-6, 1e-10) << b;
    if (i == 0) {
      EXPECT_NEAR(std::stod(rows[b][5]), 1 / std::sin(15 * kDeg), 1e-7) << b;
      EXPECT_EQ(rows[b][6], "floor") << b;
    }
  }
}

// An Ouster head of 4 rows and 512 columns whose lidar frame is turned a quarter turn about z and
// raised 30 mm: row r of column c leaves from the beam origin (15.806 mm out along the encoder
// angle 2 pi (1 - c / 512)) along the encoder angle less the row's azimuth offset, at the row's
// altitude (Ouster's formulas, written out here), and meets the room where worked out here.
const double kOusterAlt[4] = {20.5, 7.25, -3.0, -21.75};
const double kOusterAz[4] = {4.0, 1.5, -1.25, -3.5};
const std::string kOusterJson =
    "{\"beam_altitude_angles\": [20.5, 7.25, -3.0, -21.75],"
    " \"beam_azimuth_angles\": [4.0, 1.5, -1.25, -3.5],"
    " \"lidar_origin_to_beam_origin_mm\": 15.806, \"lidar_mode\": \"512x20\","
    " \"lidar_to_sensor_transform\": [0, -1, 0, 0, 1, 0, 0, 0, 0, 0, 1, 30, 0, 0, 0, 1]}";

void expectOusterRows(const std::vector<std::vector<std::string>>& rows, double scan_time) {
  const Eigen::Vector3d sensor(0, 0, 1);
  for (std::size_t b = 0; b < rows.size(); b += 5) {
    const int c = static_cast<int>(b) / 4, r = static_cast<int>(b) % 4;
    const double encoder = 2 * M_PI * (1 - c / 512.0);
    const double az = encoder - kOusterAz[r] * kDeg, alt = kOusterAlt[r] * kDeg;
    // The quarter turn: lidar (x, y, z) is sensor (-y, x, z).
    const Eigen::Vector3d d(-std::sin(az) * std::cos(alt), std::cos(az) * std::cos(alt),
                            std::sin(alt));
    const Eigen::Vector3d origin(-0.015806 * std::sin(encoder), 0.015806 * std::cos(encoder),
                                 0.030);
    EXPECT_EQ(std::stoi(rows[b][1]), r) << b;
    EXPECT_NEAR(std::stod(rows[b][2]), std::atan2(d.y(), d.x()), 1e-8) << b;
    EXPECT_NEAR(std::stod(rows[b][3]), std::asin(d.z()), 1e-8) << b;
    EXPECT_NEAR(std::stod(rows[b][4]), c * scan_time / 512, 1e-10) << b;  // 9 digits
    EXPECT_NEAR(std::stod(rows[b][5]), roomDistance(sensor + origin, d), 1e-7) << b;
  }
}

TEST(CastScanBeams, OusterMetadataGivesTheHeadsBeams) {
  const std::string metadata = writeFile("ouster.json", kOusterJson);
  CliRun run = runCli(kRoom + " --sensor 0,0,1,0,0,0 --ouster-metadata " + metadata);
  ASSERT_EQ(run.status, 0) << run.err;
  auto rows = csvRows(run.out, "index,line,azimuth,elevation,time,range,link");
  ASSERT_EQ(rows.size(), 512u * 4u);
  expectOusterRows(rows, 1 / 20.0);  // the lidar mode's turn
  run = runCli(kRoom + " --sensor 0,0,1,0,0,0 --sweep rotating --scan-time 0.08" +
               " --ouster-metadata " + metadata);
  ASSERT_EQ(run.status, 0) << run.err;
  rows = csvRows(run.out, "index,line,azimuth,elevation,time,range,link");
  ASSERT_EQ(rows.size(), 512u * 4u);
  expectOusterRows(rows, 0.08);
}

TEST(CastScanBeams, BadArgumentsNameTheProblem) {
  const std::string pattern = writeFile("bad.csv", "Time/s,Azimuth/deg,Zenith/deg\n0,0,200\n");
  const std::string good = writeFile("good.csv", "Time/s,Azimuth/deg,Zenith/deg\n0,0,90\n");
  const std::string sensor = " --sensor 0,0,1,0,0,0";
  CliRun run = runCli(kRoom + sensor + " --pattern-file " + good);
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.err.find("--point-rate"), std::string::npos) << run.err;
  run = runCli(kRoom + sensor + " --pattern-file " + pattern + " --point-rate 10");
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.err.find("line 2: zenith 200 deg"), std::string::npos) << run.err;
  run = runCli(kRoom + sensor + " --pattern-file " + good + " --point-rate 10 --samples 5");
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.err.find("--samples: not with --pattern-file"), std::string::npos) << run.err;
  run = runCli(kRoom + sensor + " --calibration " + kData + "vlp16_calibration.yaml" +
               " --pattern-file " + good + " --point-rate 10");
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.err.find("not both"), std::string::npos) << run.err;
  const std::string ouster = writeFile("ouster.json", kOusterJson);
  run = runCli(kRoom + sensor + " --calibration " + kData + "vlp16_calibration.yaml" +
               " --ouster-metadata " + ouster);
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.err.find("give --calibration or --ouster-metadata, not both"), std::string::npos)
      << run.err;
  run = runCli(kRoom + sensor + " --ouster-metadata " + ouster + " --elevations 0.1,0.2");
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.err.find("--elevations: not with --ouster-metadata"), std::string::npos) << run.err;
  run = runCli(kRoom + sensor + " --ouster-metadata " + ouster + " --beam-samples 4");
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.err.find("--beam-samples > 1: not with --ouster-metadata"), std::string::npos)
      << run.err;
  const std::string bad = writeFile("bad_ouster.json", "{\"beam_altitude_angles\": [1]}");
  run = runCli(kRoom + sensor + " --ouster-metadata " + bad);
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.err.find("--ouster-metadata: ouster metadata " + bad +
                         ": beam_azimuth_angles is missing"),
            std::string::npos)
      << run.err;
  run = runCli(kRoom + sensor + " --points-per-scan 4");
  EXPECT_EQ(run.status, 2);
  EXPECT_NE(run.err.find("only with --pattern-file"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace laser_raycast_test
