// The offline CLI cast_scan, run as a user would: its scans (each flag's effect, the CSV format,
// the return and intensity columns). Expected ranges are worked out by hand in
// test/data/cli_joints.urdf, node_scene.urdf and cli_rings.urdf. Its help, argument forms and exit
// statuses: test_cast_scan_args.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include "cast_scan_cli.h"

namespace laser_raycast_test {
namespace {

const std::string kData = std::string(LASER_RAYCAST_SOURCE_DIR) + "/test/data/";
// Four beams: -pi/2, 0, pi/2, pi.
const std::string kFour =
    " --angle-min -1.5707963267948966 --angle-max 3.141592653589793 --samples 4";

struct Row {
  int index;
  double angle;
  std::string range;  // as printed
  std::string link;
};

std::vector<Row> parse(const std::string& csv) {
  std::vector<Row> rows;
  for (const auto& f : csvRows(csv, "index,angle,range,link")) {
    rows.push_back(Row{std::stoi(f[0]), std::stod(f[1]), f[2], f[3]});
  }
  return rows;
}

double value(const Row& row) { return std::stod(row.range); }

struct RingRow {
  int index, ring;
  double elevation, angle;
  std::string range, link;
};

// The CSV of a scan with --elevations.
std::vector<RingRow> parseRings(const std::string& csv) {
  std::vector<RingRow> rows;
  for (const auto& f : csvRows(csv, "index,ring,elevation,angle,range,link")) {
    rows.push_back(
        RingRow{std::stoi(f[0]), std::stoi(f[1]), std::stod(f[2]), std::stod(f[3]), f[4], f[5]});
  }
  return rows;
}

TEST(CastScan, FourBeamsAtHandComputedRanges) {
  const CliRun run = runCli("--urdf " + kData + "cli_joints.urdf --sensor 0,0,0,0,0,0" + kFour);
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = parse(run.out);
  ASSERT_EQ(rows.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(rows[i].index, i);
    EXPECT_NEAR(rows[i].angle, -M_PI / 2 + i * M_PI / 2, 1e-8);
  }
  EXPECT_NEAR(value(rows[0]), 0.9, 1e-8);
  EXPECT_EQ(rows[0].link, "slider");
  EXPECT_NEAR(value(rows[1]), 1.9, 1e-8);
  EXPECT_EQ(rows[1].link, "arm");
  EXPECT_EQ(rows[2].range, "inf");
  EXPECT_EQ(rows[2].link, "");
  EXPECT_NEAR(value(rows[3]), 1.45, 1e-8);
  EXPECT_EQ(rows[3].link, "plate");
}

TEST(CastScan, NineSignificantDigits) {
  // 1.9 prints as "1.9"; at yaw 0.04 the arm's face is 1.9 / cos(0.04) m away: 9 significant
  // digits.
  const CliRun run = runCli("--urdf " + kData + "cli_joints.urdf --sensor 0,0,0,0,0,0.04" + kFour);
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = parse(run.out);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_TRUE(std::regex_match(rows[1].range, std::regex("^[0-9]\\.[0-9]{8}$"))) << rows[1].range;
  EXPECT_NEAR(value(rows[1]), 1.9 / std::cos(0.04), 5e-9);
}

TEST(CastScan, DefaultsAre360BeamsOverTheFullTurn) {
  const CliRun run = runCli("--urdf " + kData + "cli_joints.urdf --sensor 0,0,0,0,0,0");
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = parse(run.out);
  ASSERT_EQ(rows.size(), 360u);
  EXPECT_NEAR(rows.front().angle, -M_PI, 1e-8);
  EXPECT_NEAR(rows.back().angle, M_PI, 1e-8);
}

TEST(CastScan, AngleIncrementGivesRoundedBeamCount) {
  // (0.5 - 0) / 0.1 = 5 -> 6 beams.
  const CliRun run = runCli("--urdf " + kData +
                            "cli_joints.urdf --sensor 0,0,0,0,0,0 --angle-min 0 --angle-max 0.5 "
                            "--angle-increment 0.1");
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = parse(run.out);
  ASSERT_EQ(rows.size(), 6u);
  EXPECT_NEAR(rows[5].angle, 0.5, 1e-8);
}

TEST(CastScan, SensorPoseIsXyzRollPitchYaw) {
  // Yaw pi/2: beam 0 (sensor +x) looks along world +y, where nothing is; beam "-pi/2" looks along
  // +x.
  const CliRun run =
      runCli("--urdf " + kData + "cli_joints.urdf --sensor 0,0,0,0,0,1.5707963267948966" + kFour);
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = parse(run.out);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_NEAR(value(rows[0]), 1.9, 1e-8);
  EXPECT_EQ(rows[1].range, "inf");
  // Roll pi: the scan plane is flipped, so the beam at +pi/2 looks along world -y at the slider.
  const CliRun flipped =
      runCli("--urdf " + kData + "cli_joints.urdf --sensor 0,0,0,3.141592653589793,0,0" + kFour);
  const auto f = parse(flipped.out);
  ASSERT_EQ(f.size(), 4u);
  EXPECT_NEAR(value(f[2]), 0.9, 1e-8);
  // Translation: 0.5 m towards the arm.
  const CliRun moved = runCli("--urdf " + kData + "cli_joints.urdf --sensor 0.5,0,0,0,0,0" + kFour);
  EXPECT_NEAR(value(parse(moved.out)[1]), 1.4, 1e-8);
}

TEST(CastScan, ModelPoseAfterAt) {
  const CliRun run =
      runCli("--urdf " + kData + "cli_joints.urdf@0.5,0,0,0,0,0 --sensor 0,0,0,0,0,0" + kFour);
  ASSERT_EQ(run.status, 0) << run.err;
  EXPECT_NEAR(value(parse(run.out)[1]), 2.4, 1e-8);
}

TEST(CastScan, JointsMoveLinks) {
  // swing = pi/2 carries the arm to +y; slide = 0.5 pushes the slider 0.5 m further along -y.
  const CliRun run = runCli("--urdf " + kData +
                            "cli_joints.urdf --sensor 0,0,0,0,0,0 --joint swing=1.5707963267948966 "
                            "--joint slide=0.5" +
                            kFour);
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = parse(run.out);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_NEAR(value(rows[0]), 1.4, 1e-8);
  EXPECT_EQ(rows[1].range, "inf");
  EXPECT_NEAR(value(rows[2]), 1.9, 1e-8);
  EXPECT_EQ(rows[2].link, "arm");
  // Several values after one --joint.
  const CliRun both = runCli("--urdf " + kData +
                             "cli_joints.urdf --sensor 0,0,0,0,0,0 --joint "
                             "swing=1.5707963267948966 slide=0.5" +
                             kFour);
  EXPECT_EQ(both.out, run.out);
}

TEST(CastScan, GeometryCollision) {
  // At pi - 0.5 rad the beam passes beside the 1 m visual plate but meets the 3 m collision plate
  // at x = -1.45: t = 1.45 / cos(0.5).
  const std::string beam =
      " --angle-min 2.641592653589793 --angle-max 2.741592653589793 --samples 2";
  const CliRun visual = runCli("--urdf " + kData + "cli_joints.urdf --sensor 0,0,0,0,0,0" + beam);
  const CliRun collision = runCli(
      "--urdf " + kData + "cli_joints.urdf --sensor 0,0,0,0,0,0 --geometry collision" + beam);
  ASSERT_EQ(visual.status, 0) << visual.err;
  ASSERT_EQ(collision.status, 0) << collision.err;
  EXPECT_EQ(parse(visual.out)[0].range, "inf");
  EXPECT_NEAR(value(parse(collision.out)[0]), 1.45 / std::cos(0.5), 1e-8);
}

TEST(CastScan, RangeLimitsFollowRep117) {
  const CliRun run =
      runCli("--urdf " + kData +
             "cli_joints.urdf --sensor 0,0,0,0,0,0 --range-min 1.0 --range-max 1.5" + kFour);
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = parse(run.out);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].range, "-inf");  // slider at 0.9 < range_min
  EXPECT_EQ(rows[0].link, "slider");
  EXPECT_EQ(rows[1].range, "inf");  // arm at 1.9 > range_max
  EXPECT_NEAR(value(rows[3]), 1.45, 1e-8);
}

