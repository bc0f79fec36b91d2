// The offline CLI cast_scan's command line, run as a user would: its help (every flag, and the
// choices and defaults of the core's and the loader's tables), the forms of its arguments, and its
// exit statuses for bad arguments (2) and bad scene input (3). Its scans: test_cast_scan.cpp.
#include <gtest/gtest.h>

#include <cstddef>
#include <sstream>
#include <string>

#include "cast_scan_cli.h"
#include "laser_raycast/core/scan_spec.h"
#include "laser_raycast/loader/scene_loader.h"

namespace laser_raycast_test {
namespace {

const std::string kData = std::string(LASER_RAYCAST_SOURCE_DIR) + "/test/data/";
// Four beams: -pi/2, 0, pi/2, pi.
const std::string kFour =
    " --angle-min -1.5707963267948966 --angle-max 3.141592653589793 --samples 4";

TEST(CastScan, HelpExitsZero) {
  const CliRun run = runCli("--help");
  EXPECT_EQ(run.status, 0);
  EXPECT_NE(run.out.find("usage: cast_scan"), std::string::npos);
}

TEST(CastScan, HelpListsEveryFlag) {
  const CliRun run = runCli("-h");
  ASSERT_EQ(run.status, 0);
  for (const char* flag :
       {"--urdf", "--sensor", "--angle-min", "--angle-max", "--samples", "--angle-increment",
        "--range-min", "--range-max", "--geometry", "--method", "--elevations", "--joint",
        "--repeat", "--threads", "Exit status"}) {
    EXPECT_NE(run.out.find(flag), std::string::npos) << flag << "\n" << run.out;
  }
}

// "a|b|c": a name table's entries, as the synopsis lists a flag's choices.
template <typename E, std::size_t N>
std::string choices(const laser_raycast::core::EnumNames<E, N>& names) {
  std::string out;
  for (const auto& entry : names.entries())
    out += (out.empty() ? "" : "|") + std::string(entry.second);
  return out;
}

// The synopsis lists the choices of the core's and the loader's name tables, and the notes give
// their defaults, so that neither can go stale when a table or a default changes.
TEST(CastScan, HelpTakesChoicesAndDefaultsFromTheLibraries) {
  const CliRun run = runCli("--help");
  ASSERT_EQ(run.status, 0);
  EXPECT_NE(run.out.find("[--method " + choices(laser_raycast::core::kTriangleMethodNames) + "]"),
            std::string::npos)
      << run.out;
  EXPECT_NE(run.out.find("[--geometry " + choices(laser_raycast::kGeometrySourceNames) + "]"),
            std::string::npos)
      << run.out;
  const laser_raycast::core::ScanSpec defaults;
  std::ostringstream ranges;
  ranges << "ranges " << defaults.output.range_min << ".." << defaults.output.range_max << " m";
  EXPECT_NE(run.out.find(ranges.str()), std::string::npos) << run.out;
  EXPECT_NE(run.out.find(std::string("method ") + toString(defaults.method)), std::string::npos)
      << run.out;
  EXPECT_NE(
      run.out.find(std::string("geometry ") + toString(laser_raycast::LoaderOptions().geometry)),
      std::string::npos)
      << run.out;
}

TEST(CastScan, ValuesAfterAnEqualsSign) {
  const CliRun spaced = runCli("--urdf " + kData + "cli_joints.urdf --sensor 0,0,0,0,0,0" + kFour);
  const CliRun joined = runCli("--urdf=" + kData +
                               "cli_joints.urdf --sensor=0,0,0,0,0,0 "
                               "--angle-min=-1.5707963267948966 --angle-max=3.141592653589793 "
                               "--samples=4");
  ASSERT_EQ(joined.status, 0) << joined.err;
  EXPECT_EQ(joined.out, spaced.out);
}

TEST(CastScan, BadArgumentsExitTwo) {
  const std::string model = "--urdf " + kData + "cli_joints.urdf ";
  expectBadArguments("", "--urdf");
  expectBadArguments(model, "--sensor");
  expectBadArguments(model + "--sensor 0,0,0", "--sensor");
  expectBadArguments(model + "--sensor 0,0,0,0,0,nan", "--sensor");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --bogus 1", "--bogus");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --samples 1", "--samples: samples");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --samples ten", "--samples");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --samples 10 --angle-increment 0.1", "not both");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --angle-increment -0.1",
                     "--angle-increment: angle_increment");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --angle-min 1 --angle-max 0",
                     "--angle-max: angle_max");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --range-min 2 --range-max 1",
                     "--range-max: range_max (1 m)");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --range-min -1", "--range-min: range_min");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --geometry hull", "--geometry");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --method fast", "--method");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --joint elbow=1", "elbow");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --joint plate_fix=1", "plate_fix");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --joint swing", "NAME=VALUE");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --threads -1", "--threads: '-1'");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --threads 5000", "--threads: '5000'");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --threads 2x", "--threads: '2x'");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --repeat", "--repeat");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --elevations ''", "--elevations");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --elevations 0.1,nan", "--elevations: 'nan'");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --elevations 0.1,,0.2", "--elevations: ''");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --elevations 0.1,", "--elevations: ''");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --elevations 0.1,0.1", "distinct");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --elevations 0,2",
                     "--elevations: elevations[1]");
  expectBadArguments(model + "--sensor 0,0,0,0,0,0 --elevations 0 --elevations 1", "--elevations");
}

TEST(CastScan, FlagsAreNotAbbreviatedAndStrayWordsAreErrors) {
  const std::string model = "--urdf " + kData + "cli_joints.urdf --sensor 0,0,0,0,0,0 ";
  expectBadArguments(model + "--sam 4", "'--sam'");
  expectBadArguments(model + "stray", "'stray'");
  expectBadArguments(model + "--samples 4 --samples 5", "--samples");
}

// Exit status 3 for bad scene input, naming the file.
void expectBadScene(const std::string& urdf, const std::string& mention) {
  const CliRun run = runCli("--urdf " + urdf + " --sensor 0,0,0,0,0,0");
  EXPECT_EQ(run.status, 3) << urdf << "\n" << run.err;
  EXPECT_NE(run.err.find(mention), std::string::npos) << run.err;
  EXPECT_EQ(run.out, "");
}

TEST(CastScan, BadSceneExitsThree) {
  expectBadScene("/nonexistent/robot.urdf", "/nonexistent/robot.urdf");
  expectBadScene(kData + "malformed.urdf", "malformed.urdf");
  expectBadScene(kData + "bad_mesh.urdf", "does_not_exist.stl");
  expectBadScene("package://laser_raycast_no_such_package/robot.urdf",
                 "unknown package 'laser_raycast_no_such_package'");
}

// A corrupt mesh on which assimp allocates without end is refused at the memory bound (before, the
// tool allocated until the machine's memory ran out).
TEST(CastScan, CorruptMeshExitsThreeAtTheMemoryBound) {
  expectBadScene(kData + "corrupt_mesh.urdf", "regression_wall_p_letter.dae");
  expectBadScene(kData + "corrupt_mesh.urdf", "memory bound of 512 MB");
}

}  // namespace
}  // namespace laser_raycast_test
