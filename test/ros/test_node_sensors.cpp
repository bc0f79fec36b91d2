// rostest node_sensors.test: four sensors from one node over one scene (test/data/
// sensors_room.urdf, a closed room with inner faces x = +-5, y = +-4, z = 0 and 4): a planar
// scanner against hand-computed ranges, a VLP-16 cloud whose every point is checked against the
// room's planes, a rotating scanner moving at 1 m/s away from a wall, a sensor nobody subscribes to
// (not cast), the diagnostics, and a live reconfiguration taking effect from the next scan.
#include <diagnostic_msgs/DiagnosticArray.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include <Eigen/Geometry>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "scan_access.h"

namespace laser_raycast_test {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Ranges are floats: 1e-7 relative, well below this at 10 m.
constexpr double kTolerance = 1e-4;  // m
// The spinner's path (node_sensors.test): x = -3 + v (t - t0) along a 6 s ramp, then again.
constexpr double kSpeed = 1.0;  // m/s
constexpr double kRamp = 6.0;   // s

geometry_msgs::TransformStamped transform(const ros::Time& stamp, const std::string& child,
                                          const Eigen::Vector3d& t, double yaw) {
  geometry_msgs::TransformStamped m;
  m.header.stamp = stamp;
  m.header.frame_id = "world";
  m.child_frame_id = child;
  m.transform.translation.x = t.x();
  m.transform.translation.y = t.y();
  m.transform.translation.z = t.z();
  m.transform.rotation.z = std::sin(yaw / 2);
  m.transform.rotation.w = std::cos(yaw / 2);
  return m;
}

// The distance from p (inside the room) along unit direction d to the room's inner faces.
double roomDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& d) {
  const Eigen::Vector3d lo(-5, -4, 0), hi(5, 4, 4);
  double t = kInf;
  for (int axis = 0; axis < 3; ++axis) {
    if (d[axis] > 0) t = std::min(t, (hi[axis] - p[axis]) / d[axis]);
    if (d[axis] < 0) t = std::min(t, (lo[axis] - p[axis]) / d[axis]);
  }
  return t;
}

// The sensor poses and what the node publishes, recorded from the spinner's threads.
class Rig {
 public:
  const Eigen::Vector3d front{0, 0, 1}, vlp{0.5, -0.3, 1.2};
  const double vlp_yaw = 0.3;

  Rig() {
    start_ = ros::Time::now();
    const ros::Time now = ros::Time::now();
    statics_.sendTransform({transform(now, "front", front, 0), transform(now, "vlp", vlp, vlp_yaw),
                            transform(now, "idle", front, 0)});
    front_sub_ = nh_.subscribe("/front/scan", 100, &Rig::onFront, this);
    vlp_sub_ = nh_.subscribe("/vlp/points", 5, &Rig::onVlp, this);
    spinner_sub_ = nh_.subscribe("/spinner/scan", 20, &Rig::onSpinner, this);
    diagnostics_sub_ = nh_.subscribe("/diagnostics", 20, &Rig::onDiagnostics, this);
    timer_ = nh_.createTimer(ros::Duration(0.01), &Rig::publishSpinner, this);
  }

  // The spinner's x at time t (its y is 0, its height 1 m, no rotation).
  double spinnerX(const ros::Time& t) const {
    return -3 + kSpeed * std::fmod((t - start_).toSec(), kRamp);
  }
  // Whether [from, to] lies within one ramp of the path, away from its ends (the TF samples
  // around a jump are interpolated across it).
  bool withinOneRamp(const ros::Time& from, const ros::Time& to) const {
    const double a = (from - start_).toSec() - 0.05, b = (to - start_).toSec() + 0.05;
    return a > 0 && std::floor(a / kRamp) == std::floor(b / kRamp);
  }

