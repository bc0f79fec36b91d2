#include "link_poses.h"

#include <utility>

namespace laser_raycast {

LinkPoses::LinkPoses(const core::Scene& scene, TimedPoseLookup lookup,
                     StaticFrameCheck is_static)
    : scene_(scene), lookup_(std::move(lookup)), is_static_(std::move(is_static)) {}

const LinkPoses::Entry& LinkPoses::entry(const ros::Time& t, const std::vector<char>& fixed,
                                         const Entry* copy) {
  const auto found = entries_.find(t);
  if (found != entries_.end()) return found->second;
  Entry e;
  int f = 0;
  core::resolveFramePoses(
      scene_,
      [&](const std::string& frame, Eigen::Isometry3d& pose) {
        // resolveFramePoses asks for the scene's frames in order.
        const int index = f++;
        if (copy && fixed[index] && scene_.frames()[index] == frame) {
          pose = copy->poses.pose[index];
          if (copy->poses.valid[index]) return true;
          if (e.first_error.empty()) e.first_error = copy->first_error;
          return false;
        }
        ++lookups_;
        std::string error;
        if (lookup_(frame, t, &pose, &error)) return true;
        if (e.first_error.empty()) e.first_error = error;
        return false;
      },
      &e.poses);
  // resolveFramePoses also refuses a pose that is not a finite rigid transform.
  for (const char valid : e.poses.valid) e.failures += !valid;
  return entries_.emplace(t, std::move(e)).first->second;
}

LinkPosesAt LinkPoses::at(const std::vector<ros::Time>& times) {
  // The static frames, asked only when they save look-ups: at two or more new times.
  std::vector<char> fixed;
  if (is_static_) {
    std::size_t fresh = 0;
    for (const ros::Time& t : times) fresh += entries_.count(t) == 0;
    if (fresh > 1) {
      fixed.reserve(scene_.frames().size());
      for (const std::string& frame : scene_.frames()) fixed.push_back(is_static_(frame));
    }
  }
  LinkPosesAt out;
  out.frames.reserve(times.size());
  std::vector<char> lost(scene_.frames().size(), 0);
  const Entry* first = nullptr;  // the first entry looked up here: the static frames' source
  for (const ros::Time& t : times) {
    const bool looked_up = entries_.count(t) == 0;
    const Entry& e = entry(t, fixed, fixed.empty() ? nullptr : first);
    if (looked_up && !first) first = &e;
    out.frames.push_back(e.poses);
    out.failures += e.failures;
    if (out.first_error.empty()) out.first_error = e.first_error;
    for (std::size_t f = 0; f < lost.size(); ++f) lost[f] |= !e.poses.valid[f];
  }
  for (std::size_t f = 0; f < lost.size(); ++f) {
    if (lost[f]) out.missing.push_back(scene_.frames()[f]);
  }
  while (entries_.size() > kMaxTimes) entries_.erase(entries_.begin());
  return out;
}

void LinkPoses::forgetBefore(const ros::Time& t) {
  entries_.erase(entries_.begin(), entries_.lower_bound(t));
}

}  // namespace laser_raycast
