// rostest simulate_bag_node.test and simulate_bag_replay.test: simulate_bag against the live node
// for the same TF. The node (laser_raycast_node with test/data/simulate_bag_test.yaml) publishes
// its four sensors while the robot of bag_drive.h drives: on /tf that this test publishes live and
// `rosbag record` records (then simulate_bag casts the recording), or from a bag this test writes,
// which simulate_bag casts and `rosbag play --clock` plays into the node under simulated time.
// Every scan, cloud and labels message the node published at a stamp simulate_bag also wrote must
// be the same bit for bit, and the stamps they share must be nearly all of the node's.
#include <gtest/gtest.h>
#include <laser_raycast/ScanLabels.h>
#include <ros/ros.h>
#include <sensor_msgs/LaserScan.h>
#include <sensor_msgs/PointCloud2.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "bag_drive.h"
#include "run_command.h"

namespace laser_raycast_test {
namespace {

const std::string kConfig =
    std::string(LASER_RAYCAST_SOURCE_DIR) + "/test/data/simulate_bag_test.yaml";
// The node's scans are compared from this share of them on: the node may lose a scan or two to a
// loaded machine (its cast queue drops them), never compute one differently.
constexpr double kSharedShare = 0.9;

// A fresh directory, removed at the end.
struct Scratch {
  Scratch() {
    char name[] = "/tmp/laser_raycast_simulate_bag_XXXXXX";
    path = ::mkdtemp(name);
  }
  ~Scratch() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  std::string file(const std::string& name) const { return path + "/" + name; }
  std::string path;
};

// A child process: argv[0] found on PATH.
pid_t spawn(const std::vector<std::string>& args) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execvp(argv[0], argv.data());
    std::_Exit(127);
  }
  return pid;
}

// Waits up to `seconds` for the child to exit (its exit status, or -1).
int waitExit(pid_t pid, double seconds) {
  for (const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
       ros::WallTime::now() < end;) {
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid)
      return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    ros::WallDuration(0.05).sleep();
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, nullptr, 0);
  return -1;
}

// Waits up to `seconds` of wall time for ok().
template <class F>
bool waitUntil(F ok, double seconds) {
  for (const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
       ros::WallTime::now() < end; ros::WallDuration(0.01).sleep()) {
    if (ok()) return true;
  }
  return ok();
}

// Every message of one topic the node publishes, by stamp.
template <class M>
class Collector {
 public:
  Collector(ros::NodeHandle& nh, const std::string& topic)
      : topic_(topic), sub_(nh.subscribe(topic, 1000, &Collector::onMessage, this)) {}

  bool connected() const { return sub_.getNumPublishers() > 0; }
  std::map<ros::Time, M> messages() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return messages_;
  }
  const std::string& topic() const { return topic_; }

 private:
  void onMessage(const boost::shared_ptr<const M>& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    messages_[m->header.stamp] = *m;
  }

  std::string topic_;
  mutable std::mutex mutex_;
  std::map<ros::Time, M> messages_;
  ros::Subscriber sub_;
};

void expectSame(const sensor_msgs::LaserScan& node, const sensor_msgs::LaserScan& bag) {
  EXPECT_EQ(node.header.frame_id, bag.header.frame_id);
  EXPECT_EQ(node.angle_min, bag.angle_min);
  EXPECT_EQ(node.angle_max, bag.angle_max);
  EXPECT_EQ(node.angle_increment, bag.angle_increment);
  EXPECT_EQ(node.time_increment, bag.time_increment);
  EXPECT_EQ(node.scan_time, bag.scan_time);
  EXPECT_EQ(node.range_min, bag.range_min);
  EXPECT_EQ(node.range_max, bag.range_max);
  ASSERT_EQ(node.ranges.size(), bag.ranges.size());
  ASSERT_EQ(node.intensities.size(), bag.intensities.size());
  // Bits, so that NaN and the signs of infinities count too.
  EXPECT_EQ(std::memcmp(node.ranges.data(), bag.ranges.data(), node.ranges.size() * 4), 0);
  EXPECT_EQ(
      std::memcmp(node.intensities.data(), bag.intensities.data(), node.intensities.size() * 4), 0);
}

void expectSame(const sensor_msgs::PointCloud2& node, const sensor_msgs::PointCloud2& bag) {
  EXPECT_EQ(node.header.frame_id, bag.header.frame_id);
  EXPECT_EQ(node.height, bag.height);
  EXPECT_EQ(node.width, bag.width);
  EXPECT_EQ(node.fields.size(), bag.fields.size());
  EXPECT_EQ(node.point_step, bag.point_step);
  EXPECT_EQ(node.row_step, bag.row_step);
  EXPECT_EQ(node.is_dense, bag.is_dense);
  EXPECT_TRUE(node.data == bag.data);
}

void expectSame(const laser_raycast::ScanLabels& node, const laser_raycast::ScanLabels& bag) {
  EXPECT_EQ(node.header.frame_id, bag.header.frame_id);
  EXPECT_EQ(node.link_names, bag.link_names);
  EXPECT_TRUE(node.labels == bag.labels);
}

