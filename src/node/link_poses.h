// The poses of the scene's link frames at scan times, looked up in TF once per time for every
// sensor that needs them. Sensors due at one stamp need different times when their sweeps differ
// (an instantaneous scan needs its stamp, a rotating one the stamp and times across its sweep):
// they are separate jobs of the scan queue, cast as each one's transforms come, and take the poses
// at a time another job already looked up from here. Times are forgotten once no queued scan can
// need them. Not thread-safe (the cast thread's own). Pure apart from the look-up it is given, so
// unit tests count the look-ups.
#pragma once

#include <ros/time.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "laser_raycast/core/scene.h"

namespace laser_raycast {

// The pose of `frame` in the fixed frame at t; false with the reason in *error.
using TimedPoseLookup = std::function<bool(const std::string& frame, const ros::Time& t,
                                           Eigen::Isometry3d* pose, std::string* error)>;

// Whether `frame`'s pose in the fixed frame is the same at every time (TF holds only static
// transforms between them): then a scan's several times take it from one look-up.
using StaticFrameCheck = std::function<bool(const std::string& frame)>;

// The link poses of one scan.
struct LinkPosesAt {
  std::vector<core::FramePoses> frames;  // one per time asked for
  std::vector<std::string> missing;      // frames without a pose at some of the times
  std::uint64_t failures = 0;            // (frame, time) pairs without a pose
  std::string first_error;               // the look-up's message for the first of them
};

class LinkPoses {
 public:
  // At most this many times are kept, whatever the queue holds (a backstop: forgetBefore keeps
  // far fewer, the times of the scans still queued).
  static constexpr std::size_t kMaxTimes = 1024;

  // scene must outlive this. Without is_static every frame is looked up at every time.
  LinkPoses(const core::Scene& scene, TimedPoseLookup lookup, StaticFrameCheck is_static = {});

  // Every frame at each of `times`: looked up at a time not seen since it was last forgotten,
  // taken from here otherwise. When two or more times are new, a frame that is_static says is
  // static is looked up at the first of them only, and its pose (or failure) copied to the rest:
  // a rotating scan's sweep samples of a warehouse's hundreds of fixed links cost one look-up
  // each, not one a sample.
  LinkPosesAt at(const std::vector<ros::Time>& times);
  // Forgets the times before t.
  void forgetBefore(const ros::Time& t);

  std::size_t times() const { return entries_.size(); }
  // Calls of the look-up so far (one per frame and time looked up).
  std::uint64_t lookups() const { return lookups_; }

 private:
  struct Entry {
    core::FramePoses poses;
    std::uint64_t failures = 0;
    std::string first_error;
  };

  // The entry at t, looked up unless already here; `copy` (if not null) gives the frames marked in
  // `fixed` instead of looking them up.
  const Entry& entry(const ros::Time& t, const std::vector<char>& fixed, const Entry* copy);

  const core::Scene& scene_;
  TimedPoseLookup lookup_;
  StaticFrameCheck is_static_;
  std::map<ros::Time, Entry> entries_;
  std::uint64_t lookups_ = 0;
};

}  // namespace laser_raycast