  // Waits (wall time) for the first message in `slot` satisfying ok; nullptr after `seconds`.
  template <class M, class F>
  typename M::ConstPtr waitFor(std::vector<typename M::ConstPtr>* slot, F ok, double seconds) {
    const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(seconds);
    std::size_t seen = 0;
    while (ros::ok() && ros::WallTime::now() < give_up) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        for (; seen < slot->size(); ++seen) {
          if (ok(*(*slot)[seen])) return (*slot)[seen];
        }
      }
      ros::WallDuration(0.01).sleep();
    }
    return nullptr;
  }

  std::vector<sensor_msgs::LaserScan::ConstPtr> front_scans, spinner_scans;
  std::vector<sensor_msgs::PointCloud2::ConstPtr> clouds;
  std::vector<diagnostic_msgs::DiagnosticArray::ConstPtr> diagnostics;

 private:
  template <class M>
  void store(std::vector<M>* slot, const M& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    slot->push_back(m);
  }
  void onFront(const sensor_msgs::LaserScan::ConstPtr& m) { store(&front_scans, m); }
  void onSpinner(const sensor_msgs::LaserScan::ConstPtr& m) { store(&spinner_scans, m); }
  void onVlp(const sensor_msgs::PointCloud2::ConstPtr& m) { store(&clouds, m); }
  void onDiagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
    store(&diagnostics, m);
  }
  void publishSpinner(const ros::TimerEvent&) {
    const ros::Time now = ros::Time::now();
    broadcaster_.sendTransform(transform(now, "spinner", {spinnerX(now), 0, 1}, 0));
  }

  ros::NodeHandle nh_;
  ros::Time start_;
  tf2_ros::StaticTransformBroadcaster statics_;
  tf2_ros::TransformBroadcaster broadcaster_;
  ros::Subscriber front_sub_, vlp_sub_, spinner_sub_, diagnostics_sub_;
  ros::Timer timer_;
  std::mutex mutex_;
};

Rig* rig = nullptr;

// "front": 8 beams from -pi by pi/4, at (0, 0, 1): the walls 5 m (x) and 4 m (y) away, the
// diagonals 4 sqrt(2) m (the y walls come first).
TEST(NodeSensors, APlanarSensorMatchesHandComputedRanges) {
  const auto scan = rig->waitFor<sensor_msgs::LaserScan>(
      &rig->front_scans, [](const sensor_msgs::LaserScan& s) { return s.ranges.size() == 8; },
      30.0);
  ASSERT_TRUE(scan) << "no scan from sensor front";
  EXPECT_EQ(scan->header.frame_id, "front");
  const double diagonal = 4 * std::sqrt(2.0);
  const double expected[8] = {5, diagonal, 4, diagonal, 5, diagonal, 4, diagonal};
  for (int i = 0; i < 8; ++i) EXPECT_NEAR(rangeOf(*scan, i), expected[i], kTolerance) << i;
}

// The VLP-16 preset: 16 rings from -15 to +15 deg, 1800 azimuths. In the closed room every beam
// returns, and every point must lie where its beam meets the room's faces.
TEST(NodeSensors, AVlp16CloudMatchesTheGeometry) {
  const auto cloud = rig->waitFor<sensor_msgs::PointCloud2>(
      &rig->clouds, [](const sensor_msgs::PointCloud2&) { return true; }, 30.0);
  ASSERT_TRUE(cloud) << "no cloud from sensor vlp";
  EXPECT_EQ(cloud->header.frame_id, "vlp");
  ASSERT_EQ(cloud->height, 1u);
  ASSERT_EQ(cloud->width, 16u * 1800u);
  std::vector<std::string> fields;
  for (const auto& f : cloud->fields) fields.push_back(f.name);
  EXPECT_EQ(fields, (std::vector<std::string>{"x", "y", "z", "intensity", "ring", "time"}));

  const Eigen::Isometry3d world_from_vlp =
      Eigen::Translation3d(rig->vlp) * Eigen::AngleAxisd(rig->vlp_yaw, Eigen::Vector3d::UnitZ());
  sensor_msgs::PointCloud2ConstIterator<float> x(*cloud, "x"), y(*cloud, "y"), z(*cloud, "z");
  sensor_msgs::PointCloud2ConstIterator<float> time(*cloud, "time");
  sensor_msgs::PointCloud2ConstIterator<std::uint16_t> ring(*cloud, "ring");
  int bad = 0;
  std::vector<int> per_ring(16, 0);
  for (; x != x.end(); ++x, ++y, ++z, ++time, ++ring) {
    const Eigen::Vector3d p(*x, *y, *z);
    const double r = p.norm();
    const Eigen::Vector3d dir = p / r;
    const double expected = roomDistance(rig->vlp, world_from_vlp.linear() * dir);
    const double elevation = std::asin(dir.z()) * 180 / M_PI;
    ASSERT_LT(*ring, 16);
    ++per_ring[*ring];
    const bool ok = std::abs(r - expected) < kTolerance &&
                    std::abs(elevation - (-15.0 + 2.0 * *ring)) < 1e-3 && *time == 0.0f;
    if (!ok && ++bad <= 5) {
      ADD_FAILURE() << "point " << p.transpose() << " (ring " << *ring << ", elevation "
                    << elevation << " deg, time " << *time << "): range " << r << ", the room at "
                    << expected;
    }
  }
  EXPECT_EQ(bad, 0);
  for (int r = 0; r < 16; ++r) EXPECT_EQ(per_ring[r], 1800) << "ring " << r;
}

