// Run-time scene editing end to end (rostest node_edit.test): laser_raycast_node on a wall 4.9 m in
// front of the sensor (test/data/edit_room.urdf); this test spawns a 0.5 m cube through
// ~spawn_model, moves it with ~set_model_pose and deletes it with ~delete_model, and checks the
// first scan stamped after each call against ranges worked out from the geometry, and the links
// the labels name; a two-link model placed by its joint's origin; a cube whose link is looked up
// in TF, seen once its transform is published; bad requests; then 100
// spawn/delete cycles while the node scans at 20 Hz, counting the scans against quiet stretches
// between them and reading the node's resident memory from /proc.
#include <gtest/gtest.h>
#include <laser_raycast/ScanLabels.h>
#include <laser_raycast/SetModelPose.h>
#include <laser_raycast/SpawnModel.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "edit_services.h"

namespace laser_raycast_test {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTolerance = 1e-5;  // m
constexpr double kWall = 4.9;        // m, the wall's near face (edit_room.urdf)
constexpr double kHalf = 0.25;       // m, half the cube's side
// The beams: samples 5 from -0.4 to 0.4 rad.
const std::vector<double> kAngles = {-0.4, -0.2, 0.0, 0.2, 0.4};

const char* const kCube = R"(<robot name="cube"><link name="cube"><visual>
  <geometry><box size="0.5 0.5 0.5"/></geometry></visual></link></robot>)";

// The range of beam a (rad) from the origin to an axis-aligned cube of side 2 kHalf centred at
// (cx, cy), if it hits the face nearest the sensor (x = cx - kHalf), else the wall's.
double expectedRange(double a, bool cube, double cx, double cy) {
  if (cube) {
    const double x = cx - kHalf, y = x * std::tan(a);
    if (std::abs(y - cy) <= kHalf) return x / std::cos(a);
  }
  return kWall / std::cos(a);
}

Scans* scans = nullptr;

void expectRanges(const sensor_msgs::LaserScan& scan, bool cube, double cx, double cy,
                  const std::string& what) {
  ASSERT_EQ(scan.ranges.size(), kAngles.size()) << what;
  for (std::size_t i = 0; i < kAngles.size(); ++i) {
    EXPECT_NEAR(scan.ranges[i], expectedRange(kAngles[i], cube, cx, cy), kTolerance)
        << what << ", beam " << i << " at " << kAngles[i] << " rad";
  }
}

// Whether every range of scan is that of the scene with (cube) or without the cube at (cx, cy).
bool matches(const sensor_msgs::LaserScan& scan, bool cube, double cx, double cy) {
  if (scan.ranges.size() != kAngles.size()) return false;
  for (std::size_t i = 0; i < kAngles.size(); ++i) {
    if (!(std::abs(scan.ranges[i] - expectedRange(kAngles[i], cube, cx, cy)) <= kTolerance)) {
      return false;
    }
  }
  return true;
}

// The link beam i of the scan stamped at stamp hit ("" for none).
std::string linkHit(const ros::Time& stamp, std::size_t beam) {
  const laser_raycast::ScanLabels labels = scans->labelsOf(stamp);
  if (beam >= labels.labels.size() || labels.labels[beam] < 0) return "";
  return labels.link_names.at(labels.labels[beam]);
}

