// rostest node_startup.test: a wrong parameter or bad geometry stops laser_raycast_node at start-up
// with exit status 1 and a message naming the parameter or file; skip_bad_geometry lets it start
// anyway. Each case runs the node executable with rosrun against the test's master.
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

TEST(NodeStartup, NegativeRangeMax) {
  expectRefused(scene("/a") + " _range_max:=-1.0", {"range_max", "-1"});
}

TEST(NodeStartup, SamplesAndIncrementTogether) {
  expectRefused(scene("/b") + " _samples:=100 _angle_increment:=0.01", {"~samples", "not both"});
}

TEST(NodeStartup, UnknownGeometry) {
  expectRefused(scene("/c") + " _geometry:=hull", {"~geometry", "'hull'"});
}

TEST(NodeStartup, WrongType) {
  expectRefused(scene("/d") + " _rate:=fast", {"~rate", "expected a number"});
}

TEST(NodeStartup, UnknownMinRangePolicy) {
  expectRefused(scene("/e") + " _min_range_policy:=zero", {"~min_range_policy", "'zero'"});
}

TEST(NodeStartup, AngleMaxBelowAngleMin) {
  expectRefused(scene("/f") + " _angle_min:=1.0 _angle_max:=0.5", {"angle_max", "angle_min"});
}

TEST(NodeStartup, ReflectivityOfAnUnknownLink) {
  XmlRpc::XmlRpcValue reflectivity;
  reflectivity["no_such_link"] = 0.5;
  ros::NodeHandle().setParam("/g/node/reflectivity", reflectivity);
  expectRefused(scene("/g") + " _intensity:=reflectivity", {"no_such_link", "has no geometry"});
}

TEST(NodeStartup, ModelsOfTheWrongShape) {
  XmlRpc::XmlRpcValue models;
  models.setSize(1);
  models[0]["param"] = "robot_description";
  models[0]["file"] = "/both/given.urdf";
  ros::NodeHandle().setParam("/k/node/models", models);
  expectRefused(scene("/k"), {"~models[0]", "exactly one of"});
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

TEST(NodeStartup, SkipBadGeometryStartsWithAWarning) {
  ros::NodeHandle().setParam("/j/node/models", modelFile(data("bad_mesh.urdf")));
  const NodeRun run = runNode("__ns:=/j __name:=node _skip_bad_geometry:=true", 4);
  EXPECT_EQ(run.status, 124) << "the node should still be running when timeout stops it:\n"
                             << run.output;
  EXPECT_NE(run.output.find("broken_link"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("WARN"), std::string::npos) << run.output;
}

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_startup");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
