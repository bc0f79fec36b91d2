// End to end (rostest node_map.test): laser_raycast_node on map worlds. A map file,
// test/data/maps/box_room.yaml (ranges worked out by hand in its comment), and the grids this test
// publishes on a topic, latched, then changed; the sensors placed by TF from this test; ranges
// within 1e-5 m, and within 1e-6 m for beams through cells' corners.
#include <gtest/gtest.h>
#include <laser_raycast/ScanLabels.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <cmath>
#include <limits>
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

// Places a sensor frame in the map frame, turned by yaw (rad) about z, on /tf_static: one
// broadcaster for the process keeps every frame it was given (and the newest pose of each).
void placeSensor(const std::string& frame, double x, double y, double z, double yaw = 0) {
  static tf2_ros::StaticTransformBroadcaster tf;
  geometry_msgs::TransformStamped t;
  t.header.stamp = ros::Time::now();
  t.header.frame_id = "map";
  t.child_frame_id = frame;
  t.transform.translation.x = x;
  t.transform.translation.y = y;
  t.transform.translation.z = z;
  t.transform.rotation.z = std::sin(yaw / 2);
  t.transform.rotation.w = std::cos(yaw / 2);
  tf.sendTransform(t);
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
  placeSensor("laser", 0, 0.375, 0.5);
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

// Beams at cell corners, as exact as float ranges tell (1e-6 m): the sensor at (0.875, 0.375), in
// the free cell (9, 5) right of the pillar, turned 45 degrees, so that its four beams run along
// diagonals through the corners of cells: at -45 degrees to (1.25, 0) on the right wall, where two
// of its cells meet; at 45 degrees into the room's inner corner (1.25, 0.75); at 135 and -135
// degrees to the pillar's corners (0.75, 0.5) and (0.75, 0.25), which each beam touches at that
// one point only. Walls that leaked there would give the range of the wall behind.
TEST(NodeMap, BeamsThroughCellCornersWithinAMicrometre) {
  placeSensor("laser", 0.875, 0.375, 0.5, M_PI / 4);
  // The new pose reaches the node some time after it is sent: the first scan cast with it.
  const double near = 0.125 * std::sqrt(2.0), far = 0.375 * std::sqrt(2.0);
  sensor_msgs::LaserScan::ConstPtr scan;
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(20.0);
  ros::Time after = ros::Time::now();
  while (ros::ok() && ros::WallTime::now() < give_up) {
    scan = nextOn<sensor_msgs::LaserScan>("scan", after);
    if (!scan || scan->ranges.size() != 4) break;
    if (std::abs(scan->ranges[2] - near) < 1e-3) break;
    after = scan->header.stamp;
  }
  ASSERT_TRUE(scan);
  ASSERT_EQ(scan->ranges.size(), 4u);
  for (int k = 0; k < 2; ++k) {
    const std::vector<double> expected = {far, far, near, near};
    for (std::size_t i = 0; i < 4; ++i) {
      EXPECT_NEAR(scan->ranges[i], expected[i], 1e-6) << "beam " << i << ", scan " << k;
    }
    scan = nextOn<sensor_msgs::LaserScan>("scan", scan->header.stamp);
    ASSERT_TRUE(scan);
  }
}

// box_room as a grid: 12 x 8 cells of 0.25 m from (-1.5, -1), a wall of 100 all round, the rest
// 0, and each of `cells` (i, j) set to its value.
nav_msgs::OccupancyGrid roomGrid(const std::vector<std::vector<int>>& cells) {
  nav_msgs::OccupancyGrid grid;
  grid.header.frame_id = "map";
  grid.header.stamp = ros::Time::now();
  grid.info.resolution = 0.25;
  grid.info.width = 12;
  grid.info.height = 8;
  grid.info.origin.position.x = -1.5;
  grid.info.origin.position.y = -1.0;
  grid.info.origin.orientation.w = 1;
  grid.data.assign(12 * 8, 0);
  for (int j = 0; j < 8; ++j) {
    for (int i = 0; i < 12; ++i) {
      if (i == 0 || j == 0 || i == 11 || j == 7) grid.data[j * 12 + i] = 100;
    }
  }
  for (const auto& c : cells) grid.data[c[1] * 12 + c[0]] = static_cast<std::int8_t>(c[2]);
  return grid;
}

// Scans of the map_topic node until one stamped after `after` has ranges[beam] within the
// tolerance of `range`; that scan (or the last one, after 20 s).
sensor_msgs::LaserScan::ConstPtr topicScanWith(const ros::Time& after, std::size_t beam,
                                               double range) {
  sensor_msgs::LaserScan::ConstPtr scan;
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(20.0);
  while (ros::ok() && ros::WallTime::now() < give_up) {
    scan = nextOn<sensor_msgs::LaserScan>("topic_scan", after);
    if (scan && scan->ranges.size() > beam && std::abs(scan->ranges[beam] - range) < kTolerance) {
      break;
    }
  }
  return scan;
}

// The sensor at (0.125, 0.375, 0.5): the room's walls at 1.125 m (-y), 1.125 m (+x), 0.375 m (+y)
// and 1.375 m (-x). Then a grid with the pillar's cell (8, 5) at 100 (0.375 m at +x), cell (6, 6)
// at 66 (occupied: 0.125 m at +y), and on the other beams cell (2, 5) at 65 and (6, 2) at -1
// (unknown): neither is a wall.
TEST(NodeMap, MapTopicWallsRebuiltWhenANewGridArrives) {
  ros::NodeHandle nh;
  placeSensor("laser2", 0.125, 0.375, 0.5);
  // No grid yet: no walls.
  const auto empty = nextOn<sensor_msgs::LaserScan>("topic_scan", ros::Time::now());
  ASSERT_TRUE(empty);
  for (const float r : empty->ranges) EXPECT_TRUE(std::isinf(r)) << r;

  ros::Publisher pub = nh.advertise<nav_msgs::OccupancyGrid>("/test_map", 1, true);
  pub.publish(roomGrid({}));
  const auto first = topicScanWith(ros::Time::now(), 1, 1.125);
  expectRanges(first, {1.125, 1.125, 0.375, 1.375});
  const auto labels = nextOn<laser_raycast::ScanLabels>("topic_scan_labels", first->header.stamp);
  ASSERT_TRUE(labels);
  EXPECT_EQ(labels->link_names.at(labels->labels.at(1)), "map");

  pub.publish(roomGrid({{8, 5, 100}, {6, 6, 66}, {2, 5, 65}, {6, 2, -1}}));
  expectRanges(topicScanWith(ros::Time::now(), 1, 0.375), {1.125, 0.375, 0.125, 1.375});
}

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_map");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