TEST(NodeEdit, SpawnMoveDeleteRestoresRangesBitForBit) {
  ASSERT_TRUE(ros::service::waitForService(service("spawn_model"), ros::Duration(30)));
  const sensor_msgs::LaserScan before = scans->after(ros::Time::now());
  expectRanges(before, false, 0, 0, "before spawning");

  // In front: the middle beam meets the near face at 2 - 0.25 m; the beams at +-0.2 rad pass it.
  EXPECT_EQ(linkHit(before.header.stamp, 2), "wall");
  auto spawned = spawn("cube1", kCube, "", 2.0, 0.0);
  ASSERT_TRUE(spawned.success) << spawned.message;
  const sensor_msgs::LaserScan with_cube = scans->after(ros::Time::now());
  expectRanges(with_cube, true, 2.0, 0.0, "cube at (2, 0)");
  // The labels follow: the middle beam hit the cube's link, the others the wall.
  EXPECT_EQ(linkHit(with_cube.header.stamp, 2), "cube");
  EXPECT_EQ(linkHit(with_cube.header.stamp, 0), "wall");
  const auto names = listed();
  EXPECT_NE(std::find(names.begin(), names.end(), "room"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "cube1"), names.end());

  // Moved to the left: now the beam at +0.2 rad meets it, the middle one sees the wall.
  laser_raycast::SetModelPose move;
  move.request.name = "cube1";
  move.request.pose = poseAt(1.5, 0.5);
  ASSERT_TRUE(ros::service::call(service("set_model_pose"), move));
  ASSERT_TRUE(move.response.success) << move.response.message;
  expectRanges(scans->after(ros::Time::now()), true, 1.5, 0.5, "cube moved to (1.5, 0.5)");

  auto deleted = remove("cube1");
  ASSERT_TRUE(deleted.success) << deleted.message;
  const sensor_msgs::LaserScan after = scans->after(ros::Time::now());
  ASSERT_EQ(after.ranges.size(), before.ranges.size());
  for (std::size_t i = 0; i < before.ranges.size(); ++i) {
    // Bit for bit: the scene is again the one the ranges before were cast on.
    EXPECT_EQ(after.ranges[i], before.ranges[i]) << "beam " << i;
  }
  EXPECT_EQ(linkHit(after.header.stamp, 2), "wall");
  const auto left = listed();
  EXPECT_EQ(std::find(left.begin(), left.end(), "cube1"), left.end());
}

// Two links: the cube on arm_tip, which a revolute joint holds 0.5 m ahead of and 0.25 m left of
// the root link arm_base, at the joint's zero.
const char* const kArm = R"(<robot name="arm"><link name="arm_base"/><link name="arm_tip">
  <visual><geometry><box size="0.5 0.5 0.5"/></geometry></visual></link>
  <joint name="arm_joint" type="revolute"><parent link="arm_base"/><child link="arm_tip"/>
  <origin xyz="0.5 0.25 0"/><axis xyz="0 0 1"/>
  <limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>)";

