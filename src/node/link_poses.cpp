#include "link_poses.h"

#include <utility>

namespace laser_raycast {

LinkPoses::LinkPoses(const core::Scene& scene, TimedPoseLookup lookup)
    : scene_(scene), lookup_(std::move(lookup)) {}

const LinkPoses::Entry& LinkPoses::entry(const ros::Time& t) {
  const auto found = entries_.find(t);
  if (found != entries_.end()) return found->second;
  Entry e;
  core::resolveFramePoses(
      scene_,
      [&](const std::string& frame, Eigen::Isometry3d& pose) {
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
  LinkPosesAt out;
  out.frames.reserve(times.size());
  std::vector<char> lost(scene_.frames().size(), 0);
  for (const ros::Time& t : times) {
    const Entry& e = entry(t);
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
