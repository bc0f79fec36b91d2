// End to end (rostest node_scan.test): laser_raycast_node on test/data/node_scene.urdf, with the
// sensor and a moving sphere placed by TF from this test. Ranges are checked against distances
// worked out by hand in the URDF's comment, within 1e-5 m.
#include <gtest/gtest.h>
#include <laser_raycast/ScanLabels.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <tf2_ros/transform_broadcaster.h>

#include <cmath>
#include <limits>
#include <mutex>

namespace laser_raycast_test {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTolerance = 1e-5;  // m

// One TF publisher and one pair of subscriptions for the whole process: a publisher created per
// test would lose its first messages while the node connects, and the node would then (correctly)
// interpolate between the previous test's last pose and the new one.
class World {
 public:
  World() {
    scan_sub_ = nh_.subscribe("scan", 10, &World::onScan, this);
    tuned_sub_ = nh_.subscribe("scan_tuned", 10, &World::onTuned, this);
    labels_sub_ = nh_.subscribe("scan_labels", 10, &World::onLabels, this);
    tf_timer_ = nh_.createTimer(ros::Duration(0.02), &World::publishTf, this);
  }

  // Places the sensor (x, y, yaw) and the mover (x, y, z) and returns once a scan taken afterwards
  // (stamped later than the change plus one TF period) has arrived.
  sensor_msgs::LaserScan scanWith(double laser_x, double laser_y, double laser_yaw, double mover_x,
                                  double mover_y, double mover_z) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      laser_ = {laser_x, laser_y, laser_yaw};
      mover_ = {mover_x, mover_y, mover_z};
    }
    // Two TF periods later, both TF samples around a scan's stamp carry the new poses.
    const ros::Time changed = ros::Time::now() + ros::Duration(0.05);
    const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(20.0);
    while (ros::ok() && ros::WallTime::now() < give_up) {
      ros::spinOnce();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (scan_ && scan_->header.stamp > changed) return *scan_;
      }
      ros::WallDuration(0.005).sleep();
    }
    ADD_FAILURE() << "no scan on " << scan_sub_.getTopic() << " after the poses changed";
    return sensor_msgs::LaserScan();
  }

  // The newest scan of the "tuned" node (intensities, reflectivity, an ignored link) taken at least
  // `stamp`.
  sensor_msgs::LaserScan tunedScanAfter(const ros::Time& stamp) {
    const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(20.0);
    while (ros::ok() && ros::WallTime::now() < give_up) {
      ros::spinOnce();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (tuned_ && tuned_->header.stamp >= stamp) return *tuned_;
      }
      ros::WallDuration(0.005).sleep();
    }
    ADD_FAILURE() << "no scan on " << tuned_sub_.getTopic();
    return sensor_msgs::LaserScan();
  }

  laser_raycast::ScanLabels::ConstPtr labelsFor(const ros::Time& stamp) {
    const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(10.0);
    while (ros::ok() && ros::WallTime::now() < give_up) {
      ros::spinOnce();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (labels_ && labels_->header.stamp >= stamp) return labels_;
      }
      ros::WallDuration(0.005).sleep();
    }
    return nullptr;
  }

 private:
  void onScan(const sensor_msgs::LaserScan::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    scan_ = msg;
  }
  void onTuned(const sensor_msgs::LaserScan::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    tuned_ = msg;
  }
  void onLabels(const laser_raycast::ScanLabels::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    labels_ = msg;
  }
  void publishTf(const ros::TimerEvent&) {
    std::array<double, 3> laser, mover;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      laser = laser_;
      mover = mover_;
    }
    const ros::Time now = ros::Time::now();
    geometry_msgs::TransformStamped t;
    t.header.stamp = now;
    t.header.frame_id = "world";
    t.child_frame_id = "laser";
    t.transform.translation.x = laser[0];
    t.transform.translation.y = laser[1];
    t.transform.rotation.z = std::sin(laser[2] / 2);
    t.transform.rotation.w = std::cos(laser[2] / 2);
    geometry_msgs::TransformStamped m;
    m.header = t.header;
    m.child_frame_id = "mover";
    m.transform.translation.x = mover[0];
    m.transform.translation.y = mover[1];
    m.transform.translation.z = mover[2];
    m.transform.rotation.w = 1;
    broadcaster_.sendTransform({t, m});
  }

  ros::NodeHandle nh_;
  ros::Subscriber scan_sub_, labels_sub_, tuned_sub_;
  ros::Timer tf_timer_;
  tf2_ros::TransformBroadcaster broadcaster_;
  std::mutex mutex_;
  std::array<double, 3> laser_{0, 0, 0}, mover_{0, 0, 5};
  sensor_msgs::LaserScan::ConstPtr scan_, tuned_;
  laser_raycast::ScanLabels::ConstPtr labels_;
};

World* world = nullptr;

class NodeScanTest : public ::testing::Test {
 protected:
  sensor_msgs::LaserScan scanWith(double laser_x, double laser_y, double laser_yaw, double mover_x,
                                  double mover_y, double mover_z) {
    return world->scanWith(laser_x, laser_y, laser_yaw, mover_x, mover_y, mover_z);
  }
  laser_raycast::ScanLabels::ConstPtr labelsFor(const ros::Time& stamp) {
    return world->labelsFor(stamp);
  }
  sensor_msgs::LaserScan tunedScanAfter(const ros::Time& stamp) {
    return world->tunedScanAfter(stamp);
  }
};

void expectRange(const sensor_msgs::LaserScan& scan, int beam, double expected) {
  ASSERT_LT(beam, static_cast<int>(scan.ranges.size()));
  if (std::isinf(expected)) {
    EXPECT_EQ(scan.ranges[beam], static_cast<float>(expected)) << "beam " << beam;
  } else {
    EXPECT_NEAR(scan.ranges[beam], expected, kTolerance) << "beam " << beam;
  }
}

