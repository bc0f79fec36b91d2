// The cast thread's link poses (link_poses.h) and the scan queue's oldest stamp, without TF or
// roscore: a look-up that counts its calls and places each frame where the test computes it.
// Sensors due at one stamp with different sample times (an instantaneous scan and a rotating one,
// as in the demo) are separate jobs; each link is looked up once per time for all of them.
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <tf2/buffer_core.h>

#include <cmath>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "link_poses.h"
#include "scan_queue.h"
#include "tf_source.h"
#include "tf_timing.h"

namespace laser_raycast_test {
namespace {

using laser_raycast::LinkPoses;
using laser_raycast::LinkPosesAt;
using laser_raycast::ScanQueue;

ros::Time at(double s) { return ros::Time(s); }

// A scene of three link frames; where a frame is at t: x = its index + t (so a pose from the wrong
// time is visible).
struct Rig {
  Rig() {
    for (const char* name : {"base", "arm", "door"}) scene.addFrame(name);
  }

  // A static frame (in `fixed`) is at x = its index at every time; with check_static, LinkPoses
  // is told which frames those are.
  LinkPoses poses(bool check_static = false) {
    laser_raycast::StaticFrameCheck check;
    if (check_static) {
      check = [this](const std::string& frame) {
        ++static_checks;
        return fixed.count(frame) > 0;
      };
    }
    return LinkPoses(
        scene,
        [this](const std::string& frame, const ros::Time& t, Eigen::Isometry3d* pose,
               std::string* error) {
          ++calls[{frame, t}];
          if (broken.count(frame)) {
            *error = "no transform for " + frame;
            return false;
          }
          pose->setIdentity();
          pose->translation().x() = index(frame) + (fixed.count(frame) ? 0.0 : t.toSec());
          return true;
        },
        check);
  }

  int index(const std::string& frame) const {
    for (std::size_t i = 0; i < scene.frames().size(); ++i) {
      if (scene.frames()[i] == frame) return static_cast<int>(i);
    }
    return -1;
  }
  std::size_t totalCalls() const {
    std::size_t n = 0;
    for (const auto& [key, count] : calls) n += count;
    return n;
  }

