#include "laser_raycast/core/pose_samples.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "laser_raycast/core/pose.h"

namespace laser_raycast {
namespace core {

Eigen::Isometry3d interpolatePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b,
                                  double s) {
  if (s == 0) return a;  // at a sample: its pose, as given
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  // Interpolated as a + s (b - a): the difference of nearby poses far from the origin is exact
  // (Sterbenz), so a pose 10^6 m out loses nothing.
  out.translation() = a.translation() + s * (b.translation() - a.translation());
  const Eigen::Quaterniond qa(a.linear()), qb(b.linear());
  out.linear() = qa.slerp(s, qb).toRotationMatrix();  // Eigen's slerp takes the shorter arc
  return out;
}

void PoseSamples::validate(const Scene& scene) const {
  std::ostringstream msg;
  if (times.empty()) {
    msg << "PoseSamples: no samples";
  } else if (world_from_sensor.size() != times.size() || frames.size() != times.size()) {
    msg << "PoseSamples: " << times.size() << " times but " << world_from_sensor.size()
        << " sensor poses and " << frames.size() << " frame pose sets";
  } else {
    // tellp(), not str(): str() copies the message at every sample.
    for (std::size_t i = 0; i < times.size() && msg.tellp() == 0; ++i) {
      if (!std::isfinite(times[i])) {
        msg << "PoseSamples: time " << i << " is not finite (" << times[i] << ")";
      } else if (i > 0 && !(times[i] > times[i - 1])) {
        msg << "PoseSamples: times must be strictly ascending, got " << times[i - 1] << " then "
            << times[i] << " s";
      } else if (frames[i].pose.size() != scene.frames().size() ||
                 frames[i].valid.size() != scene.frames().size()) {
        msg << "PoseSamples: sample " << i << " has " << frames[i].pose.size()
            << " frame poses for a scene of " << scene.frames().size() << " frames";
      }
    }
  }
  if (!msg.str().empty()) throw std::invalid_argument(msg.str());
}

void PoseSamples::bracket(double t, std::size_t* i, std::size_t* j, double* s) const {
  const auto after = std::upper_bound(times.begin(), times.end(), t);
  if (after == times.begin()) {
    *i = *j = 0;
    *s = 0;
  } else if (after == times.end()) {
    *i = *j = times.size() - 1;
    *s = 0;
  } else {
    *j = static_cast<std::size_t>(after - times.begin());
    *i = *j - 1;
    *s = (t - times[*i]) / (times[*j] - times[*i]);
    if (*s == 0) *j = *i;  // exactly at a sample: that sample alone
  }
}

Eigen::Isometry3d PoseSamples::sensorAt(double t) const {
  std::size_t i, j;
  double s;
  bracket(t, &i, &j, &s);
  if (!isValidPose(world_from_sensor[i]) || !isValidPose(world_from_sensor[j])) {
    Eigen::Isometry3d nan;
    nan.matrix().setConstant(std::numeric_limits<double>::quiet_NaN());
    return nan;
  }
  return interpolatePose(world_from_sensor[i], world_from_sensor[j], s);
}

void PoseSamples::framesAt(double t, FramePoses* out) const {
  const std::size_t n = frames.front().pose.size();
  out->pose.resize(n);
  out->valid.assign(n, 0);
  for (std::size_t f = 0; f < n; ++f) {
    out->pose[f] = Eigen::Isometry3d::Identity();
    out->valid[f] = frameAt(t, f, &out->pose[f]);
  }
}

bool PoseSamples::frameAt(double t, std::size_t f, Eigen::Isometry3d* pose) const {
  std::size_t i, j;
  double s;
  bracket(t, &i, &j, &s);
  const bool ok = frames[i].valid[f] && frames[j].valid[f] && isValidPose(frames[i].pose[f]) &&
                  isValidPose(frames[j].pose[f]);
  if (ok) *pose = interpolatePose(frames[i].pose[f], frames[j].pose[f], s);
  return ok;
}

}  // namespace core
}  // namespace laser_raycast
