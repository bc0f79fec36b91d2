// rostest node_tf_stops.test and node_tf_late.test: the node under the TF faults a robot stack
// really has, on test/data/node_scene.urdf (README, "Faults"). The test publishes the sensor's and
// the mover's transforms itself: in one case the mover's stop (a driver died), in the other every
// transform arrives 0.3 s after its stamp (a loaded TF tree, a bag, a slow link).
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_msgs/TFMessage.h>

#include <cmath>
#include <deque>
#include <iostream>
#include <limits>
#include <mutex>
#include <vector>

#include "scan_access.h"

namespace laser_raycast_test {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// ~tf_timeout of the nodes (the default).
constexpr double kTfTimeout = 0.5;  // s
// Each scan checked against the geometry at its stamp: ranges are float (1e-7 relative) and TF
// interpolates the test's smooth path linearly between 100 Hz samples (below 1e-5 m here).
constexpr double kTolerance = 1e-4;  // m

geometry_msgs::TransformStamped transform(const ros::Time& stamp, const std::string& child,
                                          double x, double y, double z) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = stamp;
  t.header.frame_id = "world";
  t.child_frame_id = child;
  t.transform.translation.x = x;
  t.transform.translation.y = y;
  t.transform.translation.z = z;
  t.transform.rotation.w = 1;
  return t;
}

// Publishes the laser's and the mover's transforms at 100 Hz on /tf (from its own timer thread),
// each `delay` after its stamp, and records every scan of the node.
class Rig {
 public:
  explicit Rig(double delay) : delay_(delay) {
    tf_pub_ = nh_.advertise<tf2_msgs::TFMessage>("/tf", 100);
    scan_sub_ = nh_.subscribe("scan", 100, &Rig::onScan, this);
    start_ = ros::Time::now();
    timer_ = nh_.createTimer(ros::Duration(0.01), &Rig::onTimer, this);
  }

  // The laser's x at time t: a slow sway, so that a scan from the wrong time is metres wrong.
  double laserX(const ros::Time& t) const { return 0.5 * std::sin(0.5 * (t - start_).toSec()); }

  void setMover(bool publish, double x, double y, double z) {
    std::lock_guard<std::mutex> lock(mutex_);
    mover_ = publish;
    mover_x_ = x, mover_y_ = y, mover_z_ = z;
  }
  void setLaserMoves(bool moves) {
    std::lock_guard<std::mutex> lock(mutex_);
    laser_moves_ = moves;
  }

  // Waits (wall time) until a scan satisfying `ok` arrives; false after `seconds`.
  template <class F>
  bool waitFor(F ok, double seconds) {
    const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(seconds);
    while (ros::ok() && ros::WallTime::now() < give_up) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        for (const auto& scan : scans_) {
          if (ok(*scan)) return true;
        }
      }
      ros::WallDuration(0.01).sleep();
    }
    return false;
  }

  std::vector<sensor_msgs::LaserScan::ConstPtr> scans() {
    std::lock_guard<std::mutex> lock(mutex_);
    return scans_;
  }

 private:
  void onScan(const sensor_msgs::LaserScan::ConstPtr& scan) {
    std::lock_guard<std::mutex> lock(mutex_);
    scans_.push_back(scan);
  }

  void onTimer(const ros::TimerEvent&) {
    const ros::Time now = ros::Time::now();
    std::lock_guard<std::mutex> lock(mutex_);
    tf2_msgs::TFMessage msg;
    msg.transforms.push_back(transform(now, "laser", laser_moves_ ? laserX(now) : 0.0, 0, 0));
    if (mover_) msg.transforms.push_back(transform(now, "mover", mover_x_, mover_y_, mover_z_));
    pending_.push_back(msg);
    while (!pending_.empty() &&
           pending_.front().transforms.front().header.stamp + ros::Duration(delay_) <= now) {
      tf_pub_.publish(pending_.front());
      pending_.pop_front();
    }
  }

  ros::NodeHandle nh_;
  double delay_;
  ros::Publisher tf_pub_;
  ros::Subscriber scan_sub_;
  ros::Timer timer_;
  ros::Time start_;
  std::mutex mutex_;
  bool mover_ = true, laser_moves_ = false;
  double mover_x_ = 0, mover_y_ = 0, mover_z_ = 5;
  std::deque<tf2_msgs::TFMessage> pending_;
  std::vector<sensor_msgs::LaserScan::ConstPtr> scans_;
};