// "spinner": 721 beams over the full turn, the head turning once in 0.1 s, beam i at stamp +
// i / 7200 s. It moves along +x at 1 m/s, away from the wall x = -5: beams 0 and 720 both look
// along -x, 0.1 s apart, so the wall is 0.1 m farther in the last beam than in the first.
TEST(NodeSensors, ARotatingScannerMovingAwayFromAWall) {
  const double dt = 0.1 / 720;
  const auto scan = rig->waitFor<sensor_msgs::LaserScan>(
      &rig->spinner_scans,
      [&](const sensor_msgs::LaserScan& s) {
        return s.ranges.size() == 721 &&
               rig->withinOneRamp(s.header.stamp, s.header.stamp + ros::Duration(0.1));
      },
      30.0);
  ASSERT_TRUE(scan) << "no spinner scan within one ramp of its path";
  EXPECT_NEAR(scan->time_increment, dt, 1e-9);
  EXPECT_NEAR(scan->scan_time, 0.1, 1e-7);
  const double first = rangeOf(*scan, 0), last = rangeOf(*scan, 720);
  std::cout << "rotating scanner at 1 m/s: the wall behind is " << first << " m away in the first "
            << "beam, " << last << " m in the last: " << last - first << " m apart\n";
  RecordProperty("rotating_last_minus_first_beam_m", std::to_string(last - first));
  EXPECT_NEAR(last - first, kSpeed * 720 * dt, 0.005);
  // And every beam on that wall, each at its own time.
  int on_wall = 0;
  for (int i = 0; i <= 720; ++i) {
    const double angle = -M_PI + i * M_PI / 360;
    const double x = rig->spinnerX(scan->header.stamp + ros::Duration(i * dt));
    const double to_wall = (x + 5) / -std::cos(angle);
    if (std::cos(angle) >= 0 || std::abs(to_wall * std::sin(angle)) > 3.9) continue;
    ++on_wall;
    EXPECT_NEAR(rangeOf(*scan, i), to_wall, 1e-3) << "beam " << i;
  }
  EXPECT_GT(on_wall, 100);
}

// The status whose name ("<node>: <task>") ends in `suffix`, or nullptr.
const diagnostic_msgs::DiagnosticStatus* statusIn(const diagnostic_msgs::DiagnosticArray& array,
                                                  const std::string& suffix) {
  for (const auto& s : array.status) {
    if (s.name.size() >= suffix.size() &&
        s.name.compare(s.name.size() - suffix.size(), suffix.size(), suffix) == 0) {
      return &s;
    }
  }
  return nullptr;
}

// The status of `name` in the newest diagnostics that have it.
const diagnostic_msgs::DiagnosticStatus* findStatus(
    const std::vector<diagnostic_msgs::DiagnosticArray::ConstPtr>& arrays,
    const std::string& suffix) {
  for (auto a = arrays.rbegin(); a != arrays.rend(); ++a) {
    if (const auto* s = statusIn(**a, suffix)) return s;
  }
  return nullptr;
}

