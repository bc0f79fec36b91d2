// rostest node_pose_topic.test: the sensor pose from geometry_msgs/PoseWithCovarianceStamped (of
// another frame, combined with TF) and from geometry_msgs/PoseStamped; non-finite poses are
// ignored.
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <cmath>
#include <limits>
#include <mutex>

namespace laser_raycast_test {
namespace {

constexpr double kTolerance = 1e-5;  // m

class PoseTopicTest : public ::testing::Test {
 protected:
  void SetUp() override {
    cov_pub_ = nh_.advertise<geometry_msgs::PoseWithCovarianceStamped>("/pose_cov", 10);
    plain_pub_ = nh_.advertise<geometry_msgs::PoseStamped>("/pose_plain", 10);
    cov_sub_ = nh_.subscribe<sensor_msgs::LaserScan>(
        "scan_cov", 10,
        [this](const sensor_msgs::LaserScan::ConstPtr& m) { store(&cov_scan_, m); });
    plain_sub_ = nh_.subscribe<sensor_msgs::LaserScan>(
        "scan_plain", 10,
        [this](const sensor_msgs::LaserScan::ConstPtr& m) { store(&plain_scan_, m); });
    // The laser is mounted 0.5 m ahead of "base".
    geometry_msgs::TransformStamped mount;
    mount.header.stamp = ros::Time::now();
    mount.header.frame_id = "base";
    mount.child_frame_id = "laser";
    mount.transform.translation.x = 0.5;
    mount.transform.rotation.w = 1;
    static_broadcaster_.sendTransform(mount);
  }

  void store(sensor_msgs::LaserScan::ConstPtr* slot, const sensor_msgs::LaserScan::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    *slot = m;
  }

  // Publishes `publish` repeatedly until a scan stamped after the first publication arrives in
  // slot.
  template <class F>
  sensor_msgs::LaserScan scanAfter(F publish, sensor_msgs::LaserScan::ConstPtr* slot) {
    const ros::Time since = ros::Time::now() + ros::Duration(0.1);
    const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(20.0);
    while (ros::ok() && ros::WallTime::now() < give_up) {
      publish();
      ros::spinOnce();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (*slot && (*slot)->header.stamp > since) return **slot;
      }
      ros::WallDuration(0.01).sleep();
    }
    ADD_FAILURE() << "no scan after publishing the pose";
    return sensor_msgs::LaserScan();
  }

  void publishCov(double x, double y) {
    geometry_msgs::PoseWithCovarianceStamped m;
    m.header.stamp = ros::Time::now();
    m.header.frame_id = "world";
    m.pose.pose.position.x = x;
    m.pose.pose.position.y = y;
    m.pose.pose.orientation.w = 1;
    cov_pub_.publish(m);
  }
  void publishPlain(double x, double y, double qw) {
    geometry_msgs::PoseStamped m;
    m.header.stamp = ros::Time::now();
    m.header.frame_id = "world";
    m.pose.position.x = x;
    m.pose.position.y = y;
    m.pose.orientation.w = qw;
    plain_pub_.publish(m);
  }

  ros::NodeHandle nh_;
  ros::Publisher cov_pub_, plain_pub_;
  ros::Subscriber cov_sub_, plain_sub_;
  tf2_ros::StaticTransformBroadcaster static_broadcaster_;
  std::mutex mutex_;
  sensor_msgs::LaserScan::ConstPtr cov_scan_, plain_scan_;
};

// Beam 4 looks along +x at the box face x = 2.5 (test/data/node_scene.urdf); beam 0 along -x at the
// sphere surface x = -1.5.
TEST_F(PoseTopicTest, PoseWithCovarianceOfAnotherFrameIsCombinedWithTf) {
  // base at x = -0.5 puts the laser at the origin.
  sensor_msgs::LaserScan scan = scanAfter([&] { publishCov(-0.5, 0); }, &cov_scan_);
  ASSERT_EQ(scan.ranges.size(), 8u);
  EXPECT_NEAR(scan.ranges[4], 2.5, kTolerance);
  EXPECT_NEAR(scan.ranges[0], 1.5, kTolerance);
  // base at x = 0.5: the laser at x = 1.
  scan = scanAfter([&] { publishCov(0.5, 0); }, &cov_scan_);
  EXPECT_NEAR(scan.ranges[4], 1.5, kTolerance);
  EXPECT_NEAR(scan.ranges[0], 2.5, kTolerance);
}

TEST_F(PoseTopicTest, PoseStampedGivesTheLaserPoseAndBadPosesAreIgnored) {
  sensor_msgs::LaserScan scan = scanAfter([&] { publishPlain(0.5, 0, 1); }, &plain_scan_);
  ASSERT_EQ(scan.ranges.size(), 8u);
  EXPECT_NEAR(scan.ranges[4], 2.0, kTolerance);
  // A NaN position and a zero quaternion are dropped: scans keep using the last good pose.
  scan = scanAfter(
      [&] {
        publishPlain(std::numeric_limits<double>::quiet_NaN(), 0, 1);
        publishPlain(0.1, 0, 0);
      },
      &plain_scan_);
  EXPECT_NEAR(scan.ranges[4], 2.0, kTolerance);
}

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_pose_topic");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
