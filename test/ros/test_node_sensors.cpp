// rostest node_sensors.test: five sensors from one node over one scene (test/data/
// sensors_room.urdf, a closed room with inner faces x = +-5, y = +-4, z = 0 and 4): a planar
// scanner against hand-computed ranges, a VLP-16 cloud whose every point is checked against the
// room's planes, a rotating scanner moving at 1 m/s away from a wall, a rotating 3D lidar's
// organized cloud (per-column times, NaN points for no return), a sensor nobody subscribes to (not
// cast), the diagnostics, and live reconfiguration taking effect from the next scan.
#include <dynamic_reconfigure/Reconfigure.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "scan_access.h"
#include "sensors_rig.h"
#include "vlp16_manual.h"

namespace laser_raycast_test {
namespace {

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

// The VLP-16 preset: its lasers as the user manual fires them, 16 a firing sequence 2.304 us apart,
// a sequence every 55.296 us, 1808 sequences in the 0.1 s turn (vlp16Firing). Cast at once (sweep
// instant), each point keeps its firing time and lies at the head's azimuth then (pi at the stamp,
// turning clockwise). In the closed room every beam returns, and every point must lie where its
// beam meets the room's faces.
TEST(NodeSensors, AVlp16CloudMatchesTheGeometryAndTheFiringTimes) {
  const auto cloud = rig->waitFor<sensor_msgs::PointCloud2>(
      &rig->clouds, [](const sensor_msgs::PointCloud2&) { return true; }, 30.0);
  ASSERT_TRUE(cloud) << "no cloud from sensor vlp";
  EXPECT_EQ(cloud->header.frame_id, "vlp");
  const int sequences = 1808;
  ASSERT_EQ(cloud->height, 1u);
  ASSERT_EQ(cloud->width, 16u * sequences);
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
  std::set<std::pair<int, int>> fired;  // (sequence, laser id): each once
  for (; x != x.end(); ++x, ++y, ++z, ++time, ++ring) {
    const Eigen::Vector3d p(*x, *y, *z);
    const double r = p.norm();
    const Eigen::Vector3d dir = p / r;
    const double expected = roomDistance(rig->vlp, world_from_vlp.linear() * dir);
    const double elevation = std::asin(dir.z()) * 180 / M_PI;
    ASSERT_LT(*ring, 16);
    ++per_ring[*ring];
    const Vlp16Firing firing = vlp16Firing(*ring, *time, 0.1);
    fired.insert({static_cast<int>(firing.sequence), firing.id});
    const double azimuth_off =
        std::remainder(std::atan2(dir.y(), dir.x()) - firing.azimuth, 2 * M_PI);
    const bool ok = std::abs(r - expected) < kTolerance &&
                    std::abs(elevation - (-15.0 + 2.0 * *ring)) < 1e-3 && firing.sequence >= 0 &&
                    firing.sequence < sequences && std::abs(*time - firing.time) < 1e-8 &&
                    std::abs(azimuth_off) < 2e-6;
    if (!ok && ++bad <= 5) {
      ADD_FAILURE() << "point " << p.transpose() << " (ring " << *ring << ", elevation "
                    << elevation << " deg, time " << *time << ", " << azimuth_off
                    << " rad from the head's azimuth): range " << r << ", the room at " << expected;
    }
  }
  EXPECT_EQ(bad, 0);
  EXPECT_EQ(fired.size(), 16u * sequences);
  for (int r = 0; r < 16; ++r) EXPECT_EQ(per_ring[r], sequences) << "ring " << r;
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

// "sweep3d" (node_sensors.test): rings at -0.3, 0 and 0.3 rad (given unsorted), 361 azimuths over
// the full turn, range_max 4.5 m, rotating at 10 Hz: the head turns in 0.1 s, so column c is taken
// c * time_increment after the stamp, time_increment = (2 pi / 360) * 0.1 s / (2 pi).
constexpr double kSweepElevations[3] = {-0.3, 0.0, 0.3};  // ring 0 lowest
constexpr int kSweepAzimuths = 361;
constexpr double kSweepRangeMax = 4.5;             // m
constexpr double kSweepTimeIncrement = 0.1 / 360;  // s

// Beam (ring, column) of sweep3d: its direction in the sensor frame, and the room's distance along
// it from where the rig put the sensor.
Eigen::Vector3d sweepDirection(int ring, int column) {
  const double e = kSweepElevations[ring], a = -M_PI + column * (2 * M_PI / 360);
  return {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
}
double sweepDistance(int ring, int column) {
  const Eigen::AngleAxisd yaw(rig->sweep3d_yaw, Eigen::Vector3d::UnitZ());
  return roomDistance(rig->sweep3d, yaw * sweepDirection(ring, column));
}
// How many of sweep3d's beams meet the room within range_max.
int sweepReturns() {
  int n = 0;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < kSweepAzimuths; ++c) n += sweepDistance(r, c) <= kSweepRangeMax;
  }
  return n;
}

// The organized cloud of a rotating 3D lidar: every beam a point, row r ring r, each point's time
// that of its column; a beam whose wall is beyond range_max is a NaN point, so is_dense is false.
TEST(NodeSensors, ARotatingOrganizedCloudHasColumnTimesAndNanForNoReturn) {
  const auto cloud = rig->waitFor<sensor_msgs::PointCloud2>(
      &rig->sweep3d_clouds, [](const sensor_msgs::PointCloud2&) { return true; }, 30.0);
  ASSERT_TRUE(cloud) << "no cloud from sensor sweep3d";
  EXPECT_EQ(cloud->header.frame_id, "sweep3d");
  ASSERT_EQ(cloud->height, 3u);
  ASSERT_EQ(cloud->width, static_cast<std::uint32_t>(kSweepAzimuths));
  ASSERT_EQ(cloud->data.size(), std::size_t{cloud->row_step} * cloud->height);
  EXPECT_FALSE(cloud->is_dense);
  sensor_msgs::PointCloud2ConstIterator<float> x(*cloud, "x"), y(*cloud, "y"), z(*cloud, "z");
  sensor_msgs::PointCloud2ConstIterator<float> intensity(*cloud, "intensity"), time(*cloud, "time");
  sensor_msgs::PointCloud2ConstIterator<std::uint16_t> ring(*cloud, "ring");
  int bad = 0, nan = 0, valid = 0;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < kSweepAzimuths; ++c, ++x, ++y, ++z, ++intensity, ++time, ++ring) {
      const double expected = sweepDistance(r, c);
      const Eigen::Vector3d p(*x, *y, *z);
      bool ok = *ring == r && std::abs(*time - c * kSweepTimeIncrement) <= 1e-7;
      if (expected > kSweepRangeMax) {
        ++nan;
        ok = ok && std::isnan(*x) && std::isnan(*y) && std::isnan(*z) && std::isnan(*intensity);
      } else {
        ++valid;
        ok = ok && (p - expected * sweepDirection(r, c)).norm() < kTolerance;
      }
      if (!ok && ++bad <= 5) {
        ADD_FAILURE() << "ring " << r << " column " << c << ": point " << p.transpose()
                      << ", ring field " << *ring << ", time " << *time << " (expected "
                      << c * kSweepTimeIncrement << " s); the room at " << expected << " m";
      }
    }
  }
  EXPECT_EQ(bad, 0);
  std::cout << "sweep3d: " << valid << " returns, " << nan << " NaN points of "
            << 3 * kSweepAzimuths << "; last column at " << kSweepTimeIncrement * 360 << " s\n";
  EXPECT_GT(nan, 100);
  EXPECT_GT(valid, 100);
  EXPECT_EQ(valid, sweepReturns());
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
  for (const std::string sensor : {"front", "vlp", "spinner", "sweep3d", "idle"}) {
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

// The sensors that are cast (someone subscribes), in the closed room.
const std::vector<std::string> kCast = {"front", "vlp", "spinner", "sweep3d"};

// Once the diagnostics' rate window (5 s) is full, each cast sensor achieves its rate within 10 %,
// and every beam hits (they face the room's walls all round: share 1) except sweep3d's beyond its
// range_max of 4.5 m. Front's transform is static: once it publishes, none of its look-ups fails.
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
    const double share = sensor == "sweep3d" ? sweepReturns() / (3.0 * kSweepAzimuths) : 1.0;
    // Printed with 6 significant digits; one beam of sweep3d's is 1 / 1083.
    EXPECT_NEAR(number(*scans, "Beams hit in the last scan (share)"), share, 1e-5) << sensor;
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

// The scan times of one second that need link poses, from the sensors' configuration
// (node_sensors.test): front's 20 Hz stamps (vlp's 10 Hz ones among them), and the sample times of
// the rotating spinner and sweep3d at 10 Hz: from each stamp to its last beam 0.1 s later, at most
// 10 ms apart (Sensor::kSweepSampleSpacing), i.e. stamp + 0, 10, ..., 100 ms.
std::size_t scanTimesPerSecond() {
  std::set<std::int64_t> ms;
  for (int k = 0; k < 20; ++k) ms.insert(50 * k);
  for (int k = 0; k < 10; ++k) {
    for (int j = 0; j <= 10; ++j) ms.insert((100 * k + 10 * j) % 1000);
  }
  return ms.size();
}

// The link look-ups of one second for a static link frame (this room's only one, "world", is the
// fixed frame itself): a rotating job (spinner and sweep3d share one, 10 a second) looks a static
// frame up once for all its new sample times. Front's stamps at 50 ms past a sweep's stamp add one
// each (10 a second) when front's job is cast before the sweep that has that time among its
// samples, and none when the sweep comes first: which one does depends on when their transforms
// come. So between 10 and 20 a second; a look-up per time would make 100.
constexpr double kStaticLookUpsMin = 10, kStaticLookUpsMax = 20;

// The link poses are looked up once per scan time for every sensor due then: an instantaneous and
// a rotating sensor at one stamp share it, and the 20 Hz stamps inside a sweep; a static frame once
// per rotating job. The node counts its link look-ups ("link poses"); over 5 s they must come to
// the count above, not more (a look-up per time of the sweeps would make 100 a second here, one per
// job and time 130).
TEST(NodeSensors, LinkPosesAreLookedUpOncePerScanTime) {
  const auto has = [](const diagnostic_msgs::DiagnosticArray& a) {
    return statusIn(a, "link poses") != nullptr;
  };
  const ros::Time now = ros::Time::now();  // every sensor casts by now (the tests above)
  const auto first = rig->waitFor<diagnostic_msgs::DiagnosticArray>(
      &rig->diagnostics,
      [&](const diagnostic_msgs::DiagnosticArray& a) { return has(a) && a.header.stamp >= now; },
      30.0);
  ASSERT_TRUE(first) << "no 'link poses' diagnostics";
  const ros::Time later = first->header.stamp + ros::Duration(5.0);
  const auto last = rig->waitFor<diagnostic_msgs::DiagnosticArray>(
      &rig->diagnostics,
      [&](const diagnostic_msgs::DiagnosticArray& a) { return has(a) && a.header.stamp >= later; },
      20.0);
  ASSERT_TRUE(last) << "no 'link poses' diagnostics 5 s later";
  const double frames = number(*statusIn(*last, "link poses"), "Link frames");
  const double lookups = number(*statusIn(*last, "link poses"), "Link pose look-ups") -
                         number(*statusIn(*first, "link poses"), "Link pose look-ups");
  const double seconds = (last->header.stamp - first->header.stamp).toSec();

  std::cout << "link pose look-ups: " << lookups / seconds << " a second for " << frames
            << " link frames and " << scanTimesPerSecond() << " scan times a second\n";
  EXPECT_EQ(frames, 1.0);  // the room's links are merged into its root, "world"
  EXPECT_EQ(scanTimesPerSecond(), 100u);
  EXPECT_GE(lookups / seconds, 0.95 * frames * kStaticLookUpsMin);
  EXPECT_LE(lookups / seconds, 1.05 * frames * kStaticLookUpsMax);
}

// Sets live parameters of a sensor (front unless named) through dynamic_reconfigure; returns the
// configuration the node replied with.
dynamic_reconfigure::Config reconfigureFront(const dynamic_reconfigure::Config& change,
                                             const std::string& sensor = "front") {
  dynamic_reconfigure::Reconfigure srv;
  srv.request.config = change;
  EXPECT_TRUE(ros::service::call("/laser_raycast/" + sensor + "/set_parameters", srv));
  return srv.response.config;
}

// A double parameter of front (or the sensor named); returns the doubles the node replied with.
std::map<std::string, double> setFront(const std::string& name, double value,
                                       const std::string& sensor = "front") {
  dynamic_reconfigure::Config change;
  dynamic_reconfigure::DoubleParameter p;
  p.name = name;
  p.value = value;
  change.doubles.push_back(p);
  std::map<std::string, double> out;
  for (const auto& d : reconfigureFront(change, sensor).doubles) out[d.name] = d.value;
  return out;
}

// A string parameter of front; returns the value of that parameter the node replied with.
std::string setFront(const std::string& name, const std::string& value) {
  dynamic_reconfigure::Config change;
  dynamic_reconfigure::StrParameter p;
  p.name = name;
  p.value = value;
  change.strs.push_back(p);
  for (const auto& v : reconfigureFront(change).strs) {
    if (v.name == name) return v.value;
  }
  return "<not in the reply>";
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

// front's scans stamped after `after`: `count` of them, consecutive, `period` apart on the grid
// of that period, each saying scan_time = period.
void expectScansEvery(const ros::Time& after, double period, std::size_t count) {
  const auto scans = rig->waitForSome<sensor_msgs::LaserScan>(
      &rig->front_scans, [&](const sensor_msgs::LaserScan& s) { return s.header.stamp > after; },
      count, 10 + count * period);
  ASSERT_EQ(scans.size(), count) << "scans after t = " << after << " at " << period << " s";
  const auto grid = static_cast<std::uint64_t>(std::llround(period * 1e9));
  for (std::size_t i = 0; i < count; ++i) {
    EXPECT_EQ(scans[i]->header.stamp.toNSec() % grid, 0u) << scans[i]->header.stamp;
    EXPECT_NEAR(scans[i]->scan_time, period, 1e-6);
    if (i > 0) {
      EXPECT_NEAR((scans[i]->header.stamp - scans[i - 1]->header.stamp).toSec(), period, 1e-6)
          << "scan " << i << " at t = " << scans[i]->header.stamp;
    }
  }
}

// A live rate restarts the timer on the new period's grid: from 20 Hz to 5 Hz and back.
TEST(NodeSensors, ALiveRateChangesThePeriod) {
  ASSERT_TRUE(ros::service::waitForService("/laser_raycast/front/set_parameters", 30000));
  // Scans queued before a change are stamped at most one old period after it.
  ros::Time changed = ros::Time::now();
  EXPECT_EQ(setFront("rate", 5.0)["rate"], 5.0);
  expectScansEvery(changed + ros::Duration(1.0 / 20), 1.0 / 5, 4);
  changed = ros::Time::now();
  EXPECT_EQ(setFront("rate", 20.0)["rate"], 20.0);
  expectScansEvery(changed + ros::Duration(1.0 / 5), 1.0 / 20, 6);
}

// Intensity switched on while the node runs: from the next scan, the links' reflectivity (1, the
// default) times |cos| of the incidence angle: 1 for the beams along the room's axes, which meet
// the walls head-on, cos 45 deg for the diagonals (on the y walls, 4 m being nearer than 5).
// Switched off: no intensities.
TEST(NodeSensors, ALiveIntensityToggle) {
  ASSERT_TRUE(ros::service::waitForService("/laser_raycast/front/set_parameters", 30000));
  EXPECT_EQ(setFront("intensity", "reflectivity"), "reflectivity");
  const ros::Time on = ros::Time::now() + ros::Duration(1.0 / 20);
  auto scan = rig->waitFor<sensor_msgs::LaserScan>(
      &rig->front_scans, [&](const sensor_msgs::LaserScan& s) { return s.header.stamp >= on; },
      10.0);
  ASSERT_TRUE(scan) << "no scan after switching intensity on";
  ASSERT_EQ(scan->intensities.size(), 8u);
  for (int i = 0; i < 8; ++i) {
    EXPECT_NEAR(scan->intensities[i], i % 2 == 0 ? 1.0 : std::sqrt(0.5), 1e-6) << "beam " << i;
  }
  EXPECT_NEAR(rangeOf(*scan, 0), 5.0, kTolerance);  // the ranges stay

  EXPECT_EQ(setFront("intensity", "off"), "off");
  const ros::Time off = ros::Time::now() + ros::Duration(1.0 / 20);
  scan = rig->waitFor<sensor_msgs::LaserScan>(
      &rig->front_scans, [&](const sensor_msgs::LaserScan& s) { return s.header.stamp >= off; },
      10.0);
  ASSERT_TRUE(scan) << "no scan after switching intensity off";
  EXPECT_TRUE(scan->intensities.empty());
}

// The VLP-16 preset's turn follows its rate: set live to 20 Hz, the next clouds fire 904
// sequences in the 0.05 s turn, each point at the head's azimuth at its firing time in that
// turn; back at 10 Hz, 1808 again.
TEST(NodeSensors, ALiveRateTurnsTheVlp16sHeadAtTheNewRate) {
  ASSERT_TRUE(ros::service::waitForService("/laser_raycast/vlp/set_parameters", 30000));
  for (const double rate : {20.0, 10.0}) {
    EXPECT_EQ(setFront("rate", rate, "vlp")["rate"], rate);
    const double turn = 1 / rate;
    const int sequences = static_cast<int>(turn / 55.296e-6);
    // Clouds cast before the change may still arrive: the first of the new turn's size after it.
    const ros::Time after = ros::Time::now() + ros::Duration(0.1);
    const auto cloud = rig->waitFor<sensor_msgs::PointCloud2>(
        &rig->clouds,
        [&](const sensor_msgs::PointCloud2& c) {
          return c.header.stamp >= after && c.width == 16u * sequences;
        },
        10.0);
    ASSERT_TRUE(cloud) << "no cloud of " << sequences << " sequences at " << rate << " Hz";
    sensor_msgs::PointCloud2ConstIterator<float> x(*cloud, "x"), y(*cloud, "y");
    sensor_msgs::PointCloud2ConstIterator<float> time(*cloud, "time");
    sensor_msgs::PointCloud2ConstIterator<std::uint16_t> ring(*cloud, "ring");
    int bad = 0;
    double last = 0;
    for (; x != x.end(); ++x, ++y, ++time, ++ring) {
      const Vlp16Firing firing = vlp16Firing(*ring, *time, turn);
      const double off = std::remainder(std::atan2(*y, *x) - firing.azimuth, 2 * M_PI);
      last = std::max(last, static_cast<double>(*time));
      if (!(std::abs(off) < 2e-6 && std::abs(*time - firing.time) < 1e-8) && ++bad <= 5) {
        ADD_FAILURE() << "at " << rate << " Hz: a point of time " << *time << " lies " << off
                      << " rad from the head's azimuth";
      }
    }
    EXPECT_EQ(bad, 0);
    EXPECT_LT(last, turn);
    EXPECT_GT(last, turn - 2 * 55.296e-6);
  }
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