std::map<std::string, std::string> values(const diagnostic_msgs::DiagnosticStatus& s) {
  std::map<std::string, std::string> out;
  for (const auto& kv : s.values) out[kv.key] = kv.value;
  return out;
}

TEST(NodeSensors, DiagnosticsPerSensorAndTheIdleOneIsNotCast) {
  // Wait until the front sensor has published in two reports.
  const auto array = rig->waitFor<diagnostic_msgs::DiagnosticArray>(
      &rig->diagnostics,
      [](const diagnostic_msgs::DiagnosticArray& a) {
        for (const auto& s : a.status) {
          if (s.name.find("front scans") != std::string::npos) {
            for (const auto& kv : s.values) {
              if (kv.key == "Scans published" && kv.value != "0") return true;
            }
          }
        }
        return false;
      },
      30.0);
  ASSERT_TRUE(array) << "no diagnostics with front's scans";
  const std::vector<diagnostic_msgs::DiagnosticArray::ConstPtr> arrays = {array};
  for (const std::string sensor : {"front", "vlp", "spinner", "idle"}) {
    const auto* rate = findStatus(arrays, sensor + " scan rate");
    const auto* scans = findStatus(arrays, sensor + " scans");
    ASSERT_TRUE(rate && scans) << "no diagnostics for sensor " << sensor;
    const auto r = values(*rate), s = values(*scans);
    for (const char* key : {"Actual frequency (Hz)", "Target frequency (Hz)", "Events in window"}) {
      EXPECT_TRUE(r.count(key)) << sensor << ": " << key;
    }
    for (const char* key : {"Cast time of the last scan (ms)", "Beams hit in the last scan (share)",
                            "TF look-up failures", "Scans skipped: no sensor transform",
                            "Scans skipped: pose topic stale or non-finite"}) {
      EXPECT_TRUE(s.count(key)) << sensor << ": " << key;
    }
  }
  EXPECT_EQ(values(*findStatus(arrays, "front scan rate"))["Target frequency (Hz)"], "20");
  const auto* idle = findStatus(arrays, "idle scan rate");
  EXPECT_EQ(idle->message, "not cast: nobody subscribes");
  EXPECT_EQ(values(*idle)["Events since startup"], "0");
}

// A diagnostics value as a number (NaN with a failure if absent).
double number(const diagnostic_msgs::DiagnosticStatus& s, const std::string& key) {
  for (const auto& kv : s.values) {
    if (kv.key == key) return std::stod(kv.value);
  }
  ADD_FAILURE() << s.name << ": no '" << key << "'";
  return std::numeric_limits<double>::quiet_NaN();
}

// The sensors that are cast (someone subscribes), in the closed room.
const std::vector<std::string> kCast = {"front", "vlp", "spinner"};

