// rostest node_pose_topic.test: the sensor pose from geometry_msgs/PoseWithCovarianceStamped (of
// another frame, combined with TF) and from geometry_msgs/PoseStamped; a pose older than
// ~pose_timeout or a non-finite one gives no scan; a pose in a frame without a transform is a
// failed TF look-up in the diagnostics.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <array>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "scan_access.h"

namespace laser_raycast_test {
namespace {

constexpr double kTolerance = 1e-5;  // m
// ~pose_timeout of node "plain" (node_pose_topic.test).
// s. Long enough (12 scan periods) that a node starved of CPU for a moment on a loaded machine
// still casts some scans while the last pose is fresh: a cast thread that falls behind drops its
// oldest scans (ScanQueue), which is right for a live node but would empty a shorter window.
constexpr double kPoseTimeout = 0.6;

bool anyValid(const sensor_msgs::LaserScan& scan) {
  for (const float r : scan.ranges) {
    if (r >= scan.range_min && r <= scan.range_max) return true;
  }
  return false;
}

class PoseTopicTest : public ::testing::Test {
 protected:
  void SetUp() override {
    cov_pub_ = nh_.advertise<geometry_msgs::PoseWithCovarianceStamped>("/pose_cov", 10);
    plain_pub_ = nh_.advertise<geometry_msgs::PoseStamped>("/pose_plain", 10);
    cov_sub_ = nh_.subscribe<sensor_msgs::LaserScan>(
        "scan_cov", 10,
        [this](const sensor_msgs::LaserScan::ConstPtr& m) { store(&cov_scan_, m); });
    plain_sub_ = nh_.subscribe<sensor_msgs::LaserScan>(
        "scan_plain", 100, [this](const sensor_msgs::LaserScan::ConstPtr& m) {
          store(&plain_scan_, m);
          std::lock_guard<std::mutex> lock(mutex_);
          plain_all_.push_back(m);
        });
    // The laser is mounted 0.5 m ahead of "base".
    geometry_msgs::TransformStamped mount;
    mount.header.stamp = ros::Time::now();
    mount.header.frame_id = "base";
    mount.child_frame_id = "laser";
    mount.transform.translation.x = 0.5;
    mount.transform.rotation.w = 1;
    static_broadcaster_.sendTransform(mount);
    diagnostics_sub_ = nh_.subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 20, [this](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
          for (const auto& status : m->status) {
            if (status.name != "plain: laser scans") continue;
            std::lock_guard<std::mutex> lock(mutex_);
            plain_status_stamp_ = m->header.stamp;
            plain_status_.clear();
            for (const auto& kv : status.values) plain_status_[kv.key] = kv.value;
          }
        });
  }

  // Node "plain"'s scans status ("<sensor> scans") from a report made after `after`, calling
  // `publish` every 50 ms meanwhile (so that the pose does not go stale); empty (with a failure)
  // if none comes.
  template <class F>
  std::map<std::string, std::string> plainStatusAfter(const ros::Time& after, F publish) {
    const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(10.0);
    while (ros::ok() && ros::WallTime::now() < give_up) {
      publish();
      for (int i = 0; i < 5; ++i) {
        ros::spinOnce();
        std::lock_guard<std::mutex> lock(mutex_);
        if (plain_status_stamp_ > after) return plain_status_;
        ros::WallDuration(0.01).sleep();
      }
    }
    ADD_FAILURE() << "no diagnostics from node plain after t = " << after;
    return {};
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

  // Calls `publish` every 50 ms for `seconds` (wall time), spinning; returns the scans of node
  // "plain" that arrived meanwhile.
  template <class F>
  std::vector<sensor_msgs::LaserScan::ConstPtr> plainScansWhile(double seconds, F publish) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      plain_all_.clear();
    }
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
    while (ros::ok() && ros::WallTime::now() < end) {
      publish();
      for (int i = 0; i < 5; ++i) {
        ros::spinOnce();
        ros::WallDuration(0.01).sleep();
      }
    }
    std::lock_guard<std::mutex> lock(mutex_);
    return plain_all_;
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
  // Returns the message's stamp.
  ros::Time publishPlain(double x, double y, double qw, const std::string& frame = "world") {
    geometry_msgs::PoseStamped m;
    m.header.stamp = ros::Time::now();
    m.header.frame_id = frame;
    m.pose.position.x = x;
    m.pose.position.y = y;
    m.pose.orientation.w = qw;
    plain_pub_.publish(m);
    return m.header.stamp;
  }

  // Every scan with a valid range must be stamped at most pose_timeout after the last good pose.
  void expectNoScanFromAStalePose(const std::vector<sensor_msgs::LaserScan::ConstPtr>& scans,
                                  const ros::Time& last_good) {
    for (const auto& scan : scans) {
      const double age = (scan->header.stamp - last_good).toSec();
      if (age > kPoseTimeout) {
        EXPECT_FALSE(anyValid(*scan)) << "a scan at t = " << scan->header.stamp << " from a pose "
                                      << age << " s old (~pose_timeout " << kPoseTimeout << ")";
      }
    }
  }

