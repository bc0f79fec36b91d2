// rostest node_startup.test: what start-up needs a running node for. A wrong parameter, a missing
// URDF or bad geometry stops laser_raycast_node with exit status 1 and a message naming the
// parameter or file (a nodelet then fails to load); skip_bad_geometry lets it start anyway. Each
// case runs the node executable (or a nodelet manager) with rosrun against the test's master.
// (Every parameter check is in test_node_params.cpp and test_sensor_params.cpp.)
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <ros/package.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "laser_raycast/node/raycast_node.h"
#include "run_command.h"

namespace laser_raycast_test {
namespace {

using NodeRun = CommandResult;

// Runs the node with the given arguments for at most `seconds` (status 124: it was still running).
// Its INFO lines (stdout) are line-buffered so that none is lost when timeout stops it.
NodeRun runNode(const std::string& args, int seconds = 20) {
  return runCommand("ROSCONSOLE_STDOUT_LINE_BUFFERED=1 timeout " + std::to_string(seconds) +
                    " rosrun laser_raycast laser_raycast_node " + args + " 2>&1");
}

std::string data(const std::string& file) {
  return ros::package::getPath("laser_raycast") + "/test/data/" + file;
}

// Expects exit status 1 and every one of `mentions` in the output.
void expectRefused(const std::string& args, const std::vector<std::string>& mentions) {
  const NodeRun run = runNode(args);
  EXPECT_EQ(run.status, 1) << args << "\n" << run.output;
  for (const std::string& m : mentions) {
    EXPECT_NE(run.output.find(m), std::string::npos) << "the message should say '" << m << "':\n"
                                                     << run.output;
  }
}

// Arguments for a node named `ns`/node whose robot_description is the test scene, so that only the
// parameter under test is wrong. Scalars go on the command line; lists and dicts mostly through the
// master (ListsAndDictsFromTheCommandLine gives them on the command line, as YAML strings).
std::string scene(const std::string& ns) {
  ros::NodeHandle nh;
  std::string xml;
  nh.getParam("/scene_description", xml);
  nh.setParam(ns + "/robot_description", xml);
  return "__ns:=" + ns + " __name:=node _fixed_frame:=world";
}

XmlRpc::XmlRpcValue modelFile(const std::string& path) {
  XmlRpc::XmlRpcValue models;
  models.setSize(1);
  models[0]["file"] = path;
  return models;
}

// One wrong parameter, end to end (test/unit/test_node_params.cpp and
// test_sensor_params.cpp check every parameter).
TEST(NodeStartup, AWrongParameterStopsTheNode) {
  expectRefused(scene("/d") + " _rate:=fast", {"~rate", "'fast'", "expected a number"});
}

// The sensors' bad input, end to end: refused with the parameter and the value named, before
// anything starts (no topic advertised, no "started" line).
TEST(NodeStartup, BadSensorInputStopsTheNodeBeforeAnythingStarts) {
  const auto refused = [](const std::string& args, const std::vector<std::string>& mentions) {
    const NodeRun run = runNode(args);
    EXPECT_EQ(run.status, 1) << args << "\n" << run.output;
    EXPECT_EQ(run.output.find("laser_raycast: started"), std::string::npos) << run.output;
    EXPECT_EQ(run.output.find("model '"), std::string::npos) << "the scene was loaded:\n"
                                                             << run.output;
    for (const std::string& m : mentions) {
      EXPECT_NE(run.output.find(m), std::string::npos) << "the message should say '" << m << "':\n"
                                                       << run.output;
    }
  };
  ros::NodeHandle nh;
  refused(scene("/p1") + " _sensor_model:=VLP-15",
          {"~sensor_model", "'VLP-15' is not one of", "VLP-16"});
  refused(
      scene("/p7") + " _point_layout:=xyzirt",
      {"~point_layout", "'xyzirt' is not one of velodyne, ouster, ouster_legacy, livox, hesai"});
  XmlRpc::XmlRpcValue empty;
  empty.setSize(0);
  nh.setParam("/p2/node/elevations", empty);
  refused(scene("/p2"), {"~elevations", "must not be empty"});
  XmlRpc::XmlRpcValue infinite;
  infinite[0] = 0.1;
  infinite[1] = std::numeric_limits<double>::infinity();
  nh.setParam("/p3/node/elevations", infinite);
  refused(scene("/p3"), {"~elevations[1]", "got inf"});
  XmlRpc::XmlRpcValue no_frame;
  no_frame[0]["frame_id"] = "a";
  no_frame[1]["samples"] = 10;
  nh.setParam("/p4/node/sensors", no_frame);
  refused(scene("/p4"), {"~sensors[1]/frame_id", "not set"});
  XmlRpc::XmlRpcValue same_topic;
  same_topic[0]["frame_id"] = "a";
  same_topic[0]["topic"] = "scan";
  same_topic[1]["frame_id"] = "b";
  same_topic[1]["topic"] = "scan";
  nh.setParam("/p5/node/sensors", same_topic);
  refused(scene("/p5"), {"~sensors[1]/topic", "'scan'", "~sensors[0]"});
  // Written differently, one topic once resolved in the node's namespace (/p6).
  same_topic[1]["topic"] = "/p6/scan";
  nh.setParam("/p6/node/sensors", same_topic);
  refused(scene("/p6"), {"~sensors[1]/topic", "'/p6/scan' publishes on /p6/scan", "('scan')"});
}

TEST(NodeStartup, ReflectivityOfAnUnknownLink) {
  XmlRpc::XmlRpcValue reflectivity;
  reflectivity["no_such_link"] = 0.5;
  ros::NodeHandle().setParam("/g/node/reflectivity", reflectivity);
  expectRefused(scene("/g") + " _intensity:=reflectivity", {"no_such_link", "has no geometry"});
}

TEST(NodeStartup, MissingRobotDescription) {
  expectRefused("__ns:=/nothing_here __name:=node", {"robot_description", "not set"});
}

TEST(NodeStartup, MissingUrdfFile) {
  ros::NodeHandle().setParam("/h/node/models", modelFile("/nonexistent/model.urdf"));
  expectRefused("__ns:=/h __name:=node", {"/nonexistent/model.urdf"});
}

// A map entry whose file is missing or not a map, or whose walls have no height: the node stops
// naming the entry, the file and the problem.
TEST(NodeStartup, BadMapEntriesNameTheEntryAndFile) {
  XmlRpc::XmlRpcValue models;
  models.setSize(1);
  models[0]["map"] = data("maps/no_such_map.yaml");
  ros::NodeHandle().setParam("/map_a/node/models", models);
  expectRefused("__ns:=/map_a __name:=node", {"~models[0]", "no_such_map.yaml", "file not found"});
  models[0]["map"] = data("cli_joints.urdf");
  ros::NodeHandle().setParam("/map_b/node/models", models);
  expectRefused("__ns:=/map_b __name:=node", {"~models[0]", "cli_joints.urdf", "not valid YAML"});
  models[0]["map"] = data("maps/box_room.yaml");
  models[0]["height"] = 0.0;
  ros::NodeHandle().setParam("/map_c/node/models", models);
  expectRefused("__ns:=/map_c __name:=node", {"~models[0]/height", "> 0"});
}

TEST(NodeStartup, MissingMeshNamesTheFileAndLink) {
  ros::NodeHandle().setParam("/i/node/models", modelFile(data("bad_mesh.urdf")));
  expectRefused("__ns:=/i __name:=node",
                {"does_not_exist.stl", "broken_link", "skip_bad_geometry"});
}

// A corrupt mesh on which assimp allocates without end: refused at the memory bound, the node
// stops with the named error (before, it allocated until the machine's memory ran out).
TEST(NodeStartup, CorruptMeshIsRefusedAtTheMemoryBound) {
  ros::NodeHandle().setParam("/k/node/models", modelFile(data("corrupt_mesh.urdf")));
  expectRefused("__ns:=/k __name:=node",
                {"regression_wall_p_letter.dae", "corrupt_link", "memory bound of 512 MB"});
}

// The same file in a nodelet manager: the nodelet fails to load (its load command exits non-zero,
// not by timeout), the manager logs the named error and keeps running. The manager gets
// $LASER_RAYCAST_NODELET_PREFIX, as in nodelet_scan.test (the sanitizer build's LD_PRELOAD).
TEST(NodeStartup, CorruptMeshMakesTheNodeletFailToLoad) {
  ros::NodeHandle().setParam("/n/node/models", modelFile(data("corrupt_mesh.urdf")));
  const char* prefix = std::getenv("LASER_RAYCAST_NODELET_PREFIX");
  const NodeRun run = runCommand(
      "export ROSCONSOLE_STDOUT_LINE_BUFFERED=1; " + std::string(prefix ? prefix : "") +
      " rosrun nodelet nodelet manager __ns:=/n __name:=manager 2>&1 & manager=$!; "
      "timeout 40 rosrun nodelet nodelet load laser_raycast/RaycastNodelet /n/manager __ns:=/n "
      "__name:=node 2>&1; status=$?; "
      "if kill -0 $manager; then echo MANAGER_RUNNING; fi; kill -INT $manager; wait $manager; "
      "exit $status");
  EXPECT_NE(run.status, 0) << run.output;
  EXPECT_NE(run.status, 124) << "the load command should fail, not time out:\n" << run.output;
  for (const char* m : {"regression_wall_p_letter.dae", "corrupt_link", "memory bound of 512 MB",
                        "MANAGER_RUNNING"}) {
    EXPECT_NE(run.output.find(m), std::string::npos) << "the output should say '" << m << "':\n"
                                                     << run.output;
  }
}

TEST(NodeStartup, UrdfFileAsPackageUri) {
  // Found through ROS_PACKAGE_PATH: the loader reads the file and then names its missing mesh.
  ros::NodeHandle().setParam("/l/node/models",
                             modelFile("package://laser_raycast/test/data/bad_mesh.urdf"));
  expectRefused("__ns:=/l __name:=node",
                {"package://laser_raycast/test/data/bad_mesh.urdf", "does_not_exist.stl"});
  ros::NodeHandle().setParam("/m/node/models",
                             modelFile("package://laser_raycast_no_such_package/model.urdf"));
  expectRefused("__ns:=/m __name:=node", {"unknown package 'laser_raycast_no_such_package'"});
}

// Also: a misspelt parameter gets a warning and is otherwise ignored.
TEST(NodeStartup, SkipBadGeometryStartsWithAWarning) {
  ros::NodeHandle().setParam("/j/node/models", modelFile(data("bad_mesh.urdf")));
  const NodeRun run = runNode("__ns:=/j __name:=node _skip_bad_geometry:=true _samplez:=5", 4);
  EXPECT_EQ(run.status, 124) << "the node should still be running when timeout stops it:\n"
                             << run.output;
  EXPECT_NE(run.output.find("broken_link"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("WARN"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("~samplez is not a parameter"), std::string::npos) << run.output;
}

// Lists and dicts on the command line, as YAML: roscpp sets them as strings, which the node reads
// as the lists and dicts they hold.
TEST(NodeStartup, ListsAndDictsFromTheCommandLine) {
  const NodeRun run =
      runNode(scene("/w") +
                  " '_elevations:=[-0.1, 0.1]' '_ignore_links:=[sphere_link]'"
                  " '_models:=[{param: robot_description}]' _intensity:=reflectivity"
                  " '_reflectivity:={wall_link: 0.5}'",
              4);
  EXPECT_EQ(run.status, 124) << "the node should still be running when timeout stops it:\n"
                             << run.output;
  for (const std::string m : {"~elevations = [-0.1, 0.1] rad", "~ignore_links = [sphere_link]",
                              "~models[0] = parameter robot_description",
                              "~reflectivity = {wall_link: 0.5}", "publishing /w/points"}) {
    EXPECT_NE(run.output.find(m), std::string::npos) << "the log should say '" << m << "':\n"
                                                     << run.output;
  }
  expectRefused(scene("/w2") + " '_elevations:=[-0.1, 0.1'",
                {"~elevations", "'[-0.1, 0.1'", "YAML", "a list of numbers"});
}

// The ROS time (s) of the first console line of `severity` ("INFO", "WARN") containing `text`;
// NaN if there is none.
double logTime(const std::string& output, const std::string& severity, const std::string& text) {
  const std::regex line("\\[ *" + severity + "\\] \\[([0-9]+\\.[0-9]+)\\]: ([^\n]*)");
  for (auto it = std::sregex_iterator(output.begin(), output.end(), line);
       it != std::sregex_iterator(); ++it) {
    if ((*it)[2].str().find(text) != std::string::npos) return std::stod((*it)[1].str());
  }
  return std::nan("");
}

// A subscriber to the scans of the node in namespace ns: the node casts only while someone listens.
void ignoreScan(const sensor_msgs::LaserScan::ConstPtr&) {}
ros::Subscriber listenTo(const std::string& ns) {
  return ros::NodeHandle().subscribe(ns + "/scan", 1, &ignoreScan);
}

// Transforms that arrive a second after the node starts are waited for without a warning.
TEST(NodeStartup, WaitsQuietlyForTheFirstTransforms) {
  const ros::Subscriber listener = listenTo("/t");
  tf2_ros::StaticTransformBroadcaster broadcaster;
  std::thread late([&broadcaster] {
    ros::WallDuration(1.0).sleep();
    geometry_msgs::TransformStamped laser, mover;
    laser.header.stamp = ros::Time::now();
    laser.header.frame_id = "world";
    laser.child_frame_id = "late_laser";
    laser.transform.rotation.w = 1;
    mover = laser;
    mover.child_frame_id = "mover";
    mover.transform.translation.z = 5;
    broadcaster.sendTransform({laser, mover});
  });
  const NodeRun run = runNode(scene("/t") + " _frame_id:=late_laser _rate:=20", 4);
  late.join();
  EXPECT_EQ(run.status, 124) << run.output;
  EXPECT_EQ(run.output.find("WARN"), std::string::npos) << run.output;
  EXPECT_FALSE(std::isnan(logTime(run.output, "INFO", "first scan at"))) << run.output;
}

// Transforms that never come are warned about once the grace period is over.
TEST(NodeStartup, WarnsWhenTheTransformsNeverCome) {
  const double grace = laser_raycast::RaycastNode::kTfGracePeriod;
  const ros::Subscriber listener = listenTo("/u");
  const NodeRun run =
      runNode(scene("/u") + " _frame_id:=no_such_laser", static_cast<int>(grace) + 4);
  const double ready = logTime(run.output, "INFO", "laser_raycast: ");
  const double warned = logTime(run.output, "WARN", "no transform from 'no_such_laser'");
  ASSERT_FALSE(std::isnan(ready)) << run.output;
  ASSERT_FALSE(std::isnan(warned)) << run.output;
  EXPECT_GE(warned - ready, grace) << run.output;
  EXPECT_NE(run.output.find("scan skipped"), std::string::npos) << run.output;
}

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_startup");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
