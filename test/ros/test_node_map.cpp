// End to end (rostest node_map.test): laser_raycast_node on map worlds. A map file,
// test/data/maps/box_room.yaml (ranges worked out by hand in its comment), with the sensor placed
// by TF from this test; ranges within 1e-5 m.
#include <gtest/gtest.h>
#include <laser_raycast/ScanLabels.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <string>
#include <vector>

namespace laser_raycast_test {
namespace {

constexpr double kTolerance = 1e-5;  // m

// The newest message on topic stamped after `after`, waiting up to 20 s.
template <class Message>
typename Message::ConstPtr nextOn(const std::string& topic, const ros::Time& after) {
  ros::NodeHandle nh;
  typename Message::ConstPtr got;
  const ros::Subscriber sub =
      nh.subscribe<Message>(topic, 1, [&](const typename Message::ConstPtr& m) {
        if (m->header.stamp > after) got = m;
      });
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(20.0);
  while (ros::ok() && !got && ros::WallTime::now() < give_up) {
    ros::spinOnce();
    ros::WallDuration(0.005).sleep();
  }
  EXPECT_TRUE(got) << "nothing on " << topic;
  return got;
}

void expectRanges(const sensor_msgs::LaserScan::ConstPtr& scan, const std::vector<double>& ranges) {
  ASSERT_TRUE(scan);
  ASSERT_EQ(scan->ranges.size(), ranges.size());
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    EXPECT_NEAR(scan->ranges[i], ranges[i], kTolerance) << "beam " << i;
  }
}

// The sensor at (0, 0.375, 0.5) in the map frame, looking along x: the room's walls at 1.125 m
// (-y), 0.375 m (+y) and 1.25 m (-x), the pillar at 0.5 m (+x).
TEST(NodeMap, MapFileWallsAtHandComputedRanges) {
  tf2_ros::StaticTransformBroadcaster tf;
  geometry_msgs::TransformStamped laser;
  laser.header.stamp = ros::Time::now();
  laser.header.frame_id = "map";
  laser.child_frame_id = "laser";
  laser.transform.translation.y = 0.375;
  laser.transform.translation.z = 0.5;
  laser.transform.rotation.w = 1;
  tf.sendTransform(laser);
  const ros::Time now = ros::Time::now();
  expectRanges(nextOn<sensor_msgs::LaserScan>("scan", now), {1.125, 0.5, 0.375, 1.25});
  const auto labels = nextOn<laser_raycast::ScanLabels>("scan_labels", now);
  ASSERT_TRUE(labels);
  ASSERT_EQ(labels->labels.size(), 4u);
  for (const int label : labels->labels) {
    ASSERT_GE(label, 0);
    EXPECT_EQ(labels->link_names.at(label), "map");
  }
}

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_map");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