TEST(CastScan, EveryMethodGivesTheSameScan) {
  // From beside the origin's "mover" sphere, so that beams reach the mesh plate and the primitives.
  const std::string base = "--urdf " + kData + "node_scene.urdf --sensor 0.5,0,0,0,0,0.1";
  const CliRun reference = runCli(base);
  ASSERT_EQ(reference.status, 0) << reference.err;
  for (const char* method : {"seed_plane", "seed_uv", "cramer", "moller_trumbore", "watertight"}) {
    const CliRun run = runCli(base + " --method " + method);
    EXPECT_EQ(run.status, 0) << method << ": " << run.err;
    EXPECT_EQ(parse(run.out).size(), 360u) << method;
    // The mesh plate is hit away from its edges at this yaw, so all methods agree to the printed
    // digit.
    EXPECT_EQ(run.out, reference.out) << method;
  }
}

TEST(CastScan, SeveralModelsKeepTheirLinkNames) {
  // node_scene.urdf (package:// mesh) lifted 5 m is out of the plane; a second copy of cli_joints
  // 10 m away is behind the first one's arm.
  const CliRun run = runCli("--urdf " + kData + "cli_joints.urdf --urdf " + kData +
                            "cli_joints.urdf@10,0,0,0,0,0 --urdf " + kData +
                            "node_scene.urdf@0,0,5,0,0,0 --sensor 0,0,0,0,0,0" + kFour);
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = parse(run.out);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_NEAR(value(rows[1]), 1.9, 1e-8);
  EXPECT_EQ(rows[1].link, "arm");
  EXPECT_NEAR(value(rows[3]), 1.45, 1e-8);
}

