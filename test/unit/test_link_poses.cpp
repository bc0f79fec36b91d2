// The cast thread's link poses (link_poses.h) and the scan queue's oldest stamp, without TF or
// roscore: a look-up that counts its calls and places each frame where the test computes it.
// Sensors due at one stamp with different sample times (an instantaneous scan and a rotating one,
// as in the demo) are separate jobs; each link is looked up once per time for all of them.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "link_poses.h"
#include "scan_queue.h"
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

  LinkPoses poses() {
    return LinkPoses(scene, [this](const std::string& frame, const ros::Time& t,
                                   Eigen::Isometry3d* pose, std::string* error) {
      ++calls[{frame, t}];
      if (broken.count(frame)) {
        *error = "no transform for " + frame;
        return false;
      }
      pose->setIdentity();
      pose->translation().x() = index(frame) + t.toSec();
      return true;
    });
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
  std::set<std::string> broken;
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