  laser_raycast::core::Scene scene;
  std::map<std::pair<std::string, ros::Time>, int> calls;
  std::set<std::string> broken, fixed;
  int static_checks = 0;
};

// The demo's case: an instantaneous sensor and a rotating one (0.1 s sweep, sampled every 10 ms)
// due at one stamp. The instant job is cast first (its transforms are due first), the rotating one
// later; the stamp's link poses are looked up once, for both.
TEST(LinkPoses, SensorsDueAtOneStampLookEachLinkUpOncePerTime) {
  Rig rig;
  LinkPoses poses = rig.poses();
  const ros::Time stamp = at(100);
  const std::vector<ros::Time> instant = {stamp};
  const std::vector<ros::Time> rotating =
      laser_raycast::sampleTimes(stamp, ros::Duration(0.1), ros::Duration(0.01));
  ASSERT_EQ(rotating.size(), 11u);
  ASSERT_EQ(rotating.front(), stamp);

  const LinkPosesAt a = poses.at(instant);
  const LinkPosesAt b = poses.at(rotating);
  // 3 frames at 11 distinct times, each once.
  EXPECT_EQ(rig.totalCalls(), 3u * 11u);
  EXPECT_EQ(poses.lookups(), 3u * 11u);
  for (const auto& [key, count] : rig.calls) {
    EXPECT_EQ(count, 1) << key.first << " at " << key.second;
  }
  // Each sensor gets the poses at its own times, the shared stamp's identical for both.
  ASSERT_EQ(a.frames.size(), 1u);
  ASSERT_EQ(b.frames.size(), 11u);
  for (std::size_t j = 0; j < rotating.size(); ++j) {
    for (int f = 0; f < 3; ++f) {
      EXPECT_TRUE(b.frames[j].valid[f]);
      EXPECT_DOUBLE_EQ(b.frames[j].pose[f].translation().x(), f + rotating[j].toSec());
    }
  }
  EXPECT_TRUE(a.frames[0].pose[2].isApprox(b.frames[0].pose[2], 0.0));
  EXPECT_TRUE(a.missing.empty() && b.missing.empty());
  EXPECT_EQ(a.failures + b.failures, 0u);

  // A second instantaneous sensor at the same stamp, and the 20 Hz sensor's next scan, within the
  // sweep: no look-up twice. A time not seen yet is looked up.
  poses.at(instant);
  poses.at({stamp + ros::Duration(0.05)});
  EXPECT_EQ(rig.totalCalls(), 3u * 11u);
  poses.at({stamp + ros::Duration(0.2)});
  EXPECT_EQ(rig.totalCalls(), 3u * 12u);
}

// A rotating scan's static frames (a warehouse's fixed racks) are looked up at its first new time
// only and copied to the others, failures included; the moving ones at every time. The poses are
// the ones a look-up at each time gives. An instantaneous scan (one new time) asks nothing more.
TEST(LinkPoses, StaticFramesAreLookedUpOncePerScan) {
  for (const bool broken_static : {false, true}) {
    Rig rig;
    rig.fixed = {"base", "door"};
    if (broken_static) rig.broken = {"door"};
    LinkPoses poses = rig.poses(true);
    const std::vector<ros::Time> rotating =
        laser_raycast::sampleTimes(at(7), ros::Duration(0.1), ros::Duration(0.01));
    const LinkPosesAt r = poses.at(rotating);
    EXPECT_EQ(rig.static_checks, 3);
    EXPECT_EQ((rig.calls[{"base", at(7)}]), 1);
    EXPECT_EQ((rig.calls[{"door", at(7)}]), 1);
    EXPECT_EQ(rig.totalCalls(), 2u + 11u);  // base and door once, arm at each time
    EXPECT_EQ(poses.lookups(), 2u + 11u);
    ASSERT_EQ(r.frames.size(), 11u);
    for (std::size_t j = 0; j < rotating.size(); ++j) {
      EXPECT_DOUBLE_EQ(r.frames[j].pose[0].translation().x(), 0.0);
      EXPECT_DOUBLE_EQ(r.frames[j].pose[1].translation().x(), 1 + rotating[j].toSec());
      EXPECT_TRUE(r.frames[j].valid[0] && r.frames[j].valid[1]);
      EXPECT_EQ(bool(r.frames[j].valid[2]), !broken_static);
      if (!broken_static) {
        EXPECT_DOUBLE_EQ(r.frames[j].pose[2].translation().x(), 2.0);
      }
    }
    EXPECT_EQ(r.failures, broken_static ? 11u : 0u);
    EXPECT_EQ(r.first_error, broken_static ? "no transform for door" : "");
    // One new time: looked up as before, no static check.
    poses.at({at(8)});
    EXPECT_EQ(rig.static_checks, 3);
    EXPECT_EQ(rig.totalCalls(), 2u + 11u + 3u);
  }
}

// TF says which chains are static, as the node asks it for LinkPoses: a chain of /tf_static
// transforms only is; one with a transform from /tf, or none at all, is not.
TEST(TfSource, AChainOfStaticTransformsOnlyIsStatic) {
  tf2::BufferCore buffer;
  auto add = [&](const std::string& parent, const std::string& child, double stamp, bool fixed) {
    geometry_msgs::TransformStamped t;
    t.header.frame_id = parent;
    t.header.stamp = ros::Time(stamp);
    t.child_frame_id = child;
    t.transform.rotation.w = 1;
    buffer.setTransform(t, "test", fixed);
  };
  add("map", "rack", 1, true);
  add("rack", "shelf", 1, true);
  add("map", "base", 1, false);
  add("map", "base", 2, false);
  add("base", "arm", 1, true);
  const laser_raycast::TfSource tf(buffer);
  EXPECT_TRUE(tf.isStatic("map", "rack"));
  EXPECT_TRUE(tf.isStatic("map", "shelf"));
  EXPECT_TRUE(tf.isStatic("map", "map"));
  EXPECT_FALSE(tf.isStatic("map", "base"));
  EXPECT_FALSE(tf.isStatic("map", "arm"));    // static below a moving frame
  EXPECT_FALSE(tf.isStatic("map", "wheel"));  // no such frame
}

// A link without a transform is missing from the scan; every time it is needed at is a failed
// look-up (a rotating scan's 11), made once per time whichever sensor needs it.
TEST(LinkPoses, FailuresCountEveryFrameAndTime) {
  Rig rig;
  rig.broken = {"door"};
  LinkPoses poses = rig.poses();
  const std::vector<ros::Time> rotating =
      laser_raycast::sampleTimes(at(5), ros::Duration(0.1), ros::Duration(0.01));
  const LinkPosesAt r = poses.at(rotating);
  EXPECT_EQ(r.missing, std::vector<std::string>{"door"});
  EXPECT_EQ(r.failures, 11u);
  EXPECT_EQ(r.first_error, "no transform for door");
  for (const auto& f : r.frames) {
    EXPECT_TRUE(f.valid[0] && f.valid[1]);
    EXPECT_FALSE(f.valid[2]);
  }
  // Another sensor at the stamp: the failure is its too, without a second look-up.
  const LinkPosesAt i = poses.at({at(5)});
  EXPECT_EQ(i.failures, 1u);
  EXPECT_EQ(i.missing, std::vector<std::string>{"door"});
  EXPECT_EQ((rig.calls[{"door", at(5)}]), 1);
}

// A pose that is not a finite rigid transform counts as no pose.
TEST(LinkPoses, ANonFinitePoseIsAFailure) {
  laser_raycast::core::Scene scene;
  scene.addFrame("a");
  LinkPoses poses(scene,
                  [](const std::string&, const ros::Time&, Eigen::Isometry3d* pose, std::string*) {
                    pose->setIdentity();
                    pose->translation().x() = std::nan("");
                    return true;
                  });
  const LinkPosesAt r = poses.at({at(1)});
  EXPECT_EQ(r.failures, 1u);
  EXPECT_EQ(r.missing, std::vector<std::string>{"a"});
}

// Forgotten times are looked up again; the number kept stays bounded whatever the times.
TEST(LinkPoses, ForgottenTimesAreLookedUpAgainAndTheCacheIsBounded) {
  Rig rig;
  LinkPoses poses = rig.poses();
  poses.at({at(1), at(2), at(3)});
  poses.forgetBefore(at(2));
  EXPECT_EQ(poses.times(), 2u);
  poses.at({at(1), at(2)});
  EXPECT_EQ((rig.calls[{"base", at(1)}]), 2);
  EXPECT_EQ((rig.calls[{"base", at(2)}]), 1);

  std::vector<ros::Time> many;
  for (std::size_t i = 0; i < 3 * LinkPoses::kMaxTimes; ++i) many.push_back(at(10 + 0.001 * i));
  const LinkPosesAt r = poses.at(many);
  EXPECT_EQ(r.frames.size(), many.size());  // the scan itself gets every time
  EXPECT_EQ(poses.times(), LinkPoses::kMaxTimes);
}

// What the cast thread forgets after each job: the times before the oldest stamp still queued.
TEST(ScanQueue, OldestStampIsTheEarliestStampOfAnyJob) {
  ScanQueue queue;
  EXPECT_FALSE(queue.oldestStamp());
  // A rotating scan at 10 (last beam at 10.1) is queued behind an instantaneous one at 10.05.
  queue.push({at(10), at(10.05), at(10.1)}, 0);
  queue.push({at(10.05)}, 1);
  ASSERT_EQ(queue.front().stamp(), at(10.05));
  EXPECT_EQ(queue.oldestStamp(), at(10));
  queue.pop();
  EXPECT_EQ(queue.oldestStamp(), at(10));
  queue.pop();
  EXPECT_FALSE(queue.oldestStamp());
}

}  // namespace
}  // namespace laser_raycast_test