TEST(CastScan, PackageUrisResolveThroughRosPackagePath) {
  // node_scene.urdf's plate is package://laser_raycast/test/data/wall_plate.stl. Its floating
  // "mover" (r 0.25 m) stays at the origin without joint values, so the sensor sits at x = 0.5
  // beside it.
  const CliRun run = runCli("--urdf " + kData + "node_scene.urdf --sensor 0.5,0,0,0,0,0" + kFour);
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = parse(run.out);
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_NEAR(value(rows[0]), 2.9, 1e-6);
  EXPECT_EQ(rows[0].link, "wall_link");
  EXPECT_NEAR(value(rows[1]), 2.0, 1e-8);
  EXPECT_EQ(rows[1].link, "box_link");
  EXPECT_NEAR(value(rows[3]), 0.25, 1e-8);
  EXPECT_EQ(rows[3].link, "mover");
}

TEST(CastScan, UrdfAsPackageUri) {
  // The same model through ROS_PACKAGE_PATH (it holds this package when the tests run) gives the
  // same scan as through its path.
  const std::string rest = " --sensor 0,0,0,0,0,0" + kFour;
  const CliRun by_uri =
      runCli("--urdf package://laser_raycast/test/data/cli_joints.urdf@0.5,0,0,0,0,0" + rest);
  ASSERT_EQ(by_uri.status, 0) << by_uri.err;
  EXPECT_NEAR(value(parse(by_uri.out)[1]), 2.4, 1e-8);
  EXPECT_EQ(by_uri.out, runCli("--urdf " + kData + "cli_joints.urdf@0.5,0,0,0,0,0" + rest).out);
}

TEST(CastScan, RepeatReportsTheMedianCastTime) {
  const CliRun run = runCli("--urdf " + kData + "cli_joints.urdf --sensor 0,0,0,0,0,0 --repeat 5");
  ASSERT_EQ(run.status, 0) << run.err;
  EXPECT_TRUE(std::regex_search(run.err, std::regex("(^|\n)cast_ns_per_scan_median=[0-9]+\n")))
      << run.err;
  EXPECT_EQ(parse(run.out).size(), 360u);
}

