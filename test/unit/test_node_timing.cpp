// The node's timing policy (tf_timing.h), its scan queue (scan_queue.h) and the pose topic's
// history (pose_history.h), without TF or roscore: times and answers worked out by hand.
#include <gtest/gtest.h>

#include <cmath>

#include "pose_history.h"
#include "random.h"
#include "scan_queue.h"
#include "tf_timing.h"

namespace laser_raycast_test {
namespace {

using laser_raycast::FrameAvailability;
using laser_raycast::frameAvailability;
using laser_raycast::PoseHistory;
using laser_raycast::ScanJob;
using laser_raycast::ScanQueue;

ros::Time at(double s) { return ros::Time(s); }
ros::Duration secs(double s) { return ros::Duration(s); }

TEST(FrameAvailability, TheFourCases) {
  const ros::Duration timeout = secs(0.5);
  // No transform at all.
  EXPECT_EQ(frameAvailability(std::nullopt, at(100), at(100.1), timeout),
            FrameAvailability::kMissing);
  // Static transforms (stamp 0) serve any time.
  EXPECT_EQ(frameAvailability(ros::Time(0), at(100), at(100.1), timeout),
            FrameAvailability::kCovered);
  // Data at or after the time needed.
  EXPECT_EQ(frameAvailability(at(100), at(100), at(100.1), timeout), FrameAvailability::kCovered);
  EXPECT_EQ(frameAvailability(at(100.05), at(100), at(100.1), timeout),
            FrameAvailability::kCovered);
  // Late: the newest data is 0.3 s old, within the timeout.
  EXPECT_EQ(frameAvailability(at(99.8), at(100), at(100.1), timeout), FrameAvailability::kWaiting);
  // Exactly tf_timeout old is still waited for; a nanosecond more is not.
  EXPECT_EQ(frameAvailability(at(99.6), at(100), at(100.1), timeout), FrameAvailability::kWaiting);
  ros::Time older = at(99.6);
  older.fromNSec(older.toNSec() - 1);
  EXPECT_EQ(frameAvailability(older, at(100), at(100.1), timeout), FrameAvailability::kStale);
}

// Whatever the newest data of a transform, a scan waits for it no longer than tf_timeout past its
// last beam's time: by then it is covered or stale.
TEST(FrameAvailability, NoWaitOutlastsTheTimeout) {
  Rng rng(7);
  for (int i = 0; i < 1000; ++i) {
    const ros::Time needed = at(1000 + uniform(rng, 0, 2));
    const ros::Time latest = at(999 + uniform(rng, 0, 2));
    const ros::Duration timeout = secs(uniform(rng, 0, 2));
    const ros::Time deadline = needed + timeout + secs(1e-9);
    EXPECT_NE(frameAvailability(latest, needed, deadline, timeout), FrameAvailability::kWaiting)
        << "latest " << latest << " needed " << needed << " timeout " << timeout;
  }
}

TEST(SampleTimes, AnInstantScanHasOneTime) {
  const auto times = laser_raycast::sampleTimes(at(5), secs(0), secs(0.01));
  ASSERT_EQ(times.size(), 1u);
  EXPECT_EQ(times[0], at(5));
}

TEST(SampleTimes, EvenlyFromTheFirstBeamToTheLast) {
  // 0.1 s at most 0.01 s apart: 10 intervals of exactly 10 ms.
  auto times = laser_raycast::sampleTimes(at(5), secs(0.1), secs(0.01));
  ASSERT_EQ(times.size(), 11u);
  for (std::size_t i = 0; i < times.size(); ++i) {
    EXPECT_EQ(times[i].toNSec(), at(5).toNSec() + 10000000ull * i) << i;
  }
  // 0.105 s: 11 intervals of 9.545... ms, the last time exact.
  times = laser_raycast::sampleTimes(at(5), secs(0.105), secs(0.01));
  ASSERT_EQ(times.size(), 12u);
  EXPECT_EQ(times.front(), at(5));
  EXPECT_EQ(times.back(), at(5) + secs(0.105));
  for (std::size_t i = 1; i < times.size(); ++i) {
    const std::int64_t step = (times[i] - times[i - 1]).toNSec();
    EXPECT_GE(step, 9545454);
    EXPECT_LE(step, 9545455);
  }
  // Shorter than the spacing: both ends.
  times = laser_raycast::sampleTimes(at(5), secs(0.004), secs(0.01));
  ASSERT_EQ(times.size(), 2u);
  EXPECT_EQ(times.back(), at(5.004));
}

TEST(PeriodGrid, NearestAndNextMultiples) {
  EXPECT_EQ(laser_raycast::nearestMultiple(at(1.234), secs(0.1)), at(1.2));
  EXPECT_EQ(laser_raycast::nearestMultiple(at(1.26), secs(0.1)), at(1.3));
  EXPECT_EQ(laser_raycast::nearestMultiple(at(1.3), secs(0.1)), at(1.3));
  EXPECT_EQ(laser_raycast::untilNextMultiple(at(1.23), secs(0.1)), secs(0.07));
  EXPECT_EQ(laser_raycast::untilNextMultiple(at(1.3), secs(0.1)), secs(0.1));
  // A 10 Hz grid time is on the 20 Hz grid too (the two sensors share it).
  const ros::Time t = laser_raycast::nearestMultiple(at(1700000000.123456789), secs(0.1));
  EXPECT_EQ(laser_raycast::nearestMultiple(t, secs(0.05)), t);
}

std::vector<ros::Time> instant(double s) { return {at(s)}; }

TEST(ScanQueue, OrderedByTheLastBeamsTime) {
  ScanQueue q;
  EXPECT_FALSE(q.push({at(1.0), at(1.1)}, 0));  // a sweep ending at 1.1
  EXPECT_FALSE(q.push(instant(1.05), 1));       // due before it
  EXPECT_FALSE(q.push(instant(1.2), 1));
  ASSERT_EQ(q.size(), 3u);
  EXPECT_EQ(q.pop().last(), at(1.05));
  EXPECT_EQ(q.pop().last(), at(1.1));
  EXPECT_EQ(q.pop().last(), at(1.2));
  EXPECT_TRUE(q.empty());
}

TEST(ScanQueue, SensorsAtTheSameTimesShareAJob) {
  ScanQueue q;
  q.push(instant(2.0), 0);
  q.push(instant(2.0), 1);
  q.push(instant(2.0), 1);        // once per sensor
  q.push({at(1.9), at(2.0)}, 2);  // the same last time, other times: a job of its own, after
  ASSERT_EQ(q.size(), 2u);
  const ScanJob first = q.pop();
  EXPECT_EQ(first.sensors, (std::vector<int>{0, 1}));
  EXPECT_EQ(q.front().sensors, std::vector<int>{2});
  EXPECT_EQ(q.front().stamp(), at(1.9));
}

TEST(ScanQueue, OverCapacityTheOldestIsDropped) {
  ScanQueue q(2);
  EXPECT_FALSE(q.push(instant(1.0), 0));
  EXPECT_FALSE(q.push(instant(1.1), 0));
  const auto dropped = q.push(instant(1.2), 0);
  ASSERT_TRUE(dropped);
  EXPECT_EQ(dropped->stamp(), at(1.0));
  EXPECT_EQ(q.size(), 2u);
  EXPECT_EQ(q.front().stamp(), at(1.1));
}

PoseHistory::Entry entry(double t, double x, bool valid = true) {
  PoseHistory::Entry e;
  e.stamp = at(t);
  e.frame = "map";
  e.pose.translation().x() = x;
  e.valid = valid;
  return e;
}

TEST(PoseHistory, InterpolatedBetweenMessagesAndHeldForTheTimeout) {
  PoseHistory h(secs(10), 1000);
  EXPECT_EQ(h.at(at(1), secs(1)).status, PoseHistory::Status::kNone);
  h.add(entry(1.0, 0.0));
  h.add(entry(2.0, 1.0));
  auto q = h.at(at(1.25), secs(0.5));
  ASSERT_EQ(q.status, PoseHistory::Status::kOk);
  EXPECT_EQ(q.a.stamp, at(1.0));
  EXPECT_EQ(q.b.stamp, at(2.0));
  EXPECT_DOUBLE_EQ(q.s, 0.25);
  // After the newest message it is held while at most the timeout old.
  q = h.at(at(2.5), secs(0.5));
  ASSERT_EQ(q.status, PoseHistory::Status::kOk);
  EXPECT_EQ(q.a.stamp, at(2.0));
  EXPECT_EQ(q.b.stamp, at(2.0));
  EXPECT_DOUBLE_EQ(q.age, 0.5);
  q = h.at(at(2.6), secs(0.5));
  EXPECT_EQ(q.status, PoseHistory::Status::kStale);
  EXPECT_NEAR(q.age, 0.6, 1e-9);
  // A gap longer than the timeout is stale inside it too: the pose is a guess there.
  EXPECT_EQ(h.at(at(1.75), secs(0.5)).status, PoseHistory::Status::kStale);
  // Before every message: nothing known.
  EXPECT_EQ(h.at(at(0.9), secs(0.5)).status, PoseHistory::Status::kStale);
}

TEST(PoseHistory, ANonFiniteMessageMakesThePoseUnknownUntilTheNextGoodOne) {
  PoseHistory h(secs(10), 1000);
  h.add(entry(1.0, 0.0));
  h.add(entry(2.0, 0.0, false));
  h.add(entry(3.0, 1.0));
  EXPECT_EQ(h.at(at(2.0), secs(5)).status, PoseHistory::Status::kInvalid);
  EXPECT_EQ(h.at(at(2.9), secs(5)).status, PoseHistory::Status::kInvalid);
  // Before it, the good pose is held (not interpolated towards the unknown one).
  const auto q = h.at(at(1.5), secs(5));
  ASSERT_EQ(q.status, PoseHistory::Status::kOk);
  EXPECT_EQ(q.b.stamp, at(1.0));
  EXPECT_EQ(q.s, 0.0);
  EXPECT_EQ(h.at(at(3.1), secs(5)).status, PoseHistory::Status::kOk);
}

TEST(PoseHistory, KeepsOnlyRecentMessagesInStampOrder) {
  PoseHistory h(secs(1.0), 1000);
  for (int i = 0; i < 10; ++i) h.add(entry(0.5 * i, i));
  // Within 1 s of the newest (4.5): 3.5, 4.0, 4.5.
  EXPECT_EQ(h.size(), 3u);
  h.add(entry(3.75, 99));  // out of order: inserted in order
  h.add(entry(4.0, 42));   // the same stamp: replaces
  EXPECT_EQ(h.size(), 4u);
  const auto q = h.at(at(3.8), secs(1));
  EXPECT_EQ(q.a.pose.translation().x(), 99);
  EXPECT_EQ(q.b.pose.translation().x(), 42);
  PoseHistory small(secs(100), 4);
  for (int i = 0; i < 10; ++i) small.add(entry(i, i));
  EXPECT_EQ(small.size(), 4u);
  EXPECT_EQ(small.newest().stamp, at(9));
}

}  // namespace
}  // namespace laser_raycast_test
