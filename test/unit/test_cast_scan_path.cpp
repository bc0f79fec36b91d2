// cast_scan along a path, run as a user would: a scan from each pose of a --poses file, and
// rotating sweeps of a sensor moving at a constant twist. Expected ranges are worked out by hand
// from test/data/cli_rings.urdf: a wall whose near face is the plane x = 2 and a floor whose top is
// the plane z = -1, both 20 m wide.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <regex>
#include <string>
#include <vector>

#include "cast_scan_cli.h"
#include "temp_files.h"

namespace laser_raycast_test {
namespace {

const std::string kRings = std::string(LASER_RAYCAST_SOURCE_DIR) + "/test/data/cli_rings.urdf";
// Three beams: -0.4, 0, 0.4. (The CSV's times, below 0.1 s here, carry 9 significant digits.)
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

struct SweepRow {
  int index;
  double angle;
  std::string range, link;
  double time;
};

std::vector<SweepRow> parseSweep(const std::string& csv) {
  std::vector<SweepRow> rows;
  for (const auto& f : csvRows(csv, "index,angle,range,link,time")) {
    rows.push_back(SweepRow{std::stoi(f[0]), std::stod(f[1]), f[2], f[3], std::stod(f[4])});
  }
  return rows;
}

// Nine beams a quarter turn apart, from -pi; S = 0.1 s, so column c is taken at
// c * (pi / 4) * 0.1 / (2 pi) = c * 0.0125 s, by then 1 m/s has carried the sensor c * 0.0125 m
// towards the wall: the beams in front meet it at (2 - c * 0.0125) / cos(az), the others nothing.
TEST(CastScanPath, RotatingSweepTowardsAWall) {
  const CliRun run = runCli("--urdf " + kRings +
                            " --sensor 0,0,0,0,0,0 --angle-min -3.141592653589793 --angle-max "
                            "3.141592653589793 --samples 9 --sweep rotating --scan-time 0.1 "
                            "--twist 1,0,0,0,0,0");
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = parseSweep(run.out);
  ASSERT_EQ(rows.size(), 9u);
  for (int c = 0; c < 9; ++c) {
    const double az = -M_PI + c * M_PI / 4, t = c * 0.0125;
    EXPECT_EQ(rows[c].index, c);
    EXPECT_NEAR(rows[c].angle, az, 1e-8) << c;
    EXPECT_NEAR(rows[c].time, t, 1e-10) << c;
    if (std::abs(az) < M_PI / 2) {
      EXPECT_NEAR(std::stod(rows[c].range), (2 - t) / std::cos(az), 1e-8) << c;
      EXPECT_EQ(rows[c].link, "wall") << c;
    } else {
      EXPECT_EQ(rows[c].range, "inf") << c;
    }
  }
  EXPECT_EQ(rows[4].range, "1.95");  // straight at the wall, 0.05 s (and m) after the first beam
  EXPECT_EQ(rows[8].time, 0.1);      // the last beam a whole turn after the first
}

// The turn is about the fixed frame's axes, applied on the left: rolled a quarter turn, the sensor
// scans the vertical plane y = 0, and turning about the world's z at 5 rad/s swings that plane
// sideways by th = 5 t. Beam az then points along (cos az cos th, cos az sin th, sin az): the wall
// at 2 / (cos az cos th), the floor below at 1 / sin(-az). (A turn about the sensor's own z would
// tilt the beam within its plane instead, to 2 / cos(az + th).)
TEST(CastScanPath, RotatingSweepTurnsAboutTheFixedAxes) {
  const CliRun run = runCli("--urdf " + kRings +
                            " --sensor 0,0,0,1.5707963267948966,0,0 --angle-min -0.6 --angle-max "
                            "0.6 --samples 7 --sweep rotating --scan-time 0.1 --twist 0,0,0,0,0,5");
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = parseSweep(run.out);
  ASSERT_EQ(rows.size(), 7u);
  for (int c = 0; c < 7; ++c) {
    const double az = -0.6 + 0.2 * c, t = c * 0.2 * 0.1 / (2 * M_PI), th = 5 * t;
    const double wall = 2 / (std::cos(az) * std::cos(th));
    const double floor = az < 0 ? 1 / std::sin(-az) : HUGE_VAL;
    EXPECT_NEAR(rows[c].time, t, 1e-10) << c;
    EXPECT_NEAR(std::stod(rows[c].range), std::min(wall, floor), 1e-8) << c;
    EXPECT_EQ(rows[c].link, floor < wall ? "floor" : "wall") << c;
  }
  EXPECT_NEAR(std::stod(rows[6].range), 2.43434749, 1e-8);  // 2 / (cos 0.6 cos(0.3 / pi))
}

// A turn of more than half a turn within one sweep (40 rad/s over 0.1 s: 4 rad): the sweep's
// samples lie close enough that each beam's pose is interpolated the way the sensor turns (two
// samples a sweep apart would be slerped the short way round, backwards). A level beam at az,
// cast t s after the first, points at world bearing b = az + 40 t and meets the wall at
// 2 / cos b where cos b > 0 and |tan b| < 5 (the wall is 20 m wide), and nothing where cos b < 0.
TEST(CastScanPath, RotatingSweepTurnsBeyondHalfATurn) {
  const int samples = 64;
  const double lo = -3.0, hi = 3.0, increment = (hi - lo) / (samples - 1);
  const CliRun run = runCli("--urdf " + kRings + " --sensor 0,0,0,0,0,0 --angle-min -3 " +
                            "--angle-max 3 --samples 64 --range-max 30 --sweep rotating " +
                            "--scan-time 0.1 --twist 0,0,0,0,0,40");
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = parseSweep(run.out);
  ASSERT_EQ(rows.size(), static_cast<std::size_t>(samples));
  int hits = 0, misses = 0;
  for (int c = 0; c < samples; ++c) {
    const double az = lo + c * increment, t = c * increment * 0.1 / (2 * M_PI), b = az + 40 * t;
    EXPECT_NEAR(rows[c].time, t, 1e-10) << c;
    if (std::cos(b) > 0.1 && std::abs(std::tan(b)) < 4.5) {
      EXPECT_NEAR(std::stod(rows[c].range), 2 / std::cos(b), 1e-8) << c;
      ++hits;
    } else if (std::cos(b) < -0.1) {
      EXPECT_EQ(rows[c].range, "inf") << c;
      ++misses;
    }
  }
  EXPECT_GT(hits, 10);
  EXPECT_GT(misses, 10);
}

// Without motion a rotating sweep is the instant scan, with the time column; planar and in rings.
TEST(CastScanPath, SweepWithoutTwistIsTheInstantScan) {
  const std::string base = "--urdf " + kRings +
                           " --sensor 0.3,-0.5,0.2,0.1,-0.05,0.4 --angle-min -1 --angle-max 1 "
                           "--samples 21";
  for (const std::string rings : {"", " --elevations -0.3,0,0.2"}) {
    const std::string sweep_args = rings + " --sweep rotating --scan-time 0.05";
    const CliRun instant = runCli(base + rings);
    const CliRun sweep = runCli(base + sweep_args);
    ASSERT_EQ(instant.status, 0) << instant.err;
    ASSERT_EQ(sweep.status, 0) << sweep.err;
    EXPECT_EQ(runCli(base + sweep_args + " --twist 0,0,0,0,0,0").out, sweep.out);
    const std::string header =
        rings.empty() ? "index,angle,range,link" : "index,ring,elevation,angle,range,link";
    const auto a = csvRows(instant.out, header);
    const auto b = csvRows(sweep.out, header + ",time");
    ASSERT_EQ(a.size(), rings.empty() ? 21u : 63u);
    ASSERT_EQ(b.size(), a.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      const std::size_t range = a[i].size() - 2;  // then the link; before it, as printed
      EXPECT_TRUE(std::equal(a[i].begin(), a[i].begin() + range, b[i].begin())) << i;
      EXPECT_NEAR(std::stod(b[i][range]), std::stod(a[i][range]), 1e-9) << i;
      EXPECT_EQ(b[i][range + 1], a[i][range + 1]) << i;
      EXPECT_NEAR(std::stod(b[i].back()), i % 21 * 0.1 * 0.05 / (2 * M_PI), 1e-10) << i;
    }
  }
}

// Each pose of the file starts a sweep of its own at the same twist: pose p at x = p meets the wall
// at (2 - p - t) / cos(az).
TEST(CastScanPath, RotatingSweepFromEachPose) {
  const std::string poses = writeFile("sweeps.txt", "0,0,0,0,0,0\n1,0.5,0,0,0,0\n");
  const CliRun run = runCli("--urdf " + kRings + " --poses " + poses + kThree +
                            " --sweep rotating --scan-time 0.1 --twist 1,0,0,0,0,0 --repeat 2");
  ASSERT_EQ(run.status, 0) << run.err;
  EXPECT_TRUE(std::regex_search(run.err, std::regex("(^|\n)cast_ns_per_scan_median=[0-9]+\n")))
      << run.err;
  const auto rows = csvRows(run.out, "pose,index,angle,range,link,time");
  ASSERT_EQ(rows.size(), 6u);
  for (int i = 0; i < 6; ++i) {
    const int pose = i / 3, c = i % 3;
    const double az = -0.4 + 0.4 * c, t = c * 0.4 * 0.1 / (2 * M_PI);
    EXPECT_EQ(rows[i][0], std::to_string(pose));
    EXPECT_EQ(rows[i][1], std::to_string(c));
    EXPECT_NEAR(std::stod(rows[i][3]), (2 - pose - t) / std::cos(az), 1e-8) << i;
    EXPECT_NEAR(std::stod(rows[i][5]), t, 1e-10) << i;
  }
}

TEST(CastScanPath, BadSweepsExitTwo) {
  const std::string base = "--urdf " + kRings + " --sensor 0,0,0,0,0,0 ";
  expectBadArguments(base + "--twist 1,0,0,0,0,0", "--twist: only with --sweep rotating");
  expectBadArguments(base + "--sweep instant --twist 1,0,0,0,0,0",
                     "--twist: only with --sweep rotating");
  expectBadArguments(base + "--scan-time 0.1", "--scan-time: only with --sweep rotating");
  expectBadArguments(base + "--sweep rotating", "--sweep rotating: give --scan-time");
  expectBadArguments(base + "--sweep rotating --twist 1,0,0,0,0,0",
                     "--sweep rotating: give --scan-time");
  expectBadArguments(base + "--sweep spinning",
                     "--sweep: 'spinning' is not one of instant, rotating");
  const std::string rotating = base + "--sweep rotating --scan-time ";
  expectBadArguments(rotating + "0", "--scan-time: '0' is not > 0 s");
  expectBadArguments(rotating + "-0.1", "--scan-time: '-0.1' is not > 0 s");
  expectBadArguments(rotating + "inf", "--scan-time: 'inf' is not a finite number");
  expectBadArguments(rotating + "nan", "--scan-time: 'nan' is not a finite number");
  expectBadArguments(rotating + "0.1 --twist 1,0,0", "--twist: '1,0,0' is not vx,vy,vz,wx,wy,wz");
  expectBadArguments(rotating + "0.1 --twist 1,0,0,0,0,inf", "--twist: '1,0,0,0,0,inf'");
  // Column times that doubles cannot tell apart, or that overflow.
  expectBadArguments(rotating + "1e-323", "--scan-time: too short: every beam's time is 0 s");
  expectBadArguments(rotating + "1e308 --samples 3",
                     "--scan-time: too long: the last beam's time is not finite");
}

TEST(CastScanPath, HelpListsThePathFlags) {
  const CliRun run = runCli("--help");
  ASSERT_EQ(run.status, 0);
  for (const char* text :
       {"(--sensor x,y,z,roll,pitch,yaw | --poses FILE)", "--poses FILE",
        "[--sweep instant | --sweep rotating --scan-time S [--twist vx,vy,vz,wx,wy,wz]]",
        "--scan-time S", "--twist vx,vy,vz,wx,wy,wz", "led by 'pose'", "ends with 'time'"}) {
    EXPECT_NE(run.out.find(text), std::string::npos) << text << "\n" << run.out;
  }
}

}  // namespace
}  // namespace laser_raycast_test