// With --repeat, what loading cost too: the times, and the meshes' triangles and memory (the wall
// plate's 12 triangles hold at least their vertex indices and the BVH's copies of their corners,
// 12 + 72 bytes each).
TEST(CastScan, RepeatReportsTheLoadAndTheMeshesMemory) {
  const CliRun run =
      runCli("--urdf " + kData + "node_scene.urdf --sensor 0.5,0,0,0,0,0 --repeat 1");
  ASSERT_EQ(run.status, 0) << run.err;
  for (const char* key : {"load_seconds", "bvh_build_seconds", "mesh_bytes_per_triangle"}) {
    EXPECT_TRUE(
        std::regex_search(run.err, std::regex(std::string("(^|\n)") + key + "=[0-9.e+-]+\n")))
        << key << " in: " << run.err;
  }
  EXPECT_NE(run.err.find("\nmesh_triangles=12\n"), std::string::npos) << run.err;
  std::smatch bytes;
  ASSERT_TRUE(std::regex_search(run.err, bytes, std::regex("\nmesh_bytes=([0-9]+)\n")));
#ifndef __SANITIZE_ADDRESS__  // AddressSanitizer's allocator is not glibc's, which counts them
  EXPECT_GE(std::stoul(bytes[1]), 12u * (12 + 72));
#endif
}

// Three rings given out of order (ring 0 is the lowest) of three azimuths against a wall at x = 2
// and a floor at z = -1: the wall at 2 / (cos el cos az), the floor at 1 / sin(-el) where nearer.
TEST(CastScan, RingsAtHandComputedRanges) {
  const CliRun run = runCli("--urdf " + kData +
                            "cli_rings.urdf --sensor 0,0,0,0,0,0 --angle-min -0.4 --angle-max 0.4 "
                            "--samples 3 --elevations 0.3,-0.6,0");
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = parseRings(run.out);
  ASSERT_EQ(rows.size(), 9u);
  const double elevations[3] = {-0.6, 0.0, 0.3};
  for (int i = 0; i < 9; ++i) {
    const int ring = i / 3;
    const double el = elevations[ring], az = -0.4 + 0.4 * (i % 3);
    EXPECT_EQ(rows[i].index, i);
    EXPECT_EQ(rows[i].ring, ring);
    EXPECT_NEAR(rows[i].elevation, el, 1e-9);
    EXPECT_NEAR(rows[i].angle, az, 1e-9);
    const double wall = 2 / (std::cos(el) * std::cos(az));
    const double floor = el < 0 ? 1 / std::sin(-el) : HUGE_VAL;
    EXPECT_NEAR(std::stod(rows[i].range), std::min(wall, floor), 1e-8) << i;
    EXPECT_EQ(rows[i].link, floor < wall ? "floor" : "wall") << i;
  }
  EXPECT_NEAR(std::stod(rows[0].range), 1.77103220, 1e-8);  // 1 / sin 0.6
  EXPECT_NEAR(std::stod(rows[4].range), 2.0, 1e-8);
  EXPECT_NEAR(std::stod(rows[8].range), 2.27292570, 1e-8);  // 2 / (cos 0.3 cos 0.4)
}

// One ring at elevation 0 is the planar scan, with the ring columns.
TEST(CastScan, OneRingAtZeroIsThePlanarScan) {
  const std::string base = "--urdf " + kData + "cli_joints.urdf --sensor 0,0,0,0,0,0" + kFour;
  const CliRun planar = runCli(base);
  const CliRun ring = runCli(base + " --elevations 0");
  ASSERT_EQ(ring.status, 0) << ring.err;
  const auto p = parse(planar.out);
  const auto r = parseRings(ring.out);
  ASSERT_EQ(r.size(), 4u);
  ASSERT_EQ(p.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(r[i].ring, 0);
    EXPECT_EQ(r[i].elevation, 0.0);
    EXPECT_EQ(r[i].range, p[i].range) << i;
    EXPECT_EQ(r[i].link, p[i].link) << i;
  }
}

TEST(CastScan, RepeatWithRings) {
  const CliRun run = runCli("--urdf " + kData +
                            "cli_rings.urdf --sensor 0,0,0,0,0,0 --samples 8 --elevations "
                            "-0.2,0.2 --repeat 3");
  ASSERT_EQ(run.status, 0) << run.err;
  EXPECT_TRUE(std::regex_search(run.err, std::regex("(^|\n)cast_ns_per_scan_median=[0-9]+\n")))
      << run.err;
  EXPECT_EQ(parseRings(run.out).size(), 16u);
}

