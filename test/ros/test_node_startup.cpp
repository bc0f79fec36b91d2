// rostest node_startup.test: what start-up needs a running node for. A wrong parameter, a missing
// URDF or bad geometry stops laser_raycast_node with exit status 1 and a message naming the
// parameter or file; skip_bad_geometry lets it start anyway. Each case runs the node executable
// with rosrun against the test's master. (Every parameter check is in test_node_params.cpp.)
#include <gtest/gtest.h>
#include <ros/package.h>
#include <ros/ros.h>

#include <array>
#include <cstdio>
#include <string>
#include <vector>

#include "run_command.h"

namespace laser_raycast_test {
namespace {

using NodeRun = CommandResult;

// Runs the node with the given arguments for at most `seconds` (status 124: it was still running).
NodeRun runNode(const std::string& args, int seconds = 20) {
  return runCommand("timeout " + std::to_string(seconds) +
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
// parameter under test is wrong. Scalars go on the command line; lists and dicts through the master
// (roscpp reads _name:=value as a scalar).
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

// One wrong parameter, end to end (test/unit/test_node_params.cpp checks every parameter).
TEST(NodeStartup, AWrongParameterStopsTheNode) {
  expectRefused(scene("/d") + " _rate:=fast", {"~rate", "'fast'", "expected a number"});
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

TEST(NodeStartup, MissingMeshNamesTheFileAndLink) {
  ros::NodeHandle().setParam("/i/node/models", modelFile(data("bad_mesh.urdf")));
  expectRefused("__ns:=/i __name:=node",
                {"does_not_exist.stl", "broken_link", "skip_bad_geometry"});
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

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_startup");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
