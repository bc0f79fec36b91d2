// simulate_bag, run as a user would, on bags the test writes with rosbag's C++ API: the robot of
// test/support/bag_drive.h driving through the closed room, its transforms (and a pose topic) at
// 100 Hz. Every range of every scan is checked against the room and the robot worked out by hand
// at the beam's own time; the stamps against the node's grid and the time the transforms cover;
// the output against itself on two threads; each bad input against its exit status and message.
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <laser_raycast/ScanLabels.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "bag_drive.h"
#include "run_command.h"
#include "sensors_room.h"
#include "temp_files.h"

namespace laser_raycast_test {
namespace {

const std::string kSource = LASER_RAYCAST_SOURCE_DIR;
// Not on any sensor's grid, so that the first scan of each is the grid's next time.
const ros::Time kStart(1000, 5000000);
// Ranges are floats: 1e-7 relative, well below this at 10 m.
constexpr double kTolerance = 1e-4;  // m
constexpr double kInf = std::numeric_limits<double>::infinity();

// What a bag holds.
struct BagSpec {
  double seconds = 3.0;  // of /tf, at 100 Hz, from kStart (both ends included)
  bool tf = true;
  double static_delay = 0;  // /tf_static this long after kStart
  bool with_bumper = true;  // /tf_static has the bumper's mount
  // /robot_pose: base_link in world at 100 Hz, this far (y) from where TF has it (0: none).
  double pose_offset = 0;
  // /tf received this long after its stamps (a loaded TF tree): a scan is then cast after the pose
  // topic's messages around its stamp have come, and takes its pose between them.
  double tf_delay = 0;
};

std::string writeDriveBag(const std::string& name, const BagSpec& spec) {
  const std::string path = (tempDir() / name).string();
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  Drive drive{kStart};
  if (spec.tf) {
    const ros::Time at = kStart + ros::Duration(spec.static_delay);
    tf2_msgs::TFMessage statics = staticTf(at);
    if (!spec.with_bumper) {
      statics.transforms.erase(statics.transforms.begin() + 1);  // mounts(): laser, bumper, lidar
    }
    bag.write("/tf_static", at, statics, latchedHeader<tf2_msgs::TFMessage>());
    for (int i = 0; i <= static_cast<int>(std::lround(spec.seconds * 100)); ++i) {
      const ros::Time t = kStart + ros::Duration(0.01 * i);
      bag.write("/tf", t + ros::Duration(spec.tf_delay), driveTf(drive, t));
    }
  }
  if (spec.pose_offset != 0 || !spec.tf) {
    for (int i = 0; i <= static_cast<int>(std::lround(spec.seconds * 100)); ++i) {
      const ros::Time t = kStart + ros::Duration(0.01 * i);
      Eigen::Isometry3d pose = drive.base(t);
      pose.translation().y() += spec.pose_offset;
      geometry_msgs::PoseStamped m;
      m.header.stamp = t;
      m.header.frame_id = "world";
      const geometry_msgs::TransformStamped tf = toMsg(pose, t, "world", "base_link");
      m.pose.position.x = tf.transform.translation.x;
      m.pose.position.y = tf.transform.translation.y;
      m.pose.position.z = tf.transform.translation.z;
      m.pose.orientation = tf.transform.rotation;
      bag.write("/robot_pose", t, m);
    }
  }
  bag.close();
  return path;
}

// simulate_bag_test.yaml with its package:// URIs made paths of the source tree (no
// ROS_PACKAGE_PATH needed), then `extra` lines.
std::string writeConfig(const std::string& name, const std::string& extra = "",
                        const std::string& file = "simulate_bag_test.yaml") {
  std::ifstream in(kSource + "/test/data/" + file);
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const std::string uri = "package://laser_raycast/";
  for (std::size_t at; (at = yaml.find(uri)) != std::string::npos;) {
    yaml.replace(at, uri.size(), kSource + "/");
  }
  return writeFile(name, yaml + extra);
}

struct ToolRun {
  int status = -1;
  std::string err;
};

ToolRun simulate(const std::string& args) {
  const std::string err_file = (tempDir() / "simulate_bag_stderr.txt").string();
  const CommandResult r =
      runCommand(std::string(SIMULATE_BAG_PATH) + " " + args + " 2>" + err_file);
  EXPECT_EQ(r.output, "") << "nothing on stdout";
  std::ifstream err(err_file);
  std::stringstream s;
  s << err.rdbuf();
  return ToolRun{r.status, s.str()};
}

ToolRun simulate(const std::string& in, const std::string& out, const std::string& config,
                 const std::string& more = "") {
  return simulate("--input " + in + " --output " + out + " --config " + config + " " + more);
}

std::string out(const std::string& name) { return (tempDir() / name).string(); }

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

const Mount& mount(const std::string& frame) {
  for (const Mount& m : mounts()) {
    if (m.frame == frame) return m;
  }
  throw std::invalid_argument(frame);
}

// The stamps the node's rules give a sensor of `period` over TF from `first` to `last`: every
// multiple of the period after `first` whose last beam (sweep s after it) is not after `last`.
std::vector<ros::Time> gridStamps(const ros::Time& first, const ros::Time& last, double period,
                                  double sweep) {
  const std::uint64_t p = ros::Duration(period).toNSec();
  std::vector<ros::Time> stamps;
  ros::Time t;
  for (t.fromNSec((first.toNSec() / p + 1) * p); t + ros::Duration(sweep) <= last;
       t += ros::Duration(period)) {
    stamps.push_back(t);
  }
  return stamps;
}

template <class M>
std::vector<ros::Time> stampsOf(const std::map<ros::Time, M>& messages) {
  std::vector<ros::Time> stamps;
  for (const auto& entry : messages) stamps.push_back(entry.first);
  return stamps;
}

// A planar scan's every beam against the room, from the sensor pose at the beam's own time.
void expectRoomScan(const Drive& drive, const sensor_msgs::LaserScan& scan, const Mount& m) {
  ASSERT_FALSE(scan.ranges.empty());
  for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
    const ros::Time t = scan.header.stamp + ros::Duration(i * double(scan.time_increment));
    const Eigen::Isometry3d sensor = drive.base(t) * m.pose();
    const double a = scan.angle_min + i * double(scan.angle_increment);
    const double d = roomDistance(sensor.translation(),
                                  sensor.linear() * Eigen::Vector3d(std::cos(a), std::sin(a), 0));
    const double expected = d <= scan.range_max ? d : kInf;
    if (std::isinf(expected)) {
      EXPECT_EQ(scan.ranges[i], expected) << "beam " << i << " at " << scan.header.stamp;
    } else {
      EXPECT_NEAR(scan.ranges[i], expected, kTolerance)
          << "beam " << i << " at " << scan.header.stamp;
    }
  }
}

// Which face of the room a beam from p along unit d meets (0: x = +-5, 1: y = +-4, 2: floor or
// ceiling), and how much farther the next face along it is.
struct RoomFace {
  int axis;
  double margin;
};

RoomFace roomFace(const Eigen::Vector3d& p, const Eigen::Vector3d& d) {
  const Eigen::Vector3d half(5, 4, 2), centre(0, 0, 2);
  double t[3];
  for (int axis = 0; axis < 3; ++axis) {
    const double face = centre[axis] + (d[axis] > 0 ? half[axis] : -half[axis]);
    t[axis] = d[axis] != 0 ? (face - p[axis]) / d[axis] : kInf;
  }
  const int axis = int(std::min_element(t, t + 3) - t);
  double next = kInf;
  for (int other = 0; other < 3; ++other) {
    if (other != axis) next = std::min(next, t[other]);
  }
  return RoomFace{axis, next - t[axis]};
}

class DrivingRobot : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    input_ = writeDriveBag("drive.bag", BagSpec());
    output_ = out("drive_out.bag");
    const ToolRun run = simulate(input_, output_, writeConfig("drive.yaml"));
    status_ = run.status;
    err_ = run.err;
  }

  void SetUp() override { ASSERT_EQ(status_, 0) << err_; }

  static std::string input_, output_, err_;
  static int status_;
  const Drive drive_{kStart};
  const ros::Time end_ = kStart + ros::Duration(3.0);
};

