// What a live change (dynamic_reconfigure, Sensor::setLive) may change, without a node: the
// refusals name the parameter and the value and leave the previous values; the rest is applied.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "expect_invalid.h"
#include "live_params.h"
#include "node_params_inputs.h"
#include "vlp16_manual.h"

namespace laser_raycast_test {
namespace {

using laser_raycast::applyLiveParams;
using laser_raycast::LiveParams;
using laser_raycast::liveParams;
using laser_raycast::SensorParams;
using laser_raycast::Sweep;

// A rotating scanner at 10 Hz whose head turns in 0.1 s (scan_time set explicitly).
SensorParams rotating(double scan_time) {
  SensorParams p;
  p.rate = 10.0;
  p.sweep = Sweep::kRotating;
  p.scan_time = scan_time;
  return p;
}

// Expects the change refused with every one of `mentions`, and params unchanged.
void expectRefused(const LiveParams& live, SensorParams params,
                   const std::vector<std::string>& mentions) {
  const SensorParams before = params;
  const std::string error = applyLiveParams(live, &params);
  EXPECT_FALSE(error.empty()) << "accepted rate " << live.rate;
  expectMentions(error, mentions);
  EXPECT_EQ(params.rate, before.rate);
  EXPECT_EQ(params.scan.output.range_max, before.scan.output.range_max);
  EXPECT_EQ(params.scan.output.intensity, before.scan.output.intensity);
}

// One turn per scan: with scan_time 0.1 s the period may not drop below 0.1 s (10 Hz).
TEST(LiveParams, ARateTooFastForScanTimeIsRefused) {
  const SensorParams p = rotating(0.1);
  LiveParams live = liveParams(p);
  live.rate = 20.0;
  live.output.range_max = 12.0;  // the whole change is refused, not just the rate
  expectRefused(live, p, {"rate 20 Hz", "too fast for scan_time 0.1 s", "restart"});

  // 10 Hz exactly and slower are fine.
  for (const double rate : {10.0, 4.0}) {
    SensorParams q = p;
    live.rate = rate;
    EXPECT_EQ(applyLiveParams(live, &q), "") << rate;
    EXPECT_EQ(q.rate, rate);
    EXPECT_EQ(q.scan.output.range_max, 12.0);
    EXPECT_EQ(q.scan_time, 0.1);
  }
}

// Without scan_time the head turns once per period, whatever the rate; an instantaneous sensor has
// no turn.
TEST(LiveParams, ScanTimeFollowingTheRateOrNoSweepAllowsAnyRate) {
  for (SensorParams p : {rotating(0.0), SensorParams()}) {
    if (p.sweep == Sweep::kInstant) p.scan_time = 0.1;  // no effect without a sweep
    LiveParams live = liveParams(p);
    live.rate = 50.0;
    EXPECT_EQ(applyLiveParams(live, &p), "");
    EXPECT_EQ(p.rate, 50.0);
  }
  SensorParams p = rotating(0.0);
  LiveParams live = liveParams(p);
  live.rate = 50.0;
  ASSERT_EQ(applyLiveParams(live, &p), "");
  EXPECT_DOUBLE_EQ(p.scanTime(), 1.0 / 50);
}

// A rate so slow that a sweep following it (scan_time unset) outlasts what ouster's uint32 ns
// hold (4.29 s) is refused; the velodyne layout's float seconds hold it.
TEST(LiveParams, ASweepTooLongForThePointLayoutIsRefused) {
  SensorParams p = rotating(0.0);
  p.scan.fan.samples = 360;
  p.scan.elevations = {-0.1, 0.1};
  p.point_layout = laser_raycast::PointLayout::kOuster;
  LiveParams live = liveParams(p);
  live.rate = 0.2;  // a 5 s turn
  expectRefused(live, p, {"rate 0.2 Hz", "too slow for point_layout 'ouster'", "uint32 ns"});
  live.rate = 0.25;  // 4 s
  SensorParams q = p;
  EXPECT_EQ(applyLiveParams(live, &q), "");
  p.point_layout = laser_raycast::PointLayout::kVelodyne;
  live.rate = 0.2;
  EXPECT_EQ(applyLiveParams(live, &p), "");
}

// A head's beams (a preset's lasers) are one turn of the scan time: with scan_time following the
// rate, a live rate change fires them again over the new turn (VLP-16 at 20 Hz: 904 sequences of
// 16, the head's azimuth turning twice as fast); with scan_time set, or a change refused, the
// turn stays; a rate whose turn fires more beams than a list holds is refused by name.
TEST(LiveParams, AHeadWhoseTurnFollowsTheRateFiresAgainAtTheNewRate) {
  const Parsed parsed = parse(values({{"sensor_model", "VLP-16"}, {"sweep", "rotating"}}));
  ASSERT_EQ(parsed.error, "");
  SensorParams p = parsed.params.sensors.at(0);
  ASSERT_TRUE(p.calibrated);
  const auto at_10_hz = p.calibrated;
  ASSERT_EQ(at_10_hz->size(), 16 * 1808);
  LiveParams live = liveParams(p);
  live.rate = 20.0;
  ASSERT_EQ(applyLiveParams(live, &p), "");
  ASSERT_TRUE(p.calibrated);
  EXPECT_EQ(at_10_hz->size(), 16 * 1808);  // the list a cast may hold is left as it was
  ASSERT_EQ(p.calibrated->size(), 16 * static_cast<int>(0.05 / 55.296e-6));  // 904 sequences
  // Laser id 0 of sequence 903 (ring 0, -15 deg): at 903 * 55.296 us, the head at pi less the
  // share of a 0.05 s turn.
  const int b = 903 * 16;
  const double t = vlp16FiringTime(903, 0);
  EXPECT_NEAR(p.calibrated->time(b), t, 1e-15);
  const Eigen::Vector3d& d = p.calibrated->directions[b];
  EXPECT_NEAR(std::remainder(std::atan2(d.y(), d.x()) - vlp16HeadAzimuth(t, 0.05), 2 * M_PI), 0.0,
              1e-12);
  EXPECT_NEAR(p.sweepDuration(), p.calibrated->times.back(), 0.0);

  // scan_time set: the turn does not follow the rate.
  SensorParams fixed = parsed.params.sensors.at(0);
  fixed.scan_time = 0.1;
  const auto before = fixed.calibrated;
  live.rate = 5.0;
  ASSERT_EQ(applyLiveParams(live, &fixed), "");
  EXPECT_EQ(fixed.calibrated, before);
  // Refused (too fast for that scan_time): the turn stays too.
  live.rate = 20.0;
  EXPECT_NE(applyLiveParams(live, &fixed), "");
  EXPECT_EQ(fixed.calibrated, before);

  // A 40 s turn would fire 11.6M beams.
  SensorParams slow = parsed.params.sensors.at(0);
  live.rate = 0.025;
  expectRefused(live, slow, {"rate 0.025 Hz", "VLP-16 preset's lasers", "40 s", "10000000"});
  EXPECT_EQ(slow.calibrated->size(), 16 * 1808);
}

TEST(LiveParams, RatesOutsideTheRangeAreRefused) {
  for (const double rate : {0.0, -1.0, 1000.5, std::numeric_limits<double>::quiet_NaN(),
                            std::numeric_limits<double>::infinity()}) {
    LiveParams live = liveParams(SensorParams());
    live.rate = rate;
    expectRefused(live, SensorParams(), {"rate must be in (0, 1000] Hz"});
  }
}

// The measurement model's own validation, naming the field.
TEST(LiveParams, InconsistentOutputSettingsAreRefused) {
  LiveParams live = liveParams(SensorParams());
  live.output.range_min = 6.0;
  live.output.range_max = 4.5;
  expectRefused(live, SensorParams(), {"range_max"});
  live = liveParams(SensorParams());
  live.output.dropout_probability = 1.5;
  expectRefused(live, SensorParams(), {"dropout_probability", "1.5"});
}

TEST(LiveParams, AnAcceptedChangeIsApplied) {
  SensorParams p;
  LiveParams live = liveParams(p);
  live.rate = 5.0;
  live.output.intensity = true;
  live.output.range_max = 4.5;
  ASSERT_EQ(applyLiveParams(live, &p), "");
  EXPECT_EQ(p.rate, 5.0);
  EXPECT_TRUE(p.scan.output.intensity);
  EXPECT_EQ(p.scan.output.range_max, 4.5);
  EXPECT_EQ(liveParams(p).rate, 5.0);
}

}  // namespace
}  // namespace laser_raycast_test