// Scans stamped in [from, from + seconds) per second.
double rateOver(const std::vector<sensor_msgs::LaserScan::ConstPtr>& scans, const ros::Time& from,
                double seconds) {
  int n = 0;
  for (const auto& scan : scans) {
    n += scan->header.stamp >= from && scan->header.stamp < from + ros::Duration(seconds);
  }
  return n / seconds;
}

// Beams at -pi + i pi/4 (8 samples): beam 4 looks along +x at the box face x = 2.5, beam 5 (pi/4)
// at the mover when it is at (1.5, 1.5, 0).
TEST(NodeFaults, OneLinksTfStopsTheRateStays) {
  Rig rig(0.0);
  rig.setMover(true, 1.5, 1.5, 0);
  const double with_mover = 1.5 * std::sqrt(2.0) - 0.25;
  ASSERT_TRUE(rig.waitFor(
      [&](const sensor_msgs::LaserScan& s) {
        return s.ranges.size() == 8 && std::abs(s.ranges[5] - with_mover) < kTolerance;
      },
      30.0))
      << "no scan showing the mover";

  rig.setMover(false, 0, 0, 0);  // its driver dies
  const ros::Time stopped = ros::Time::now();
  const double kWindow = 5.0;  // s
  ros::WallDuration(kWindow + 2 * kTfTimeout + 0.5).sleep();
  const auto scans = rig.scans();

  const double rate = rateOver(scans, stopped, kWindow);
  std::cout << "20 Hz node, one link's TF stopped: " << rate << " Hz over " << kWindow << " s\n";
  RecordProperty("rate_after_link_stops_hz", std::to_string(rate));
  EXPECT_GE(rate, 18.0);
  // Once its newest transform is older than tf_timeout the mover is left out, the rest is cast.
  int checked = 0;
  for (const auto& scan : scans) {
    if (scan->header.stamp < stopped + ros::Duration(kTfTimeout + 0.1)) continue;
    ++checked;
    EXPECT_EQ(rangeOf(*scan, 5), kInf) << "t = " << scan->header.stamp;
    EXPECT_NEAR(rangeOf(*scan, 4), 2.5, kTolerance) << "t = " << scan->header.stamp;
  }
  EXPECT_GT(checked, 0);
}

// The laser sways along x; beam 4 (+x) sees the box face at 2.5 - x, beam 0 (-x) the sphere at
// x + 1.5, x taken at the scan's own stamp.
TEST(NodeFaults, EveryTransformLateTheRateStaysAndScansMatchTheirStamps) {
  Rig rig(0.3);
  rig.setLaserMoves(true);
  ASSERT_TRUE(
      rig.waitFor([](const sensor_msgs::LaserScan& s) { return s.ranges.size() == 8; }, 30.0))
      << "no scan with every transform 0.3 s late";
  const ros::Time first = ros::Time::now();
  const double kWindow = 5.0;  // s
  ros::WallDuration(kWindow + kTfTimeout + 0.5).sleep();
  const auto scans = rig.scans();

  const double rate = rateOver(scans, first, kWindow);
  std::cout << "10 Hz node, every transform 0.3 s late: " << rate << " Hz over " << kWindow
            << " s\n";
  RecordProperty("rate_with_late_tf_hz", std::to_string(rate));
  EXPECT_GE(rate, 9.0);
  for (const auto& scan : scans) {
    const double x = rig.laserX(scan->header.stamp);
    EXPECT_NEAR(rangeOf(*scan, 4), 2.5 - x, kTolerance) << "t = " << scan->header.stamp;
    EXPECT_NEAR(rangeOf(*scan, 0), x + 1.5, kTolerance) << "t = " << scan->header.stamp;
  }
}

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_faults");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