std::string DrivingRobot::input_, DrivingRobot::output_, DrivingRobot::err_;
int DrivingRobot::status_ = -1;

TEST_F(DrivingRobot, ScansAreStampedOnTheGridFromTheFirstTimeTheTransformsCoverToTheLast) {
  // front: 20 Hz, instantaneous; spin: 10 Hz, rotating over 0.1 s; rear: 10 Hz.
  const auto front = readBag<sensor_msgs::LaserScan>(output_, "/front/scan");
  const auto spin = readBag<sensor_msgs::LaserScan>(output_, "/spin/scan");
  const auto rear = readBag<sensor_msgs::LaserScan>(output_, "/rear/scan");
  const auto vlp = readBag<sensor_msgs::PointCloud2>(output_, "/vlp/points");
  EXPECT_EQ(stampsOf(front), gridStamps(kStart, end_, 0.05, 0));
  EXPECT_EQ(stampsOf(spin), gridStamps(kStart, end_, 0.1, 0.1));
  EXPECT_EQ(stampsOf(rear), gridStamps(kStart, end_, 0.1, 0));
  EXPECT_EQ(stampsOf(vlp), gridStamps(kStart, end_, 0.1, 1799 * 0.1 / 1800));
  EXPECT_EQ(front.size(), 60u);  // 1000.05 to 1003.00
  EXPECT_EQ(spin.size(), 29u);   // 1000.1 to 1002.9: the sweep from 1003.0 ends after the bag
  EXPECT_TRUE(contains(err_, "sensor 'front': 60 scans on /front/scan")) << err_;
  EXPECT_TRUE(contains(err_, "sensor 'spin': 29 scans on /spin/scan")) << err_;
  EXPECT_TRUE(contains(err_, "1 at the end not covered by TF")) << err_;
}

