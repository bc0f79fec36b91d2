// cast_scan along a path, run as a user would: a scan from each pose of a --poses file. Expected
// ranges are worked out by hand from test/data/cli_rings.urdf: a wall whose near face is the plane
// x = 2 and a floor whose top is the plane z = -1, both 20 m wide.
#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <string>
#include <vector>

#include "cast_scan_cli.h"
#include "temp_files.h"

namespace laser_raycast_test {
namespace {

const std::string kRings = std::string(LASER_RAYCAST_SOURCE_DIR) + "/test/data/cli_rings.urdf";
// Three beams: -0.4, 0, 0.4.
const std::string kThree = " --angle-min -0.4 --angle-max 0.4 --samples 3";

struct PoseRow {
  int pose, index;
  double angle;
  std::string range, link;
};

std::vector<PoseRow> parsePoses(const std::string& csv) {
  std::vector<PoseRow> rows;
  for (const auto& f : csvRows(csv, "pose,index,angle,range,link")) {
    rows.push_back(PoseRow{std::stoi(f[0]), std::stoi(f[1]), std::stod(f[2]), f[3], f[4]});
  }
  return rows;
}

// Four poses among comments, a blank line, white space and a CRLF line end; from each, the three
// beams' ranges by hand. Level, yawed by a: the wall at (2 - x) / cos(a + az). Pitched down by p:
// the beam's direction is (cos p cos az, sin az, -sin p cos az), so the floor, 1 m below, is at
// 1 / (sin p cos az), nearer than the wall at 2 / (cos p cos az) for p = 0.6.
TEST(CastScanPath, AScanFromEachPoseInFileOrder) {
  const std::string poses = writeFile("path.txt",
                                      "# x,y,z,roll,pitch,yaw\n"
                                      "0,0,0,0,0,0\n"
                                      "\n"
                                      "  0.5,1,0,0,0,0.3  \n"
                                      "# lifted, yawed the other way\n"
                                      "-1,-2,0.5,0,0,-0.2\r\n"
                                      "0,0,0,0,0.6,0\n");
  const CliRun run = runCli("--urdf " + kRings + " --poses " + poses + kThree);
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = parsePoses(run.out);
  ASSERT_EQ(rows.size(), 4u * 3u);
  for (int i = 0; i < 12; ++i) {
    const int pose = i / 3;
    const double az = -0.4 + 0.4 * (i % 3);
    EXPECT_EQ(rows[i].pose, pose) << i;
    EXPECT_EQ(rows[i].index, i % 3) << i;
    EXPECT_NEAR(rows[i].angle, az, 1e-9) << i;
    const double expected[4] = {2 / std::cos(az), 1.5 / std::cos(0.3 + az), 3 / std::cos(-0.2 + az),
                                1 / (std::sin(0.6) * std::cos(az))};
    EXPECT_NEAR(std::stod(rows[i].range), expected[pose], 1e-8) << i;
    EXPECT_EQ(rows[i].link, pose == 3 ? "floor" : "wall") << i;
  }
  EXPECT_NEAR(std::stod(rows[4].range), 1.57012740, 1e-8);  // 1.5 / cos 0.3
}

// A file of one pose gives --sensor's scan with the column 'pose' in front, also with rings.
TEST(CastScanPath, OnePoseIsTheSensorsScanWithAPoseColumn) {
  const std::string poses = writeFile("one.txt", "0.5,1,0,0,0,0.3\n");
  for (const std::string rings : {"", " --elevations 0.3,-0.6,0"}) {
    const CliRun sensor = runCli("--urdf " + kRings + " --sensor 0.5,1,0,0,0,0.3" + kThree + rings);
    const CliRun path = runCli("--urdf " + kRings + " --poses " + poses + kThree + rings);
    ASSERT_EQ(sensor.status, 0) << sensor.err;
    ASSERT_EQ(path.status, 0) << path.err;
    const std::string with_pose =
        "pose," + std::regex_replace(sensor.out, std::regex("\n(.)"), "\n0,$1");
    EXPECT_EQ(path.out, with_pose) << rings;
  }
}

TEST(CastScanPath, RepeatTimesThePath) {
  const std::string poses = writeFile("repeat.txt", "0,0,0,0,0,0\n0.5,0,0,0,0,0\n1,0,0,0,0,0\n");
  const CliRun run = runCli("--urdf " + kRings + " --poses " + poses + kThree + " --repeat 2");
  ASSERT_EQ(run.status, 0) << run.err;
  EXPECT_TRUE(std::regex_search(run.err, std::regex("(^|\n)cast_ns_per_scan_median=[0-9]+\n")))
      << run.err;
  const auto rows = parsePoses(run.out);
  ASSERT_EQ(rows.size(), 9u);
  EXPECT_NEAR(std::stod(rows[7].range), 1.0, 1e-8);  // the last pose, straight ahead
}

TEST(CastScanPath, BadPosesFilesExitTwoNamingTheFileAndLine) {
  const std::string base = "--urdf " + kRings + kThree + " --poses ";
  const std::string short_line = writeFile("short.txt", "# path\n0,0,0,0,0,0\n\n0,0,0,0,0\n");
  expectBadArguments(base + short_line, short_line + ":4: '0,0,0,0,0' is not x,y,z,roll,pitch,yaw");
  const std::string nan = writeFile("nan.txt", "0,0,0,0,0,nan\n0,0,0,0,0,0\n");
  expectBadArguments(base + nan, nan + ":1: '0,0,0,0,0,nan'");
  const std::string trailing = writeFile("trailing.txt", "0,0,0,0,0,0\n0,0,0,0,0,0 # here\n");
  expectBadArguments(base + trailing, trailing + ":2:");
  const std::string comments = writeFile("comments.txt", "# nothing\n\n   \n");
  expectBadArguments(base + comments, "--poses " + comments + ": no pose");
  expectBadArguments(base + "/nonexistent/path.txt",
                     "--poses: cannot read '/nonexistent/path.txt'");
  expectBadArguments(base + tempDir().string(), "--poses: cannot read '" + tempDir().string());
}

TEST(CastScanPath, PosesAndSensorAreExclusive) {
  const std::string poses = writeFile("both.txt", "0,0,0,0,0,0\n");
  expectBadArguments("--urdf " + kRings + " --sensor 0,0,0,0,0,0 --poses " + poses,
                     "give --sensor or --poses, not both");
  expectBadArguments("--urdf " + kRings, "--sensor (or --poses) is required");
  expectBadArguments("--urdf " + kRings + " --poses " + poses + " --poses " + poses, "--poses");
}

TEST(CastScanPath, HelpListsThePathFlags) {
  const CliRun run = runCli("--help");
  ASSERT_EQ(run.status, 0);
  for (const char* text :
       {"(--sensor x,y,z,roll,pitch,yaw | --poses FILE)", "--poses FILE", "led by 'pose'"}) {
    EXPECT_NE(run.out.find(text), std::string::npos) << text << "\n" << run.out;
  }
}

}  // namespace
}  // namespace laser_raycast_test