// Compares what the node published on a topic with simulate_bag's output; returns the number of
// stamps they share.
template <class M>
std::size_t compare(const Collector<M>& node, const std::string& bag) {
  const std::map<ros::Time, M> published = node.messages();
  const std::map<ros::Time, M> written = readBag<M>(bag, node.topic());
  std::size_t shared = 0;
  for (const auto& [stamp, message] : published) {
    const auto found = written.find(stamp);
    if (found == written.end()) continue;
    SCOPED_TRACE(node.topic() + " at " + std::to_string(stamp.toSec()));
    expectSame(message, found->second);
    ++shared;
  }
  EXPECT_GE(shared, kSharedShare * published.size())
      << node.topic() << ": the node published " << published.size() << " messages, simulate_bag "
      << written.size() << ", at " << shared << " stamps both";
  EXPECT_GT(shared, 0u) << node.topic();
  std::cout << node.topic() << ": the node published " << published.size() << ", simulate_bag "
            << written.size() << ", " << shared << " at the same stamps, compared bit for bit\n";
  return shared;
}

// What the node publishes, collected from before it starts to publish.
class NodeScans {
 public:
  explicit NodeScans(ros::NodeHandle& nh)
      : front(nh, "/front/scan"),
        spin(nh, "/spin/scan"),
        rear(nh, "/rear/scan"),
        vlp(nh, "/vlp/points"),
        front_labels(nh, "/front/scan_labels"),
        vlp_labels(nh, "/vlp/points_labels") {}

  bool connected() const {
    return front.connected() && spin.connected() && rear.connected() && vlp.connected() &&
           front_labels.connected() && vlp_labels.connected();
  }

  void expectInBag(const std::string& bag) const {
    compare(front, bag);
    compare(spin, bag);
    compare(rear, bag);
    compare(vlp, bag);
    compare(front_labels, bag);
    compare(vlp_labels, bag);
  }

  Collector<sensor_msgs::LaserScan> front, spin, rear;
  Collector<sensor_msgs::PointCloud2> vlp;
  Collector<laser_raycast::ScanLabels> front_labels, vlp_labels;
};

int simulateBag(const std::string& in, const std::string& out) {
  const CommandResult r = runCommand(std::string(SIMULATE_BAG_PATH) + " --input " + in +
                                     " --output " + out + " --config " + kConfig + " 2>&1");
  std::cout << r.output;
  return r.status;
}

TEST(SimulateBagNode, ARecordingOfLiveTfGivesTheLiveNodesScans) {
  ros::NodeHandle nh;
  NodeScans node(nh);
  ros::Publisher tf_pub = nh.advertise<tf2_msgs::TFMessage>("/tf", 100);
  ros::Publisher static_pub = nh.advertise<tf2_msgs::TFMessage>("/tf_static", 1, true);
  const Scratch scratch;
  const std::string recording = scratch.file("drive.bag");
  const pid_t recorder = spawn({"rosrun", "rosbag", "record", "-O", recording, "/tf", "/tf_static",
                                "__name:=simulate_bag_recorder"});
  ASSERT_GT(recorder, 0);
  // The node's listener and the recorder on both TF topics, the node publishing to us.
  ASSERT_TRUE(waitUntil(
      [&] {
        return tf_pub.getNumSubscribers() >= 2 && static_pub.getNumSubscribers() >= 2 &&
               node.connected();
      },
      60.0))
      << "the node or the recorder did not connect";

  static_pub.publish(staticTf(ros::Time::now()));
  const Drive drive{ros::Time::now()};
  ros::WallRate rate(100.0);
  for (const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(4.0);
       ros::WallTime::now() < end; rate.sleep()) {
    tf_pub.publish(driveTf(drive, ros::Time::now()));
  }
  ros::WallDuration(1.0).sleep();  // the node casts what TF now covers; the recorder writes
  ::kill(recorder, SIGINT);
  ASSERT_EQ(waitExit(recorder, 20.0), 0) << "rosbag record did not stop cleanly";
  ASSERT_TRUE(std::filesystem::exists(recording));

  const std::string simulated = scratch.file("simulated.bag");
  ASSERT_EQ(simulateBag(recording, simulated), 0);
  node.expectInBag(simulated);
}

TEST(SimulateBagNode, ABagPlayedIntoTheNodeGivesSimulateBagsScans) {
  // A bag of the drive, as the unit test writes it, but stamped now (wall time: /clock starts
  // there), with the mounts on latched /tf_static.
  const Scratch scratch;
  const std::string drive_bag = scratch.file("drive.bag");
  {
    rosbag::Bag bag(drive_bag, rosbag::bagmode::Write);
    const ros::Time start(std::floor(ros::WallTime::now().toSec()) + 0.005);
    const Drive drive{start};
    bag.write("/tf_static", start, staticTf(start), latchedHeader<tf2_msgs::TFMessage>());
    for (int i = 0; i <= 400; ++i) {
      const ros::Time t = start + ros::Duration(0.01 * i);
      bag.write("/tf", t, driveTf(drive, t));
    }
  }
  const std::string simulated = scratch.file("simulated.bag");
  ASSERT_EQ(simulateBag(drive_bag, simulated), 0);

  ros::NodeHandle nh;
  NodeScans node(nh);
  ASSERT_TRUE(waitUntil([&] { return node.connected(); }, 60.0)) << "the node did not connect";
  // One second for the node's listener to connect to the player before it starts.
  const pid_t player =
      spawn({"rosrun", "rosbag", "play", "--clock", "--quiet", "--delay=1", drive_bag});
  ASSERT_GT(player, 0);
  ASSERT_EQ(waitExit(player, 60.0), 0) << "rosbag play failed";
  ros::WallDuration(1.0).sleep();
  node.expectInBag(simulated);
}

}  // namespace
}  // namespace laser_raycast_test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_simulate_bag_node");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