TEST_F(DrivingRobot, PlanarScansMatchTheRoomAtEachBeamsTime) {
  for (const auto& [stamp, scan] : readBag<sensor_msgs::LaserScan>(output_, "/front/scan")) {
    EXPECT_EQ(scan.header.frame_id, "laser");
    EXPECT_EQ(scan.time_increment, 0.0f);
    expectRoomScan(drive_, scan, mount("laser"));
  }
  for (const auto& [stamp, scan] : readBag<sensor_msgs::LaserScan>(output_, "/spin/scan")) {
    // One turn in 0.1 s over 359 steps of 2 pi / 359.
    EXPECT_FLOAT_EQ(scan.time_increment, 0.1f / 359);
    expectRoomScan(drive_, scan, mount("laser"));
  }
}

TEST_F(DrivingRobot, TheBumperScannerSeesTheMovingBody) {
  // The body's back face, 0.15 m ahead of the bumper's scanner, moves with it: the link's pose
  // from TF at each stamp puts it there.
  const auto scans = readBag<sensor_msgs::LaserScan>(output_, "/rear/scan");
  const auto labels = readBag<laser_raycast::ScanLabels>(output_, "/rear/scan_labels");
  ASSERT_EQ(scans.size(), labels.size());
  for (const auto& [stamp, scan] : scans) {
    const laser_raycast::ScanLabels& l = labels.at(stamp);
    ASSERT_EQ(l.labels.size(), scan.ranges.size());
    for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
      const double a = scan.angle_min + i * double(scan.angle_increment);
      EXPECT_NEAR(scan.ranges[i], 0.15 / std::cos(a), kTolerance) << "beam " << i;
      ASSERT_GE(l.labels[i], 0);
      EXPECT_EQ(l.link_names[l.labels[i]], "base_link");
    }
  }
}

