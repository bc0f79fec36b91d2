#include "tf_timing.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace laser_raycast {

const char* toString(FrameAvailability availability) {
  switch (availability) {
    case FrameAvailability::kCovered:
      return "covered";
    case FrameAvailability::kWaiting:
      return "waiting";
    case FrameAvailability::kStale:
      return "stale";
    case FrameAvailability::kMissing:
      return "missing";
  }
  return "?";
}

FrameAvailability frameAvailability(const std::optional<ros::Time>& latest, const ros::Time& needed,
                                    const ros::Time& now, const ros::Duration& tf_timeout) {
  if (!latest) return FrameAvailability::kMissing;
  if (latest->isZero() || *latest >= needed) return FrameAvailability::kCovered;
  if (now - *latest <= tf_timeout) return FrameAvailability::kWaiting;
  return FrameAvailability::kStale;
}

std::vector<ros::Time> sampleTimes(const ros::Time& stamp, const ros::Duration& duration,
                                   const ros::Duration& spacing) {
  if (duration <= ros::Duration(0)) return {stamp};
  const std::int64_t total = duration.toNSec();
  const std::int64_t step = std::max<std::int64_t>(spacing.toNSec(), 1);
  const std::int64_t intervals = std::max<std::int64_t>(1, (total + step - 1) / step);
  std::vector<ros::Time> times;
  times.reserve(intervals + 1);
  for (std::int64_t i = 0; i <= intervals; ++i) {
    ros::Duration offset;
    offset.fromNSec(total / intervals * i + total % intervals * i / intervals);
    times.push_back(stamp + offset);
  }
  return times;
}

ros::Time nearestMultiple(const ros::Time& t, const ros::Duration& period) {
  const std::int64_t p = std::max<std::int64_t>(period.toNSec(), 1);
  const std::int64_t n = static_cast<std::int64_t>(t.toNSec());
  ros::Time out;
  out.fromNSec(static_cast<std::uint64_t>((n + p / 2) / p * p));
  return out;
}

ros::Duration untilNextMultiple(const ros::Time& t, const ros::Duration& period) {
  const std::int64_t p = std::max<std::int64_t>(period.toNSec(), 1);
  const std::int64_t n = static_cast<std::int64_t>(t.toNSec());
  ros::Duration out;
  out.fromNSec(p - n % p);
  return out;
}

}  // namespace laser_raycast