// Beams are at -pi + i pi/4 (node_scan.test: 8 samples from -pi to 3 pi/4).
TEST_F(NodeScanTest, StaticSceneMatchesHandComputedRanges) {
  const sensor_msgs::LaserScan scan = scanWith(0, 0, 0, 0, 0, 5);
  ASSERT_EQ(scan.ranges.size(), 8u);
  EXPECT_EQ(scan.header.frame_id, "laser");
  EXPECT_NEAR(scan.angle_min, -M_PI, 1e-6);
  EXPECT_NEAR(scan.angle_max, 0.75 * M_PI, 1e-6);
  EXPECT_NEAR(scan.angle_increment, 0.25 * M_PI, 1e-6);
  EXPECT_GT(scan.angle_increment, 0.0f);
  EXPECT_EQ(scan.time_increment, 0.0f);  // every beam at the stamp
  EXPECT_NEAR(scan.scan_time, 1.0 / 20.0, 1e-6);
  EXPECT_FLOAT_EQ(scan.range_min, 0.2f);
  EXPECT_FLOAT_EQ(scan.range_max, 10.0f);
  EXPECT_TRUE(scan.intensities.empty());

  expectRange(scan, 0, 1.5);   // sphere_link
  expectRange(scan, 1, kInf);  // nothing
  expectRange(scan, 2, 2.9);   // wall_link (mesh)
  expectRange(scan, 3, kInf);  // far_link at 11.5 m, beyond range_max
  expectRange(scan, 4, 2.5);   // box_link
  expectRange(scan, 5, kInf);  // mover is 5 m above the plane
  expectRange(scan, 6, 3.5);   // cyl_link
  expectRange(scan, 7, kInf);

  const auto labels = labelsFor(scan.header.stamp);
  ASSERT_TRUE(labels);
  ASSERT_EQ(labels->labels.size(), 8u);
  auto name = [&](int beam) {
    const int l = labels->labels[beam];
    return l < 0 ? std::string("-") : labels->link_names.at(l);
  };
  EXPECT_EQ(name(0), "sphere_link");
  EXPECT_EQ(name(1), "-");
  EXPECT_EQ(name(2), "wall_link");
  EXPECT_EQ(name(3), "-");
  EXPECT_EQ(name(4), "box_link");
  EXPECT_EQ(name(6), "cyl_link");
}

TEST_F(NodeScanTest, MovingFramesChangeTheScan) {
  // The mover comes into the plane on the pi/4 beam: centre 1.5 sqrt(2) m away, radius 0.25 m.
  sensor_msgs::LaserScan scan = scanWith(0, 0, 0, 1.5, 1.5, 0);
  expectRange(scan, 5, 1.5 * std::sqrt(2.0) - 0.25);
  expectRange(scan, 4, 2.5);

  // The sensor moves 1 m along +x: the box is 1 m nearer, the sphere 1 m farther.
  scan = scanWith(1, 0, 0, 0, 0, 5);
  expectRange(scan, 4, 1.5);
  expectRange(scan, 0, 2.5);
  // The plate (y in [-3.1, -2.9], x in [-1, 1]) is seen edge-on from x = 1: the -pi/2 beam grazes
  // its end face at x = 1 exactly, so it may hit at 2.9 m; anything else would be wrong.
  ASSERT_EQ(scan.ranges.size(), 8u);
  EXPECT_TRUE(scan.ranges[2] == std::numeric_limits<float>::infinity() ||
              std::abs(scan.ranges[2] - 2.9) < kTolerance)
      << scan.ranges[2];

  // Turned by +pi/2: the beam at 0 rad now looks along +y at the cylinder, 4 - 0.5 - 0 m away.
  scan = scanWith(0, 0, M_PI / 2, 0, 0, 5);
  expectRange(scan, 4, 3.5);
  expectRange(scan, 2, 2.5);  // -pi/2 in the sensor frame is +x in the world: the box
}

TEST_F(NodeScanTest, SurfacesCloserThanRangeMinAreMinusInf) {
  // 0.1 m from the box face, below range_min = 0.2 m: REP 117 "too close" with the default policy.
  const sensor_msgs::LaserScan scan = scanWith(2.4, 0, 0, 0, 0, 5);
  expectRange(scan, 4, -kInf);
}

// ~intensity reflectivity, ~reflectivity {box_link: 0.5}, ~ignore_links [sphere_link]. Intensity is
// the link's reflectivity times the cosine of the incidence angle; the beams at 0 and pi/2 meet the
// box face and the cylinder head-on (cos 1), and the cylinder has the default reflectivity 1.
TEST_F(NodeScanTest, IntensityReflectivityAndIgnoredLinks) {
  const sensor_msgs::LaserScan plain = scanWith(0, 0, 0, 0, 0, 5);
  const sensor_msgs::LaserScan scan = tunedScanAfter(plain.header.stamp);
  ASSERT_EQ(scan.ranges.size(), 8u);
  ASSERT_EQ(scan.intensities.size(), 8u);
  expectRange(scan, 4, 2.5);
  EXPECT_NEAR(scan.intensities[4], 0.5, 1e-6);  // box_link
  expectRange(scan, 6, 3.5);
  EXPECT_NEAR(scan.intensities[6], 1.0, 1e-6);  // cyl_link
  expectRange(scan, 0, kInf);                   // sphere_link is ignored: nothing behind it
  EXPECT_EQ(scan.intensities[0], 0.0f);
  EXPECT_EQ(scan.intensities[1], 0.0f);  // no hit
}

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_scan");
  laser_raycast_test::World shared;
  laser_raycast_test::world = &shared;
  return RUN_ALL_TESTS();
}