// Enough beams (8 rings x 2048) for the cast to be split; the CSV must not change.
TEST(CastScan, ThreadsGiveTheSameScan) {
  const std::string base = "--urdf " + kData + "node_scene.urdf --sensor 0.5,0,0,0,0,0.1 " +
                           "--samples 2048 --elevations -0.3,-0.2,-0.1,-0.05,0,0.05,0.1,0.2";
  const CliRun one = runCli(base);
  ASSERT_EQ(one.status, 0) << one.err;
  ASSERT_EQ(parseRings(one.out).size(), 8u * 2048u);
  for (const char* threads : {"2", "3", "0"}) {
    const CliRun run = runCli(base + " --threads " + threads);
    EXPECT_EQ(run.status, 0) << threads << ": " << run.err;
    EXPECT_EQ(run.out, one.out) << "--threads " << threads;
  }
}

// A beam aimed just past a box edge 2 m in front of a wall 3 m away (test/data/surfaces/edge.urdf),
// as seven sub-rays of 0.03 rad, and a second beam backwards that meets nothing.
const std::string kStraddle = "--urdf " + kData +
                              "surfaces/edge.urdf --sensor 0,0,0,0,0,0 --angle-min 0.002 "
                              "--angle-max 3.002 --samples 2 --beam-divergence 0.03 "
                              "--beam-samples 7 --return-mode dual";

TEST(CastScan, DualReturnsAreTwoRowsWithTheReturnColumn) {
  const CliRun run = runCli(kStraddle + " --min-return-separation 0.5");
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = csvRows(run.out, "index,angle,range,link,return");
  ASSERT_EQ(rows.size(), 3u) << run.out;
  EXPECT_EQ(rows[0][0], "0");
  EXPECT_NEAR(std::stod(rows[0][2]), 2.0, 1e-3);  // the box: the strongest
  EXPECT_EQ(rows[0][3], "box");
  EXPECT_EQ(rows[0][4], "1");
  EXPECT_EQ(rows[1][0], "0");
  EXPECT_NEAR(std::stod(rows[1][2]), 3.0, 1e-3);  // the wall: the last
  EXPECT_EQ(rows[1][3], "base");
  EXPECT_EQ(rows[1][4], "2");
  EXPECT_EQ(rows[2][0], "1");
  EXPECT_EQ(rows[2][2], "inf");
}

TEST(CastScan, ReturnsCloserThanTheSeparationAreOneMixedRow) {
  const CliRun run = runCli(kStraddle + " --min-return-separation 1.5");
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = csvRows(run.out, "index,angle,range,link,return");
  ASSERT_EQ(rows.size(), 2u) << run.out;
  EXPECT_GT(std::stod(rows[0][2]), 2.1);
  EXPECT_LT(std::stod(rows[0][2]), 2.9);
}

TEST(CastScan, BadReturnSettingsNameTheirFlag) {
  const CliRun run = runCli(kStraddle + " --min-return-separation -1");
  EXPECT_NE(run.status, 0);
  EXPECT_NE(run.err.find("--min-return-separation"), std::string::npos) << run.err;
}

// Two beams at -0.3 and 0.3 rad across test/data/surfaces/edge.urdf: the first meets the box's face
// x = 2 and the second the wall's face x = 3, both at incidence 0.3 rad (boxes: no colours, so
// the links' reflectivity applies).
const std::string kTwoFaces = "--urdf " + kData +
                              "surfaces/edge.urdf --sensor 0,0,0,0,0,0 --angle-min -0.3 "
                              "--angle-max 0.3 --samples 2";

