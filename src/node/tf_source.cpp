#include "tf_source.h"

#include <tf2_eigen/tf2_eigen.h>

namespace laser_raycast {

std::optional<ros::Time> TfSource::latest(const std::string& target, const std::string& source,
                                          std::string* error) const {
  if (target == source) return ros::Time(0);
  try {
    // At time 0 tf2 gives the newest time every transform of the chain has data for.
    return buffer_.lookupTransform(target, source, ros::Time(0)).header.stamp;
  } catch (const tf2::TransformException& e) {
    if (error) *error = e.what();
    return std::nullopt;
  }
}

FrameAvailability TfSource::availability(const std::string& target, const std::string& source,
                                         const ros::Time& needed, const ros::Time& now,
                                         const ros::Duration& tf_timeout) const {
  return frameAvailability(latest(target, source, nullptr), needed, now, tf_timeout);
}

bool TfSource::lookup(const std::string& target, const std::string& source, const ros::Time& t,
                      Eigen::Isometry3d* pose, std::string* error) const {
  if (target == source) {
    pose->setIdentity();
    return true;
  }
  try {
    *pose = tf2::transformToEigen(buffer_.lookupTransform(target, source, t));
    return true;
  } catch (const tf2::TransformException& e) {
    if (error) *error = e.what();
    return false;
  }
}

}  // namespace laser_raycast