// Without TF, the root link goes where the pose puts it and the others where the joints' origins
// put them at zero joint values: the root at (2.25, -0.5) turned 90 degrees, so arm_tip is at
// (2.25 - 0.25, -0.5 + 0.5) = (2, 0), turned 90 degrees (the same cube).
TEST(NodeEdit, SpawnPlacesChildLinksByTheirJointsAtZero) {
  ASSERT_TRUE(ros::service::waitForService(service("spawn_model"), ros::Duration(30)));
  laser_raycast::SpawnModel srv;
  srv.request.name = "arm";
  srv.request.urdf = kArm;
  srv.request.pose = poseAt(2.25, -0.5);
  srv.request.pose.orientation.z = std::sin(M_PI / 4);
  srv.request.pose.orientation.w = std::cos(M_PI / 4);
  ASSERT_TRUE(ros::service::call(service("spawn_model"), srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  const sensor_msgs::LaserScan scan = scans->after(ros::Time::now());
  expectRanges(scan, true, 2.0, 0.0, "arm_tip at (2, 0)");
  EXPECT_EQ(linkHit(scan.header.stamp, 2), "arm_tip");
  EXPECT_TRUE(remove("arm").success);
  expectRanges(scans->after(ros::Time::now()), false, 0, 0, "arm deleted");
}

TEST(NodeEdit, SpawnFromFileAndDeleteAModelOfModels) {
  ASSERT_TRUE(ros::service::waitForService(service("spawn_model"), ros::Duration(30)));
  auto spawned = spawn("", "", "package://laser_raycast/urdf/obstacle_box.urdf", 3.0, -0.5);
  ASSERT_TRUE(spawned.success) << spawned.message;
  // Named after the URDF's robot.
  const auto names = listed();
  EXPECT_NE(std::find(names.begin(), names.end(), "obstacle_box"), names.end());
  expectRanges(scans->after(ros::Time::now()), true, 3.0, -0.5, "file's cube at (3, -0.5)");

  // The wall, a model of ~models, goes: only the cube is left.
  auto deleted = remove("room");
  ASSERT_TRUE(deleted.success) << deleted.message;
  const sensor_msgs::LaserScan scan = scans->after(ros::Time::now());
  ASSERT_EQ(scan.ranges.size(), kAngles.size());
  for (std::size_t i = 0; i < kAngles.size(); ++i) {
    const double cube = expectedRange(kAngles[i], true, 3.0, -0.5);
    if (cube < kWall / std::cos(kAngles[i])) {
      EXPECT_NEAR(scan.ranges[i], cube, kTolerance) << "beam " << i;
    } else {
      EXPECT_EQ(scan.ranges[i], kInf) << "beam " << i;
    }
  }
  // Put back as it was for the other tests: spawned from the same file, placed at the origin.
  ASSERT_TRUE(remove("obstacle_box").success);
  auto wall = spawn("room", "", "package://laser_raycast/test/data/edit_room.urdf", 0, 0);
  ASSERT_TRUE(wall.success) << wall.message;
  expectRanges(scans->after(ros::Time::now()), false, 0, 0, "the wall spawned back");
}

// A cube spawned with use_tf: its link, tf_box/cube, is looked up in TF. Without a transform for
// it the cube is left out of the scans; once a static transform places it, the scans see it at
// the range worked out from that pose; deleted, the ranges are again those from before, bit for
// bit.
TEST(NodeEdit, SpawnWithTfIsSeenOnceItsFrameIsPublished) {
  ASSERT_TRUE(ros::service::waitForService(service("spawn_model"), ros::Duration(30)));
  const sensor_msgs::LaserScan before = scans->after(ros::Time::now());
  expectRanges(before, false, 0, 0, "before spawning");

  laser_raycast::SpawnModel srv;
  srv.request.name = "tf_box";
  srv.request.urdf = kCube;
  srv.request.tf_prefix = "tf_box/";
  srv.request.use_tf = true;
  srv.request.pose = poseAt(1.0, 0.0);  // not used: the poses come from TF
  ASSERT_TRUE(ros::service::call(service("spawn_model"), srv));
  ASSERT_TRUE(srv.response.success) << srv.response.message;
  expectRanges(scans->after(ros::Time::now()), false, 0, 0, "no transform for tf_box/cube yet");

  // The cube's link 2.5 m ahead and 0.1 m to the left: the middle beam meets its near face at
  // 2.25 m, the others pass it.
  static tf2_ros::StaticTransformBroadcaster broadcaster;
  geometry_msgs::TransformStamped t;
  t.header.stamp = ros::Time::now();
  t.header.frame_id = "world";
  t.child_frame_id = "tf_box/cube";
  t.transform.translation.x = 2.5;
  t.transform.translation.y = 0.1;
  t.transform.rotation.w = 1;
  broadcaster.sendTransform(t);
  // The transform reaches the node some time after it is sent: the first scan that sees the cube
  // at all, then the one after it, range by range.
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(20.0);
  sensor_msgs::LaserScan seen = scans->after(ros::Time::now());
  while (ros::ok() && ros::WallTime::now() < give_up && seen.ranges.size() == kAngles.size() &&
         !(seen.ranges[2] < 3.0)) {
    seen = scans->after(seen.header.stamp);
  }
  ASSERT_EQ(seen.ranges.size(), kAngles.size());
  ASSERT_LT(seen.ranges[2], 3.0) << "the cube never showed in the scans";
  expectRanges(seen, true, 2.5, 0.1, "tf_box at (2.5, 0.1) by TF");
  expectRanges(scans->after(seen.header.stamp), true, 2.5, 0.1, "tf_box, the scan after");

  auto deleted = remove("tf_box");
  ASSERT_TRUE(deleted.success) << deleted.message;
  const sensor_msgs::LaserScan after = scans->after(ros::Time::now());
  ASSERT_EQ(after.ranges.size(), before.ranges.size());
  for (std::size_t i = 0; i < before.ranges.size(); ++i) {
    EXPECT_EQ(after.ranges[i], before.ranges[i]) << "beam " << i;
  }
}

TEST(NodeEdit, BadRequestsAreRefusedWithAReason) {
  ASSERT_TRUE(ros::service::waitForService(service("spawn_model"), ros::Duration(30)));
  auto both = spawn("x", kCube, "/tmp/x.urdf", 0, 0);
  EXPECT_FALSE(both.success);
  EXPECT_NE(both.message.find("exactly one"), std::string::npos) << both.message;
  auto neither = spawn("x", "", "", 0, 0);
  EXPECT_FALSE(neither.success);
  EXPECT_NE(neither.message.find("exactly one"), std::string::npos) << neither.message;
  // Malformed XML: the message names the request's URDF.
  auto malformed = spawn("bad", "<robot name='bad'><link name='a'>", "", 0, 0);
  EXPECT_FALSE(malformed.success);
  EXPECT_NE(malformed.message.find("spawn_model 'bad'"), std::string::npos) << malformed.message;
  auto missing = spawn("gone", "", "/nonexistent/model.urdf", 0, 0);
  EXPECT_FALSE(missing.success);
  EXPECT_NE(missing.message.find("/nonexistent/model.urdf"), std::string::npos) << missing.message;
  auto bad_mesh = spawn("mesh", R"(<robot name="m"><link name="m"><visual><geometry>
      <mesh filename="/nonexistent/part.stl"/></geometry></visual></link></robot>)",
                        "", 0, 0);
  EXPECT_FALSE(bad_mesh.success);
  EXPECT_NE(bad_mesh.message.find("/nonexistent/part.stl"), std::string::npos) << bad_mesh.message;
  // A mesh over the import bounds (a corrupt Collada file on which assimp allocates without end):
  // refused at the memory bound, naming the file and the bound.
  auto hostile = spawn("hostile", "", "package://laser_raycast/test/data/corrupt_mesh.urdf", 0, 0);
  EXPECT_FALSE(hostile.success);
  EXPECT_NE(hostile.message.find("regression_wall_p_letter.dae"), std::string::npos)
      << hostile.message;
  EXPECT_NE(hostile.message.find("memory bound"), std::string::npos) << hostile.message;
  // A pose that is not finite.
  auto nan_pose = spawn("nan", kCube, "", std::nan(""), 0);
  EXPECT_FALSE(nan_pose.success);
  EXPECT_NE(nan_pose.message.find("not finite"), std::string::npos) << nan_pose.message;
  ASSERT_TRUE(spawn("dup", kCube, "", 8, 8).success);
  auto duplicate = spawn("dup", kCube, "", 8, 8);
  EXPECT_FALSE(duplicate.success);
  EXPECT_NE(duplicate.message.find("already"), std::string::npos) << duplicate.message;
  EXPECT_TRUE(remove("dup").success);
  auto unknown = remove("nobody");
  EXPECT_FALSE(unknown.success);
  EXPECT_NE(unknown.message.find("nobody"), std::string::npos);
  laser_raycast::SetModelPose move_unknown;
  move_unknown.request.name = "nobody";
  move_unknown.request.pose = poseAt(1, 1);
  ASSERT_TRUE(ros::service::call(service("set_model_pose"), move_unknown));
  EXPECT_FALSE(move_unknown.response.success);
  EXPECT_NE(move_unknown.response.message.find("nobody"), std::string::npos);
  // None of them is in the scene.
  for (const std::string& name : listed()) {
    for (const char* refused : {"x", "bad", "gone", "mesh", "hostile", "nan"}) {
      EXPECT_NE(name, refused);
    }
  }

  // A model whose link poses come from TF (none are published for it: it is left out of the
  // scans) cannot be moved by the service.
  laser_raycast::SpawnModel tf_cube;
  tf_cube.request.name = "tf_cube";
  tf_cube.request.urdf = kCube;
  tf_cube.request.tf_prefix = "tf_cube/";
  tf_cube.request.use_tf = true;
  ASSERT_TRUE(ros::service::call(service("spawn_model"), tf_cube));
  ASSERT_TRUE(tf_cube.response.success) << tf_cube.response.message;
  laser_raycast::SetModelPose move;
  move.request.name = "tf_cube";
  move.request.pose = poseAt(1, 1);
  ASSERT_TRUE(ros::service::call(service("set_model_pose"), move));
  EXPECT_FALSE(move.response.success);
  EXPECT_NE(move.response.message.find("TF"), std::string::npos) << move.response.message;
  EXPECT_TRUE(remove("tf_cube").success);
  // The node still scans the wall.
  expectRanges(scans->after(ros::Time::now()), false, 0, 0, "after the refused requests");
}

// The model the cycles spawn: the cube in front of the sensor, and 255 small cubes beyond the wall
// on the same link, so that each composed scene holds 256 bodies more than the room's (some 100 kB
// with the caster's state for it): a scene kept by mistake after each cycle would grow the node by
// some 10 MB over the 100 cycles, five times the memory check's bound.
std::string cycleModel() {
  std::ostringstream urdf;
  urdf << "<robot name='cycle'><link name='cycle'><visual><geometry><box size='0.5 0.5 0.5'/>"
       << "</geometry></visual>";
  for (int i = 0; i < 255; ++i) {
    urdf << "<visual><origin xyz='" << 6 + 0.1 * (i % 16) << " " << 0.1 * (i / 16)
         << " 0'/><geometry><box size='0.05 0.05 0.05'/></geometry></visual>";
  }
  urdf << "</link></robot>";
  return urdf.str();
}

// 100 spawn/delete cycles, one every 50 ms (or as fast as the calls go), in 5 rounds of 20, each
// followed by a quiet stretch as long as its cycles took. The rate: scans stamped during the
// cycles against those stamped during the quiet stretches, counted from the stamps (the node's
// timer puts them on a 20 Hz grid; a scan its cast thread fell too far behind for is dropped, and
// missing), so that the check holds on a loaded machine whose scans fall short of 20 Hz with or
// without editing; interleaved, so that a load that comes and goes meets both alike. Memory: the
// node's resident set after the cycles against after a warm-up.
TEST(NodeEdit, HundredCyclesKeepRateAndMemory) {
  ASSERT_TRUE(ros::service::waitForService(service("spawn_model"), ros::Duration(30)));
  const int pid = nodePid();
  ASSERT_GT(pid, 0) << "the node's process was not found in /proc";
  const std::string model = cycleModel();
  const auto cycle = [&model](int i) {
    const std::string name = "cycle" + std::to_string(i);
    auto spawned = spawn(name, model, "", 2.0, 0.0);
    EXPECT_TRUE(spawned.success) << spawned.message;
    EXPECT_TRUE(remove(name).success);
  };
  const auto spinUntil = [](const ros::Time& t) {
    while (ros::ok() && ros::Time::now() < t) {
      ros::spinOnce();
      ros::WallDuration(0.002).sleep();
    }
  };
  // Warm-up: the allocator's pools and the services' connections.
  for (int i = 0; i < 20; ++i) cycle(i);
  spinUntil(ros::Time::now() + ros::Duration(0.5));
  const long rss_before = residentKb(pid);
  std::vector<std::pair<ros::Time, ros::Time>> busy, quiet;
  std::ostringstream rss_rounds;
  for (int round = 0; round < 5; ++round) {
    const ros::Time start = ros::Time::now();
    for (int i = 0; i < 20; ++i) {
      cycle(100 + 20 * round + i);
      spinUntil(start + ros::Duration(0.05 * (i + 1)));
    }
    const ros::Time end = ros::Time::now();
    busy.emplace_back(start, end);
    quiet.emplace_back(end, end + (end - start));
    spinUntil(end + (end - start));
    rss_rounds << residentKb(pid) << " ";
  }
  // Every scan stamped up to the last quiet stretch's end has arrived (or was dropped).
  scans->after(quiet.back().second);
  const auto count = [](const std::vector<std::pair<ros::Time, ros::Time>>& spans, double* s) {
    std::size_t n = 0;
    *s = 0;
    for (const auto& span : spans) {
      // Half-open: a scan stamped at a boundary counts once.
      n += scans->stampedBetween(span.first, span.second - ros::Duration(1e-9)).size();
      *s += (span.second - span.first).toSec();
    }
    return n;
  };
  double busy_seconds = 0, quiet_seconds = 0;
  const std::size_t busy_scans = count(busy, &busy_seconds);
  const std::size_t quiet_scans = count(quiet, &quiet_seconds);
  const long rss_after = residentKb(pid);
  const double busy_rate = busy_scans / busy_seconds, quiet_rate = quiet_scans / quiet_seconds;
  // In the test's XML report (rosunit-node_edit.xml).
  testing::Test::RecordProperty("cycle_seconds", std::to_string(busy_seconds));
  testing::Test::RecordProperty("rate_during_cycles", std::to_string(busy_rate));
  testing::Test::RecordProperty("rate_between_cycles", std::to_string(quiet_rate));
  testing::Test::RecordProperty("rss_before_kb", static_cast<int>(rss_before));
  testing::Test::RecordProperty("rss_rounds_kb", rss_rounds.str());
  testing::Test::RecordProperty("rss_after_kb", static_cast<int>(rss_after));
  std::printf(
      "cycles: %zu scans in %.2f s (%.1f Hz), between them %zu in %.2f s (%.1f Hz); RSS %ld "
      "kB, after each round %s\n",
      busy_scans, busy_seconds, busy_rate, quiet_scans, quiet_seconds, quiet_rate, rss_before,
      rss_rounds.str().c_str());
  ASSERT_GT(quiet_scans, 0u) << "no scan between the cycles";
  // The rate: at least 80 % of the rate between the cycles (an idle machine gives 20 Hz in both).
  EXPECT_GE(busy_rate, 0.8 * quiet_rate)
      << busy_scans << " scans in " << busy_seconds << " s of cycles, " << quiet_scans << " in "
      << quiet_seconds << " s between them";
  // Each scan during the cycles is of one scene, with the cube or without, never a mix.
  for (const auto& span : busy) {
    for (const auto& scan : scans->stampedBetween(span.first, span.second)) {
      EXPECT_TRUE(matches(scan, true, 2.0, 0.0) || matches(scan, false, 0, 0))
          << "scan stamped " << scan.header.stamp << " is of neither scene";
    }
  }
  // Memory: no growth beyond 2 MB (see cycleModel).
#ifndef __SANITIZE_THREAD__  // ThreadSanitizer's own memory grows with the threads' history
  EXPECT_LT(rss_after - rss_before, 2048)
      << "RSS " << rss_before << " -> " << rss_after << " kB (rounds: " << rss_rounds.str() << ")";
#endif
  expectRanges(scans->after(ros::Time::now()), false, 0, 0, "after the cycles");
}

// A binary STL of a flat grid of 2 n^2 triangles at path.
void writeGridStl(const std::string& path, int n) {
  std::ofstream out(path, std::ios::binary);
  const char header[80] = "laser_raycast test grid";
  out.write(header, sizeof(header));
  const std::uint32_t count = 2u * n * n;
  out.write(reinterpret_cast<const char*>(&count), 4);
  const auto corner = [n](int i, int j) {
    return std::array<float, 3>{0.0f, float(i) / n, float(j) / n};
  };
  const auto triangle = [&](std::array<float, 3> a, std::array<float, 3> b,
                            std::array<float, 3> c) {
    const float normal[3] = {1, 0, 0};
    out.write(reinterpret_cast<const char*>(normal), 12);
    for (const auto& v : {a, b, c}) out.write(reinterpret_cast<const char*>(v.data()), 12);
    const std::uint16_t attributes = 0;
    out.write(reinterpret_cast<const char*>(&attributes), 2);
  };
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      triangle(corner(i, j), corner(i + 1, j), corner(i, j + 1));
      triangle(corner(i + 1, j), corner(i + 1, j + 1), corner(i, j + 1));
    }
  }
}