TEST(CastScan, IntensityIsTheLinksReflectivityTimesTheIncidence) {
  for (const auto& [flags, box, base] :
       {std::make_tuple(std::string(""), 1.0, 1.0),
        std::make_tuple(std::string(" --reflectivity box=0.5 --default-reflectivity 0.2"), 0.5,
                        0.2)}) {
    SCOPED_TRACE(flags);
    const CliRun run = runCli(kTwoFaces + " --intensity" + flags);
    ASSERT_EQ(run.status, 0) << run.err;
    const auto rows = csvRows(run.out, "index,angle,range,link,intensity");
    ASSERT_EQ(rows.size(), 2u);
    EXPECT_EQ(rows[0][3], "box");
    EXPECT_NEAR(std::stod(rows[0][2]), 2 / std::cos(0.3), 1e-7);
    EXPECT_NEAR(std::stod(rows[0][4]), box * std::cos(0.3), 1e-7);
    EXPECT_EQ(rows[1][3], "base");
    EXPECT_NEAR(std::stod(rows[1][4]), base * std::cos(0.3), 1e-7);
  }
}

// --detection-range R@rho: a return of reflectivity r_b at range d and incidence theta is kept iff
// r_b cos(theta) / d^2 >= rho / R^2 (a Lambertian target filling the beam, the datasheet's
// target as the threshold), worked out here for the box's face at several reflectivities.
TEST(CastScan, TheDetectionRangeLosesWeakReturns) {
  const double d = 2 / std::cos(0.3), threshold = 0.1 / (10.0 * 10.0);
  for (const double box : {0.001, 0.004, 0.0045, 0.006, 0.5}) {
    SCOPED_TRACE(box);
    const CliRun run = runCli(kTwoFaces + " --detection-range 10@0.1 --reflectivity box=" +
                              std::to_string(box));
    ASSERT_EQ(run.status, 0) << run.err;
    const auto rows = csvRows(run.out, "index,angle,range,link");
    ASSERT_EQ(rows.size(), 2u);
    const bool detected = box * std::cos(0.3) / (d * d) >= threshold;
    EXPECT_EQ(rows[0][2] == "inf", !detected);
    EXPECT_EQ(rows[0][3], detected ? "box" : "");
    EXPECT_EQ(rows[1][3], "base");  // reflectivity 1 at 3.14 m: far above the threshold
  }
  // Off, every hit is a return.
  const CliRun off = runCli(kTwoFaces + " --intensity --reflectivity box=0.001");
  ASSERT_EQ(off.status, 0) << off.err;
  EXPECT_EQ(csvRows(off.out, "index,angle,range,link,intensity")[0][3], "box");
}

TEST(CastScan, DualReturnsPrintTheirIntensities) {
  const CliRun run = runCli(kStraddle + " --intensity --reflectivity box=0.5");
  ASSERT_EQ(run.status, 0) << run.err;
  const auto rows = csvRows(run.out, "index,angle,range,link,return,intensity");
  ASSERT_EQ(rows.size(), 3u) << run.out;
  // Each return's power share of the pulse: both positive, the missed beam's 0.
  EXPECT_GT(std::stod(rows[0][5]), 0);
  EXPECT_GT(std::stod(rows[1][5]), 0);
  EXPECT_EQ(rows[2][5], "0");
}

TEST(CastScan, BadRadiometrySettingsNameTheirFlag) {
  const std::pair<std::string, std::string> cases[] = {
      {" --intensity --reflectivity nosuch=0.5", "--reflectivity nosuch: no model has a link"},
      {" --intensity --reflectivity box", "--reflectivity: 'box' is not LINK=VALUE"},
      {" --intensity --reflectivity box=-1", "--reflectivity box: must be >= 0"},
      {" --reflectivity box=0.5", "--reflectivity: give --intensity or --detection-range"},
      {" --intensity --default-reflectivity -2", "--default-reflectivity: must be >= 0"},
      {" --detection-range 10", "--detection-range: '10' is not R@REFLECTIVITY"},
      {" --detection-range 0@0.1", "needs R > 0 m and REFLECTIVITY > 0"},
      {" --detection-range 10@x", "--detection-range"},
  };
  for (const auto& [flags, message] : cases) {
    SCOPED_TRACE(flags);
    const CliRun run = runCli(kTwoFaces + flags);
    EXPECT_EQ(run.status, 2);
    EXPECT_NE(run.err.find(message), std::string::npos) << run.err;
  }
}

}  // namespace
}  // namespace laser_raycast_test