TEST_F(DrivingRobot, CloudPointsLieOnTheRoomAtTheirOwnTimeWithTheirIntensity) {
  const Mount& m = mount("lidar");
  std::size_t points = 0, faced = 0;
  for (const auto& [stamp, cloud] : readBag<sensor_msgs::PointCloud2>(output_, "/vlp/points")) {
    // The preset's 16 lasers a ring each, 1808 firing sequences a turn (each its own time).
    ASSERT_EQ(cloud.height, 16u);
    ASSERT_EQ(cloud.width, 1808u);
    sensor_msgs::PointCloud2ConstIterator<float> x(cloud, "x"), time(cloud, "time"),
        intensity(cloud, "intensity");
    for (; x != x.end(); ++x, ++time, ++intensity) {
      const Eigen::Vector3d p(x[0], x[1], x[2]);
      ASSERT_TRUE(p.allFinite()) << "every beam hits the closed room";
      const Eigen::Isometry3d sensor = drive_.base(stamp + ros::Duration(*time)) * m.pose();
      const Eigen::Vector3d dir = sensor.linear() * p.normalized();
      EXPECT_NEAR(p.norm(), roomDistance(sensor.translation(), dir), kTolerance);
      // wall_front (x = 5) has reflectivity 0.5, the others the default 1; intensity is it times
      // the cosine of incidence, the direction's component along the face's normal, as
      // velodyne_pointcloud gives it: the calibrated reflectivity, 100 x that, rounded. Beams
      // within 1 mm of an edge of the room are left out: which face they hit is up to rounding.
      const RoomFace face = roomFace(sensor.translation(), dir);
      if (face.margin > 1e-3) {
        const double reflectivity = face.axis == 0 && dir.x() > 0 ? 0.5 : 1.0;
        EXPECT_NEAR(*intensity, 100 * reflectivity * std::abs(dir[face.axis]), 0.5 + 1e-3);
        ++faced;
      }
      ++points;
    }
  }
  EXPECT_EQ(points, 29u * 16 * 1808);
  EXPECT_GT(faced, points * 99 / 100);
}

TEST_F(DrivingRobot, TheInputsTfIsCopiedWithItsLatching) {
  rosbag::Bag bag(output_, rosbag::bagmode::Read);
  rosbag::View tf(bag, rosbag::TopicQuery(std::string("/tf")));
  EXPECT_EQ(tf.size(), 301u);
  rosbag::View statics(bag, rosbag::TopicQuery(std::string("/tf_static")));
  ASSERT_EQ(statics.size(), 1u);
  for (const rosbag::ConnectionInfo* c : statics.getConnections()) {
    EXPECT_EQ(c->header->at("latching"), "1");
  }
}

TEST_F(DrivingRobot, AnyThreadCountWritesTheSameScans) {
  const std::string two = out("drive_two_threads.bag");
  const ToolRun run = simulate(input_, two, writeConfig("drive_threads.yaml"), "--threads 2");
  ASSERT_EQ(run.status, 0) << run.err;
  for (const std::string topic : {"/front/scan", "/spin/scan", "/rear/scan"}) {
    const auto a = readBag<sensor_msgs::LaserScan>(output_, topic);
    const auto b = readBag<sensor_msgs::LaserScan>(two, topic);
    ASSERT_EQ(stampsOf(a), stampsOf(b)) << topic;
    for (const auto& [stamp, scan] : a) {
      const auto& other = b.at(stamp).ranges;
      ASSERT_EQ(scan.ranges.size(), other.size());
      EXPECT_EQ(std::memcmp(scan.ranges.data(), other.data(), other.size() * sizeof(float)), 0)
          << topic << " at " << stamp;
    }
  }
  const auto a = readBag<sensor_msgs::PointCloud2>(output_, "/vlp/points");
  const auto b = readBag<sensor_msgs::PointCloud2>(two, "/vlp/points");
  ASSERT_EQ(stampsOf(a), stampsOf(b));
  for (const auto& [stamp, cloud] : a) {
    EXPECT_TRUE(cloud.data == b.at(stamp).data) << "cloud at " << stamp;
  }
}

TEST(SimulateBag, ScansStartWhenTheLateStaticTransformsCoverThem) {
  // The mounts come 0.52 s into the bag: the scans before are skipped, as the node skips them
  // while it waits for its first transforms.
  BagSpec spec;
  spec.static_delay = 0.52;
  const std::string output = out("late_static_out.bag");
  const ToolRun run =
      simulate(writeDriveBag("late_static.bag", spec), output, writeConfig("late_static.yaml"));
  ASSERT_EQ(run.status, 0) << run.err;
  const ros::Time statics = kStart + ros::Duration(spec.static_delay);
  const ros::Time end = kStart + ros::Duration(spec.seconds);
  const auto front = readBag<sensor_msgs::LaserScan>(output, "/front/scan");
  EXPECT_EQ(stampsOf(front), gridStamps(statics, end, 0.05, 0));
  EXPECT_EQ(front.begin()->first, ros::Time(1000.55));
  // 1000.05 to 1000.50.
  EXPECT_TRUE(contains(run.err, "10 before the transforms covered them")) << run.err;
  const Drive drive{kStart};
  for (const auto& [stamp, scan] : front) expectRoomScan(drive, scan, mount("laser"));
}