// A slow spawn (a mesh of 800,000 triangles, read and its BVH built during the call) holds up
// neither the scans nor the other services: scans stamped while the call was under way arrive at
// the rate.
TEST(NodeEdit, ASlowSpawnDoesNotStallTheScans) {
  ASSERT_TRUE(ros::service::waitForService(service("spawn_model"), ros::Duration(30)));
  const std::string stl =
      "/tmp/laser_raycast_test_edit_grid_" + std::to_string(::getpid()) + ".stl";
  writeGridStl(stl, 632);
  const std::string urdf = "<robot name='big'><link name='big'><visual><geometry><mesh filename='" +
                           stl + "'/></geometry></visual></link></robot>";
  const ros::Time start = ros::Time::now();
  auto spawned = spawn("big", urdf, "", 50.0, 0.0);  // far beyond range_max
  const ros::Time end = ros::Time::now();
  std::remove(stl.c_str());
  ASSERT_TRUE(spawned.success) << spawned.message;
  const double seconds = (end - start).toSec();
  // The scans stamped during the call, received once it returned.
  const sensor_msgs::LaserScan last = scans->after(end);
  const std::size_t during = scans->stampedBetween(start, end).size();
  testing::Test::RecordProperty("slow_spawn_seconds", std::to_string(seconds));
  testing::Test::RecordProperty("scans_during_spawn", static_cast<int>(during));
  if (seconds >= 0.5) {  // long enough to tell (it is about 1 s)
    EXPECT_GE(during, static_cast<std::size_t>(std::floor(seconds * 20 * 0.8)))
        << during << " scans stamped during the " << seconds << " s call";
  }
  expectRanges(last, false, 0, 0, "the big mesh beyond range");
  EXPECT_TRUE(remove("big").success);
}

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_edit");
  ros::NodeHandle nh;
  laser_raycast_test::Scans s;
  laser_raycast_test::scans = &s;
  return RUN_ALL_TESTS();
}