// Once the diagnostics' rate window (5 s) is full, each cast sensor achieves its rate within 10 %,
// and every beam hits (they face the room's walls all round: share 1). Front's transform is
// static: once it publishes, none of its look-ups fails.
TEST(NodeSensors, DiagnosticsShowTheRatesMetAndEveryBeamHit) {
  const auto full = [](const diagnostic_msgs::DiagnosticArray& a) {
    for (const std::string& sensor : kCast) {
      const auto* rate = statusIn(a, sensor + " scan rate");
      if (!rate) return false;
      for (const auto& kv : rate->values) {
        if (kv.key == "Duration of window (s)" && std::stod(kv.value) < 4.9) return false;
      }
    }
    return true;
  };
  const auto array = rig->waitFor<diagnostic_msgs::DiagnosticArray>(&rig->diagnostics, full, 60.0);
  ASSERT_TRUE(array) << "no diagnostics with a full rate window for every cast sensor";
  for (const std::string& sensor : kCast) {
    const auto* rate = statusIn(*array, sensor + " scan rate");
    const auto* scans = statusIn(*array, sensor + " scans");
    ASSERT_TRUE(rate && scans) << sensor;
    const double actual = number(*rate, "Actual frequency (Hz)");
    const double target = number(*rate, "Target frequency (Hz)");
    std::cout << sensor << ": " << actual << " Hz of " << target << " Hz over "
              << number(*rate, "Duration of window (s)") << " s; share of beams hit "
              << number(*scans, "Beams hit in the last scan (share)") << "\n";
    EXPECT_NEAR(actual, target, 0.1 * target) << sensor;
    EXPECT_EQ(rate->level, diagnostic_msgs::DiagnosticStatus::OK)
        << sensor << ": " << rate->message;
    EXPECT_NEAR(number(*scans, "Beams hit in the last scan (share)"), 1.0, 1e-9) << sensor;
  }
  EXPECT_EQ(number(*statusIn(*array, "front scan rate"), "Target frequency (Hz)"), 20.0);

  // Two reports later, front has no new failed look-up.
  const double failures = number(*statusIn(*array, "front scans"), "TF look-up failures");
  const ros::Time later = array->header.stamp + ros::Duration(2.0);
  const auto next = rig->waitFor<diagnostic_msgs::DiagnosticArray>(
      &rig->diagnostics,
      [&](const diagnostic_msgs::DiagnosticArray& a) { return a.header.stamp >= later; }, 10.0);
  ASSERT_TRUE(next) << "no diagnostics 2 s later";
  const auto* front_then = statusIn(*next, "front scans");
  ASSERT_TRUE(front_then);
  EXPECT_EQ(number(*front_then, "TF look-up failures"), failures);
}

// Sets front's range_max through dynamic_reconfigure; returns the values the node replied with.
std::map<std::string, double> setFront(const std::string& name, double value) {
  dynamic_reconfigure::Reconfigure srv;
  dynamic_reconfigure::DoubleParameter p;
  p.name = name;
  p.value = value;
  srv.request.config.doubles.push_back(p);
  EXPECT_TRUE(ros::service::call("/laser_raycast/front/set_parameters", srv));
  std::map<std::string, double> out;
  for (const auto& d : srv.response.config.doubles) out[d.name] = d.value;
  return out;
}

TEST(NodeSensors, AReconfigureAppliesToTheNextScan) {
  ASSERT_TRUE(ros::service::waitForService("/laser_raycast/front/set_parameters", 30000));
  // range_max 4.5 m: the x walls (5 m, beams 0 and 4) drop out, the y walls (4 m) stay.
  EXPECT_EQ(setFront("range_max", 4.5)["range_max"], 4.5);
  const ros::Time next = ros::Time::now() + ros::Duration(1.0 / 20);  // one period later
  auto scan = rig->waitFor<sensor_msgs::LaserScan>(
      &rig->front_scans, [&](const sensor_msgs::LaserScan& s) { return s.header.stamp >= next; },
      10.0);
  ASSERT_TRUE(scan) << "no scan after the reconfiguration";
  EXPECT_FLOAT_EQ(scan->range_max, 4.5f);
  EXPECT_EQ(rangeOf(*scan, 4), kInf);
  EXPECT_NEAR(rangeOf(*scan, 2), 4.0, kTolerance);

  // A value the sensor refuses (range_min above range_max) leaves the previous ones.
  const auto refused = setFront("range_min", 6.0);
  EXPECT_EQ(refused.at("range_min"), 0.0);
  EXPECT_EQ(refused.at("range_max"), 4.5);

  EXPECT_EQ(setFront("range_max", 10.0)["range_max"], 10.0);
  const ros::Time back = ros::Time::now() + ros::Duration(1.0 / 20);
  scan = rig->waitFor<sensor_msgs::LaserScan>(
      &rig->front_scans, [&](const sensor_msgs::LaserScan& s) { return s.header.stamp >= back; },
      10.0);
  ASSERT_TRUE(scan) << "no scan after the second reconfiguration";
  EXPECT_NEAR(rangeOf(*scan, 4), 5.0, kTolerance);
}

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_sensors");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  laser_raycast_test::Rig shared;
  laser_raycast_test::rig = &shared;
  return RUN_ALL_TESTS();
}