TEST(SimulateBag, ThePoseTopicPlacesTheSensor) {
  // /robot_pose has base_link 0.5 m to the left of where TF has it; the sensor takes its pose from
  // the topic (and its mount from TF), the robot's body stays where TF has it.
  BagSpec spec;
  spec.pose_offset = 0.5;
  spec.tf_delay = 0.03;
  const std::string output = out("pose_topic_out.bag");
  const std::string config = writeFile(
      "pose_topic.yaml", "fixed_frame: world\nmodels:\n  - {file: " + kSource +
                             "/test/data/sensors_room.urdf}\n  - {file: " + kSource +
                             "/test/data/bag_robot.urdf}\nframe_id: laser\npose_topic: "
                             "/robot_pose\npose_frame: base_link\nsamples: 90\nrate: 10.0\n");
  const ToolRun run = simulate(writeDriveBag("pose_topic.bag", spec), output, config);
  ASSERT_EQ(run.status, 0) << run.err;
  const auto scans = readBag<sensor_msgs::LaserScan>(output, "/scan");
  EXPECT_EQ(stampsOf(scans), gridStamps(kStart, kStart + ros::Duration(spec.seconds), 0.1, 0));
  const Drive drive{kStart};
  for (const auto& [stamp, scan] : scans) {
    const Eigen::Isometry3d sensor =
        Eigen::Translation3d(0, spec.pose_offset, 0) * drive.base(stamp) * mount("laser").pose();
    for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
      const double a = scan.angle_min + i * double(scan.angle_increment);
      const double d = roomDistance(sensor.translation(),
                                    sensor.linear() * Eigen::Vector3d(std::cos(a), std::sin(a), 0));
      EXPECT_NEAR(scan.ranges[i], d, kTolerance) << "beam " << i << " at " << stamp;
    }
  }
}

TEST(SimulateBag, NamespaceResolvesTheTopics) {
  const std::string output = out("namespace_out.bag");
  BagSpec spec;
  spec.seconds = 0.5;
  const ToolRun run = simulate(writeDriveBag("namespace.bag", spec), output,
                               writeConfig("namespace.yaml"), "--namespace /robot1");
  ASSERT_EQ(run.status, 0) << run.err;
  // 1000.05 to 1000.50.
  EXPECT_EQ(readBag<sensor_msgs::LaserScan>(output, "/robot1/front/scan").size(), 10u);
  EXPECT_EQ(readBag<laser_raycast::ScanLabels>(output, "/robot1/front/scan_labels").size(), 10u);
  EXPECT_TRUE(readBag<sensor_msgs::LaserScan>(output, "/front/scan").empty());
}

TEST(SimulateBag, HelpListsTheFlagsAndExitStatuses) {
  const CommandResult r = runCommand(std::string(SIMULATE_BAG_PATH) + " --help");
  EXPECT_EQ(r.status, 0);
  for (const std::string flag :
       {"--input IN.bag", "--output OUT.bag", "--config CONFIG.yaml", "--threads N",
        "--namespace NS", "--no-progress", "--verbose", "Exit status: 0 ok, 2 bad arguments",
        "3 bad scene input", "4 bad input bag", "5 output not writable"}) {
    EXPECT_TRUE(contains(r.output, flag)) << flag << "\n" << r.output;
  }
}

// A failure: its exit status, a message naming `mention`, and no output bag left behind.
void expectFailure(const ToolRun& run, int status, const std::string& mention,
                   const std::string& output) {
  EXPECT_EQ(run.status, status) << run.err;
  EXPECT_TRUE(contains(run.err, mention)) << "expected '" << mention << "' in:\n" << run.err;
  EXPECT_FALSE(std::filesystem::exists(output)) << output;
}

