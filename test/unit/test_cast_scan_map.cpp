// cast_scan --map: map worlds from the command line, alone, moved, rotated, lower than the sensor
// and beside a URDF; --repeat's counts; bad arguments and bad map files. Ranges are worked out by
// hand in test/data/maps/box_room.yaml: inside, the room spans x -1.25..1.25 and y -0.75..0.75, a
// pillar fills x 0.5..0.75, y 0.25..0.5, and an unknown cell at x -0.75..-0.5, y -0.5..-0.25 has no
// wall.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "cast_scan_cli.h"

namespace laser_raycast_test {
namespace {

const std::string kData = std::string(LASER_RAYCAST_SOURCE_DIR) + "/test/data/";
const std::string kRoom = kData + "maps/box_room.yaml";
// Four beams: -pi/2, 0, pi/2, pi.
const std::string kFour =
    " --angle-min -1.5707963267948966 --angle-max 3.141592653589793 --samples 4";

struct Beam {
  double range;  // NaN for anything but a number
  std::string link;
};

// The beams of a successful run.
std::vector<Beam> beams(const CliRun& run) {
  EXPECT_EQ(run.status, 0) << run.err;
  std::vector<Beam> out;
  for (const auto& f : csvRows(run.out, "index,angle,range,link")) {
    const bool number = f[2] != "inf" && f[2] != "-inf" && f[2] != "nan";
    out.push_back({number ? std::stod(f[2]) : std::nan(""), f[3]});
  }
  return out;
}

void expectBeams(const CliRun& run, const std::vector<Beam>& expected) {
  const std::vector<Beam> got = beams(run);
  ASSERT_EQ(got.size(), expected.size()) << run.out;
  for (std::size_t i = 0; i < got.size(); ++i) {
    SCOPED_TRACE(i);
    if (std::isnan(expected[i].range)) {
      EXPECT_TRUE(std::isnan(got[i].range)) << got[i].range;
    } else {
      // The walls reach 2^-40 (the map's reach + 1 km) beyond their cells: 1e-9 m.
      EXPECT_NEAR(got[i].range, expected[i].range, 1e-8);
    }
    EXPECT_EQ(got[i].link, expected[i].link);
  }
}

const double kNone = std::nan("");

TEST(CastScanMap, WallsAtHandComputedRanges) {
  expectBeams(runCli("--map " + kRoom + " --sensor 0,0,0.5,0,0,0" + kFour),
              {{0.75, "map"}, {1.25, "map"}, {0.75, "map"}, {1.25, "map"}});
  // The pillar ahead of a sensor at y 0.375.
  expectBeams(runCli("--map " + kRoom + " --sensor 0,0.375,0.5,0,0,0" + kFour),
              {{1.125, "map"}, {0.5, "map"}, {0.375, "map"}, {1.25, "map"}});
}

// Through the middle of the unknown cell to the room's inner corner (-1.25, -0.75): no wall there.
TEST(CastScanMap, UnknownCellsAreFree) {
  const std::string yaw = std::to_string(std::atan2(-0.375, -0.625));
  const std::vector<Beam> got =
      beams(runCli("--map " + kRoom + " --sensor 0,0,0.5,0,0," + yaw +
                   " --angle-min 0 --angle-max 0.1 --samples 2"));
  ASSERT_EQ(got.size(), 2u);
  EXPECT_NEAR(got[0].range, 2 * std::hypot(0.625, 0.375), 1e-6);
  EXPECT_EQ(got[0].link, "map");
}

TEST(CastScanMap, PlacedAtItsPoseAndHeight) {
  // Moved 1 m along x: the same scan from x = 1.
  expectBeams(runCli("--map " + kRoom + "@1,0,0,0,0,0 --sensor 1,0,0.5,0,0,0" + kFour),
              {{0.75, "map"}, {1.25, "map"}, {0.75, "map"}, {1.25, "map"}});
  // Walls 0.4 m high under a sensor at 0.5 m: nothing.
  expectBeams(runCli("--map " + kRoom + " --map-height 0.4 --sensor 0,0,0.5,0,0,0" + kFour),
              {{kNone, ""}, {kNone, ""}, {kNone, ""}, {kNone, ""}});
  // 2 m by default: a sensor at 1.9 m sees them, one at 2.1 m does not.
  expectBeams(runCli("--map " + kRoom + " --sensor 0,0,1.9,0,0,0" + kFour),
              {{0.75, "map"}, {1.25, "map"}, {0.75, "map"}, {1.25, "map"}});
  expectBeams(runCli("--map " + kRoom + " --sensor 0,0,2.1,0,0,0" + kFour),
              {{kNone, ""}, {kNone, ""}, {kNone, ""}, {kNone, ""}});
}

// cli_joints.urdf (slider 0.9 m at -y, arm 1.9 m at +x, plate 1.45 m at -x) inside the room turned
// a quarter and lowered 1 m: its inside spans x -0.75..0.75 and y -1.25..1.25.
TEST(CastScanMap, BesideAUrdf) {
  expectBeams(runCli("--urdf " + kData + "cli_joints.urdf --map " + kRoom +
                     "@0,0,-1,0,0,1.5707963267948966 --sensor 0,0,0,0,0,0" + kFour),
              {{0.9, "slider"}, {0.75, "map"}, {1.25, "map"}, {0.75, "map"}});
}

TEST(CastScanMap, RepeatReportsTheCellsAndBoxes) {
  const CliRun run = runCli("--map " + kRoom + " --sensor 0,0,0.5,0,0,0 --repeat 2");
  ASSERT_EQ(run.status, 0) << run.err;
  // 36 border cells and the pillar; the bottom row, the two sides, the top row's rest, the pillar.
  EXPECT_NE(run.err.find("map_occupied_cells=37\n"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("map_boxes=5\n"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("cast_ns_per_scan_median="), std::string::npos) << run.err;
}

TEST(CastScanMap, BadArguments) {
  const std::string sensor = " --sensor 0,0,0.5,0,0,0";
  expectBadArguments("--sensor 0,0,0,0,0,0", "give at least one --urdf or --map");
  expectBadArguments("--map " + kRoom + " --map-height 0" + sensor, "--map-height: must be > 0");
  expectBadArguments("--map " + kRoom + " --map-height -1" + sensor, "got -1");
  expectBadArguments("--map " + kRoom + " --map-height nan" + sensor, "--map-height");
  expectBadArguments("--urdf " + kData + "cli_joints.urdf --map-height 1" + sensor,
                     "--map-height needs --map");
  expectBadArguments("--map @1,0,0,0,0,0" + sensor, "--map: empty path");
}

TEST(CastScanMap, BadMapFilesAreBadSceneInput) {
  const auto expectBadScene = [](const std::string& map, const std::string& mention) {
    const CliRun run = runCli("--map " + map + " --sensor 0,0,0.5,0,0,0");
    EXPECT_EQ(run.status, 3) << run.err;
    EXPECT_NE(run.err.find(mention), std::string::npos) << run.err;
    EXPECT_EQ(run.out, "");
  };
  expectBadScene(kData + "maps/no_such_map.yaml", "no_such_map.yaml': file not found");
  // A URDF is not YAML of map_server's keys.
  expectBadScene(kData + "cli_joints.urdf", "cli_joints.urdf");
  expectBadScene("package://laser_raycast/test/data/maps/missing.yaml", "missing.yaml");
}

}  // namespace
}  // namespace laser_raycast_test
