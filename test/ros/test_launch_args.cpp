// rostest launch_args.test: launch/laser_raycast.launch, included as users include it. Its argument
// defaults give exactly the node's defaults, every argument reaches its parameter, the nodes it
// starts run, and roslaunch lists every argument as optional and documented. The parameters are
// read back from the master and parsed by the node's own parser.
#include <gtest/gtest.h>
#include <ros/master.h>
#include <ros/package.h>
#include <ros/ros.h>

#include <algorithm>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "laser_raycast/node/node_params.h"
#include "run_command.h"

namespace laser_raycast_test {
namespace {

using laser_raycast::NodeParams;
using laser_raycast::ParamReport;

struct Parsed {
  XmlRpc::XmlRpcValue values;
  NodeParams params;
  ParamReport report;
  std::string error;
};

Parsed parse(const XmlRpc::XmlRpcValue& values) {
  Parsed out;
  out.values = values;
  out.error = laser_raycast::parseNodeParams(values, "/", &out.params, &out.report);
  return out;
}

// The private namespace of `node` as the node fetches it.
Parsed parseFromMaster(const std::string& node) {
  XmlRpc::XmlRpcValue values;
  EXPECT_TRUE(ros::NodeHandle().getParam(node, values)) << "nothing set under " << node;
  return parse(values);
}

std::set<std::string> keys(const XmlRpc::XmlRpcValue& values) {
  std::set<std::string> out;
  if (values.getType() != XmlRpc::XmlRpcValue::TypeStruct) return out;
  for (auto it = values.begin(); it != values.end(); ++it) out.insert(it->first);
  return out;
}

TEST(LaunchArgs, TheDefaultsAreTheNodesDefaults) {
  const Parsed launched = parseFromMaster("/defaults/laser_raycast");
  const Parsed unset = parse(XmlRpc::XmlRpcValue());
  ASSERT_EQ(launched.error, "");
  EXPECT_TRUE(launched.report.warnings.empty()) << launched.report.warnings.front();
  // One line per parameter with its exact value: equal lines, equal parameters.
  EXPECT_EQ(launched.report.values, unset.report.values);
}

TEST(LaunchArgs, EveryArgumentReachesItsParameter) {
  const Parsed all = parseFromMaster("/all/sim");
  ASSERT_EQ(all.error, "");
  EXPECT_TRUE(all.report.warnings.empty()) << all.report.warnings.front();
  const NodeParams& p = all.params;
  EXPECT_EQ(p.sensors.at(0).frame_id, "base_scan");
  EXPECT_EQ(p.fixed_frame, "odom");
  EXPECT_EQ(p.sensors.at(0).scan.fan.angle_min, -1.5);
  EXPECT_EQ(p.sensors.at(0).scan.fan.angle_max, 1.5);
  EXPECT_EQ(p.sensors.at(0).scan.fan.angle_increment, 0.01);
  EXPECT_EQ(p.sensors.at(0).scan.fan.samples, 0);
  EXPECT_EQ(p.sensors.at(0).scan.output.range_min, 0.12);
  EXPECT_EQ(p.sensors.at(0).scan.output.range_max, 3.5);
  EXPECT_EQ(p.sensors.at(0).scan.output.min_range_policy,
            laser_raycast::core::MinRangePolicy::kPassThrough);
  EXPECT_EQ(p.sensors.at(0).rate, 5.0);
  EXPECT_EQ(p.tf_timeout, 0.25);
  EXPECT_EQ(p.threads, 2);
  ASSERT_EQ(p.models.size(), 2u);
  EXPECT_EQ(p.models[0].param, "scene_description");
  EXPECT_EQ(p.models[0].tf_prefix, "s/");
  EXPECT_EQ(p.models[1].file,
            ros::package::getPath("laser_raycast") + "/test/data/cli_joints.urdf");
  EXPECT_EQ(p.models[1].tf_prefix, "t/");
  EXPECT_EQ(p.geometry, laser_raycast::GeometrySource::kCollision);
  EXPECT_EQ(p.ignore_links, (std::vector<std::string>{"s/arm", "slider"}));
  EXPECT_TRUE(p.skip_bad_geometry);
  EXPECT_EQ(p.sensors.at(0).scan.output.noise_stddev, 0.01);
  EXPECT_EQ(p.sensors.at(0).scan.output.noise_seed, 42u);
  EXPECT_TRUE(p.sensors.at(0).scan.output.intensity);
  EXPECT_EQ(p.reflectivity, (std::map<std::string, double>{{"s/plate", 0.5}, {"t/plate", 2.0}}));
  EXPECT_EQ(p.default_reflectivity, 0.25);
  EXPECT_EQ(p.sensors.at(0).scan.method, laser_raycast::core::TriangleMethod::kCramer);
  EXPECT_TRUE(p.sensors.at(0).scan.cull_backfaces);
  EXPECT_EQ(p.sensors.at(0).pose_topic, "/all/pose");
  EXPECT_EQ(p.sensors.at(0).pose_frame, "base_link");
  EXPECT_EQ(p.sensors.at(0).pose_timeout, 0.2);
  EXPECT_EQ(p.sensors.at(0).sensor_model, "UTM-30LX");
  EXPECT_EQ(p.sensors.at(0).scan.elevations, (std::vector<double>{0.1, -0.1}));
  EXPECT_EQ(p.sensors.at(0).sweep, laser_raycast::Sweep::kRotating);
  EXPECT_EQ(p.sensors.at(0).scan_time, 0.1);
  EXPECT_TRUE(p.sensors.at(0).organized);
  EXPECT_EQ(p.sensors.at(0).point_layout, laser_raycast::PointLayout::kOusterLegacy);
  EXPECT_EQ(p.sensors.at(0).scan.output.range_bias, 0.01);
  EXPECT_EQ(p.sensors.at(0).scan.output.range_resolution, 0.002);
  EXPECT_EQ(p.sensors.at(0).scan.output.dropout_probability, 0.05);
  EXPECT_FALSE(p.sensors.at(0).scan.output.surface_reflectance);
  EXPECT_EQ(p.sensors.at(0).scan.output.reflectance_from_color, 0.8);
  EXPECT_EQ(p.sensors.at(0).scan.output.detection_range, 100.0);
  EXPECT_EQ(p.sensors.at(0).scan.output.detection_reflectivity, 0.2);
  EXPECT_EQ(p.sensors.at(0).returns.beam_divergence, 0.003);
  EXPECT_EQ(p.sensors.at(0).returns.beam_samples, 7);
  EXPECT_EQ(p.sensors.at(0).returns.return_mode, laser_raycast::core::ReturnMode::kDual);
  EXPECT_EQ(p.sensors.at(0).returns.min_return_separation, 0.3);

  const Parsed pattern = parseFromMaster("/pattern/laser_raycast");
  ASSERT_EQ(pattern.error, "");
  EXPECT_EQ(pattern.params.sensors.at(0).pattern_file,
            ros::package::getPath("laser_raycast") + "/config/patterns/rosette_4line.csv");
  EXPECT_EQ(pattern.params.sensors.at(0).points_per_scan, 2000);
  EXPECT_EQ(pattern.params.sensors.at(0).point_rate, 20000.0);
  const Parsed calibrated = parseFromMaster("/calibrated/laser_raycast");
  ASSERT_EQ(calibrated.error, "");
  EXPECT_EQ(calibrated.params.sensors.at(0).calibration_file,
            ros::package::getPath("laser_raycast") + "/test/data/vlp16_calibration.yaml");
  const Parsed ouster = parseFromMaster("/ouster/laser_raycast");
  ASSERT_EQ(ouster.error, "");
  EXPECT_EQ(ouster.params.sensors.at(0).ouster_metadata,
            ros::package::getPath("laser_raycast") + "/config/ouster/os1_64_nominal.json");
  ASSERT_TRUE(ouster.params.sensors.at(0).calibrated);
  EXPECT_EQ(ouster.params.sensors.at(0).calibrated->size(), 64 * 1024);

  const Parsed realistic = parseFromMaster("/realistic/laser_raycast");
  ASSERT_EQ(realistic.error, "");
  EXPECT_EQ(realistic.params.sensors.at(0).sensor_model, "OS1-64-realistic");
  EXPECT_EQ(realistic.params.sensors.at(0).scan.output.detection_range, 40.0);
  EXPECT_EQ(realistic.params.sensors.at(0).scan.output.detection_reflectivity, 0.1);
  EXPECT_EQ(realistic.params.sensors.at(0).returns.beam_samples, 7);
  EXPECT_EQ(realistic.params.sensors.at(0).returns.min_return_separation, 0.012);

  const Parsed samples = parseFromMaster("/samples/laser_raycast");
  ASSERT_EQ(samples.error, "");
  EXPECT_EQ(samples.params.sensors.at(0).scan.fan.samples, 100);
  EXPECT_EQ(samples.params.sensors.at(0).scan.fan.angle_increment, 0.0);
  ASSERT_EQ(samples.params.sensors.size(), 2u);
  EXPECT_EQ(samples.params.sensors[0].frame_id, "front");
  EXPECT_EQ(samples.params.sensors[1].name, "top");
  EXPECT_EQ(samples.params.sensors[1].sensor_model, "VLP-16");

  // Between them, they set every parameter the node reads.
  std::set<std::string> set = keys(all.values);
  for (const Parsed* other : {&samples, &pattern, &calibrated, &ouster}) {
    for (const std::string& name : keys(other->values)) set.insert(name);
  }
  for (const std::string& name : laser_raycast::nodeParamNames()) {
    EXPECT_TRUE(set.count(name)) << "no argument of laser_raycast.launch sets ~" << name;
  }
}

// Each node advertises its scans, and their labels on <topic>_labels also when scan_topic or
// points_topic renames the topic.
TEST(LaunchArgs, TheNodesStart) {
  const std::vector<std::string> scans = {"/defaults/scan",      "/defaults/scan_labels",
                                          "/all/points_all",     "/all/points_all_labels",
                                          "/samples/front/scan", "/samples/top/points",
                                          "/topics/front_scan",  "/topics/front_scan_labels"};
  std::set<std::string> advertised;
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(60.0);
  while (advertised.size() < scans.size() && ros::WallTime::now() < give_up) {
    ros::master::V_TopicInfo topics;
    ros::master::getTopics(topics);
    for (const auto& topic : topics) {
      if (std::find(scans.begin(), scans.end(), topic.name) != scans.end()) {
        advertised.insert(topic.name);
      }
    }
    ros::WallDuration(0.1).sleep();
  }
  for (const std::string& scan : scans) {
    EXPECT_TRUE(advertised.count(scan))
        << scan << " was never advertised: the node did not start, or published elsewhere";
  }
}

TEST(LaunchArgs, RoslaunchListsEveryArgumentAsOptionalAndDocumented) {
  const std::string launch =
      ros::package::getPath("laser_raycast") + "/launch/laser_raycast.launch";
  const CommandResult r = runCommand("roslaunch --ros-args '" + launch + "' 2>&1");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_EQ(r.output.find("Required Arguments"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("undocumented"), std::string::npos) << r.output;
  for (const std::string& name : laser_raycast::nodeParamNames()) {
    EXPECT_NE(r.output.find("\n  " + name + " (default \""), std::string::npos)
        << "no argument named " << name << ":\n"
        << r.output;
  }
}

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_launch_args");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