TEST(SimulateBag, BadArgumentsAndConfigurationsExitWith2) {
  BagSpec spec;
  spec.seconds = 0.3;
  const std::string bag = writeDriveBag("args.bag", spec);
  const std::string config = writeConfig("args.yaml");
  const std::string o = out("args_out.bag");
  expectFailure(simulate("--input " + bag + " --config " + config), 2, "give --output", o);
  expectFailure(simulate(bag, o, config, "--threads many"), 2, "--threads: 'many'", o);
  expectFailure(simulate(bag, o, config, "--frobnicate"), 2, "'--frobnicate'", o);
  expectFailure(simulate(bag, o, config, "--namespace robot"), 2, "namespace 'robot'", o);
  expectFailure(simulate(bag, o, out("no_such.yaml")), 2, "no_such.yaml: cannot be read", o);
  expectFailure(simulate(bag, o, writeFile("syntax.yaml", "fixed_frame: world\nsensors: [\n")), 2,
                "syntax.yaml:3:1: not YAML", o);
  expectFailure(simulate(bag, o, writeConfig("rate.yaml", "rate: -1\n")), 2,
                "parameter ~rate: must be in (0, 1000] Hz, got -1", o);
  expectFailure(simulate(bag, o, writeFile("param.yaml", "fixed_frame: world\n")), 2,
                "~models[0] is parameter robot_description (the default), but simulate_bag has "
                "no parameter server: give the URDF as {file: PATH}",
                o);
  // The input given as the output would be truncated before it is read.
  const std::string copy = out("args_copy.bag");
  std::filesystem::copy_file(bag, copy);
  EXPECT_EQ(simulate(copy, copy, config).status, 2);
  EXPECT_GT(std::filesystem::file_size(copy), 0u);
}

TEST(SimulateBag, ABadSceneExitsWith3) {
  BagSpec spec;
  spec.seconds = 0.3;
  const std::string o = out("scene_out.bag");
  const std::string missing = (tempDir() / "no_such_robot.urdf").string();
  expectFailure(simulate(writeDriveBag("scene.bag", spec), o,
                         writeFile("scene.yaml", "fixed_frame: world\nmodels: [{file: " + missing +
                                                     "}]\nframe_id: laser\n")),
                3, "no_such_robot.urdf", o);
}

TEST(SimulateBag, BadInputBagsExitWith4NamingWhatIsMissing) {
  const std::string config = writeConfig("input.yaml");
  const std::string o = out("input_out.bag");
  expectFailure(simulate(out("no_such.bag"), o, config), 4, "no_such.bag: cannot be read as a bag",
                o);
  expectFailure(simulate(writeFile("text.bag", "not a bag\n"), o, config), 4,
                "text.bag: cannot be read as a bag", o);
  BagSpec no_tf;
  no_tf.tf = false;
  expectFailure(simulate(writeDriveBag("no_tf.bag", no_tf), o, config), 4,
                "no_tf.bag: has no messages on /tf or /tf_static", o);
  BagSpec no_bumper;
  no_bumper.with_bumper = false;
  expectFailure(simulate(writeDriveBag("no_bumper.bag", no_bumper), o, config), 4,
                "never name a frame the configuration needs: 'bumper' (sensor 'rear')", o);
  // TF that ends before any sensor's first scan time.
  BagSpec short_tf;
  short_tf.seconds = 0.03;
  expectFailure(simulate(writeDriveBag("short.bag", short_tf), o, config), 4,
                "not one scan could be cast", o);
  // A pose topic the bag does not have, or of another type.
  const std::string posed = writeConfig("posed.yaml", "pose_topic: /robot_pose\n");
  expectFailure(simulate(writeDriveBag("no_pose.bag", BagSpec()), o, posed), 4,
                "has no messages on ~pose_topic /robot_pose", o);
  const std::string wrong_type = writeDriveBag("wrong_pose_type.bag", BagSpec());
  {
    rosbag::Bag bag(wrong_type, rosbag::bagmode::Append);
    bag.write("/robot_pose", kStart, staticTf(kStart));
  }
  expectFailure(simulate(wrong_type, o, posed), 4,
                "~pose_topic /robot_pose carries tf2_msgs/TFMessage; expected "
                "geometry_msgs/PoseStamped or geometry_msgs/PoseWithCovarianceStamped",
                o);
}

TEST(SimulateBag, AnOutputThatCannotBeWrittenExitsWith5) {
  BagSpec spec;
  spec.seconds = 0.3;
  const std::string o = (tempDir() / "no_such_dir" / "out.bag").string();
  expectFailure(simulate(writeDriveBag("output.bag", spec), o, writeConfig("output.yaml")), 5,
                "out.bag: cannot be written", o);
}

}  // namespace
}  // namespace laser_raycast_test