  ros::NodeHandle nh_;
  ros::Publisher cov_pub_, plain_pub_;
  ros::Subscriber cov_sub_, plain_sub_, diagnostics_sub_;
  tf2_ros::StaticTransformBroadcaster static_broadcaster_;
  std::mutex mutex_;
  sensor_msgs::LaserScan::ConstPtr cov_scan_, plain_scan_;
  std::vector<sensor_msgs::LaserScan::ConstPtr> plain_all_;
  ros::Time plain_status_stamp_;
  std::map<std::string, std::string> plain_status_;
};

// A diagnostics count, as a number (0 with a failure if absent).
double count(const std::map<std::string, std::string>& status, const std::string& key) {
  const auto found = status.find(key);
  if (found == status.end()) {
    ADD_FAILURE() << "no '" << key << "' in the diagnostics";
    return 0;
  }
  return std::stod(found->second);
}

// Beam 4 looks along +x at the box face x = 2.5 (test/data/node_scene.urdf); beam 0 along -x at the
// sphere surface x = -1.5.
TEST_F(PoseTopicTest, PoseWithCovarianceOfAnotherFrameIsCombinedWithTf) {
  // base at x = -0.5 puts the laser at the origin.
  sensor_msgs::LaserScan scan = scanAfter([&] { publishCov(-0.5, 0); }, &cov_scan_);
  ASSERT_EQ(scan.ranges.size(), 8u);
  EXPECT_NEAR(rangeOf(scan, 4), 2.5, kTolerance);
  EXPECT_NEAR(rangeOf(scan, 0), 1.5, kTolerance);
  // base at x = 0.5: the laser at x = 1.
  scan = scanAfter([&] { publishCov(0.5, 0); }, &cov_scan_);
  EXPECT_NEAR(rangeOf(scan, 4), 1.5, kTolerance);
  EXPECT_NEAR(rangeOf(scan, 0), 2.5, kTolerance);
}

TEST_F(PoseTopicTest, PoseStampedGivesTheLaserPose) {
  const sensor_msgs::LaserScan scan = scanAfter([&] { publishPlain(0.5, 0, 1); }, &plain_scan_);
  ASSERT_EQ(scan.ranges.size(), 8u);
  EXPECT_NEAR(rangeOf(scan, 4), 2.0, kTolerance);
}

// The publisher stops: the last pose serves scans for ~pose_timeout, then none come.
TEST_F(PoseTopicTest, NoScanFromAPoseOlderThanPoseTimeout) {
  scanAfter([&] { publishPlain(0.5, 0, 1); }, &plain_scan_);
  const ros::Time last_good = publishPlain(0.5, 0, 1);
  const auto scans = plainScansWhile(2.0, [] {});
  expectNoScanFromAStalePose(scans, last_good);
  // The pose was held while fresh: scans came after the last message, none later than the timeout.
  int held = 0;
  for (const auto& scan : scans) held += scan->header.stamp > last_good && anyValid(*scan);
  std::ostringstream stamps;
  for (const auto& scan : scans) {
    stamps << " " << (scan->header.stamp - last_good).toSec() << (anyValid(*scan) ? "" : "(none)");
  }
  EXPECT_GT(held, 0) << "no scan from the last pose while it was fresh; scans at (s after it):"
                     << stamps.str();
  // And they resume with the publisher.
  const sensor_msgs::LaserScan again = scanAfter([&] { publishPlain(1.0, 0, 1); }, &plain_scan_);
  EXPECT_NEAR(rangeOf(again, 4), 1.5, kTolerance);
}

// A NaN position or a zero quaternion says the pose is unknown: no scan from the last good pose
// beyond ~pose_timeout (the node stops at the bad message's stamp).
TEST_F(PoseTopicTest, NoScanFromANonFinitePose) {
  const double kNan = std::numeric_limits<double>::quiet_NaN();
  for (const auto& bad : {std::array<double, 3>{kNan, 0, 1}, std::array<double, 3>{0.1, 0, 0}}) {
    scanAfter([&] { publishPlain(0.5, 0, 1); }, &plain_scan_);
    const ros::Time last_good = publishPlain(0.5, 0, 1);
    const auto scans = plainScansWhile(1.5, [&] { publishPlain(bad[0], bad[1], bad[2]); });
    expectNoScanFromAStalePose(scans, last_good);
    const sensor_msgs::LaserScan again = scanAfter([&] { publishPlain(0.5, 0, 1); }, &plain_scan_);
    EXPECT_NEAR(rangeOf(again, 4), 2.0, kTolerance);
  }
}

// Poses in a frame TF cannot bring into fixed_frame: each scan is skipped (the pose topic's reason)
// after a failed TF look-up, which the diagnostics count as such (a look-up failure, not a skip
// for want of the sensor's transform). Poses are published all along, so that no scan is skipped
// for a stale pose.
TEST_F(PoseTopicTest, APoseInAFrameWithoutTransformIsAFailedTfLookUp) {
  const auto good = [&] { publishPlain(0.5, 0, 1); };
  const auto lost = [&] { publishPlain(0.5, 0, 1, "nowhere"); };
  scanAfter(good, &plain_scan_);
  const auto before = plainStatusAfter(ros::Time::now(), good);
  const ros::Time last_good = publishPlain(0.5, 0, 1);
  const auto scans = plainScansWhile(2.0, lost);
  const auto after = plainStatusAfter(ros::Time::now(), lost);
  expectNoScanFromAStalePose(scans, last_good);
  const double failures =
      count(after, "TF look-up failures") - count(before, "TF look-up failures");
  const double skipped = count(after, "Scans skipped: pose topic stale or non-finite") -
                         count(before, "Scans skipped: pose topic stale or non-finite");
  std::cout << "2 s of poses in a frame without transform (20 Hz node): " << failures
            << " failed TF look-ups, " << skipped << " scans skipped\n";
  // About 40 scans in 2 s at 20 Hz (and more until the report), each skipped after a failed
  // look-up.
  EXPECT_GE(skipped, 20);
  EXPECT_GE(failures, skipped);
  EXPECT_EQ(count(after, "Scans skipped: no sensor transform"),
            count(before, "Scans skipped: no sensor transform"));
  const sensor_msgs::LaserScan again = scanAfter(good, &plain_scan_);
  EXPECT_NEAR(rangeOf(again, 4), 2.0, kTolerance);
}

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_pose_topic");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
