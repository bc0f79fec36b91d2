// The node's TF timing policy, as pure functions of times (no TF, no roscore), so that unit tests
// check it directly. A scan is cast in the node's cast thread once every transform it needs can be
// looked up at its last beam's time; the timer that schedules scans never waits. A transform that
// is late but alive is waited for; one whose newest data is older than ~tf_timeout is not (its
// link is left out, or, for the sensor, the scan is skipped), so a dead publisher delays no scan
// for longer than ~tf_timeout, once, and then none.
#pragma once

#include <ros/time.h>

#include <optional>
#include <vector>

namespace laser_raycast {

enum class FrameAvailability {
  kCovered,  // TF can give the transform at the time needed (or it is static)
  kWaiting,  // not yet, but its newest data is at most tf_timeout old: late, not dead
  kStale,    // its newest data is older than tf_timeout: not waited for
  kMissing,  // TF has no transform for it at all
};

const char* toString(FrameAvailability availability);

// Whether a transform can be used for a scan whose last beam is at `needed`, at time `now`.
// `latest` is the newest time TF can give it at (ros::Time(0): static, any time), nullopt if TF has
// none. Since needed <= now in a scan's life, a transform still missing tf_timeout after `needed`
// is stale: tf_timeout bounds every wait.
FrameAvailability frameAvailability(const std::optional<ros::Time>& latest, const ros::Time& needed,
                                    const ros::Time& now, const ros::Duration& tf_timeout);

// The times at which a scan looks its poses up: `stamp` alone for an instantaneous scan (duration
// 0), else from stamp to stamp + duration inclusive, evenly, at most `spacing` apart (at least
// two). Poses between them are interpolated (core::PoseSamples).
std::vector<ros::Time> sampleTimes(const ros::Time& stamp, const ros::Duration& duration,
                                   const ros::Duration& spacing);

// The multiple of `period` nearest to `t` (whole nanoseconds since the epoch). Scan times on this
// grid coincide between sensors whose periods are multiples of each other, so that they share
// their TF look-ups.
ros::Time nearestMultiple(const ros::Time& t, const ros::Duration& period);
// How long from `t` to the next multiple of period after it.
ros::Duration untilNextMultiple(const ros::Time& t, const ros::Duration& period);

}  // namespace laser_raycast
