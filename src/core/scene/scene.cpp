#include "laser_raycast/core/scene.h"

#include <algorithm>
#include <atomic>
#include <sstream>
#include <stdexcept>

#include "laser_raycast/core/pose.h"

namespace laser_raycast {
namespace core {
namespace {

int findOrAdd(std::vector<std::string>* names, const std::string& name) {
  const auto it = std::find(names->begin(), names->end(), name);
  if (it != names->end()) return static_cast<int>(it - names->begin());
  names->push_back(name);
  return static_cast<int>(names->size()) - 1;
}

std::uint64_t nextVersion() {
  static std::atomic<std::uint64_t> counter{0};
  return ++counter;
}

// A sphere containing the shape, in the shape's frame.
void boundingSphere(const Shape& shape, Eigen::Vector3d* center, double* radius) {
  if (const auto* mesh = std::get_if<std::shared_ptr<const Mesh>>(&shape)) {
    *center = (*mesh)->sphereCenter();
    *radius = (*mesh)->sphereRadius();
    return;
  }
  *center = Eigen::Vector3d::Zero();
  if (const auto* box = std::get_if<Box>(&shape)) {
    *radius = (box->size * 0.5).norm();
  } else if (const auto* cylinder = std::get_if<Cylinder>(&shape)) {
    *radius = std::hypot(cylinder->radius, cylinder->length * 0.5);
  } else {
    *radius = std::get<Sphere>(shape).radius;
  }
  *radius *= 1 + 4 * std::numeric_limits<double>::epsilon();  // the norm's rounding
}

// A box containing the shape, in the shape's frame: centre and half extents, rounded up a few ulps.
void boundingBox(const Shape& shape, Eigen::Vector3d* center, Eigen::Vector3d* half) {
  *center = Eigen::Vector3d::Zero();
  if (const auto* mesh = std::get_if<std::shared_ptr<const Mesh>>(&shape)) {
    *center = (*mesh)->bounds().center();
    *half = (*mesh)->bounds().extent() * 0.5;
  } else if (const auto* box = std::get_if<Box>(&shape)) {
    *half = box->size * 0.5;
  } else if (const auto* cylinder = std::get_if<Cylinder>(&shape)) {
    *half = Eigen::Vector3d(cylinder->radius, cylinder->radius, cylinder->length * 0.5);
  } else {
    *half = Eigen::Vector3d::Constant(std::get<Sphere>(shape).radius);
  }
  *half *= 1 + 4 * std::numeric_limits<double>::epsilon();  // the halving's and centre's rounding
  *half += 4 * std::numeric_limits<double>::epsilon() * center->cwiseAbs();
}

}  // namespace

Scene::Scene() : version_(nextVersion()) {}

int Scene::addFrame(const std::string& name) {
  version_ = nextVersion();
  return findOrAdd(&frames_, name);
}

int Scene::addLabel(const std::string& name) {
  version_ = nextVersion();
  return findOrAdd(&labels_, name);
}

int Scene::addBody(Body body) {
  std::ostringstream msg;
  if (body.frame < 0 || body.frame >= static_cast<int>(frames_.size())) {
    msg << "body frame index " << body.frame << " out of range (" << frames_.size() << " frames)";
  } else if (body.label < 0 || body.label >= static_cast<int>(labels_.size())) {
    msg << "body label index " << body.label << " out of range (" << labels_.size() << " labels)";
  } else if (!isValidPose(body.frame_from_body)) {
    msg << "body pose in frame '" << frames_[body.frame] << "' is not a finite rigid transform";
  } else if (const auto* mesh = std::get_if<std::shared_ptr<const Mesh>>(&body.shape);
             mesh && !*mesh) {
    msg << "body in frame '" << frames_[body.frame] << "' has a null mesh";
  } else if (body.has_color && !(body.color.allFinite() && body.color.minCoeff() >= 0 &&
                                 body.color.maxCoeff() <= 1)) {
    msg << "body colour in frame '" << frames_[body.frame] << "' is not RGB in [0, 1]";
  }
  if (!msg.str().empty()) throw std::invalid_argument(msg.str());
  if (const auto* box = std::get_if<Box>(&body.shape)) validate(*box);
  if (const auto* cylinder = std::get_if<Cylinder>(&body.shape)) validate(*cylinder);
  if (const auto* sphere = std::get_if<Sphere>(&body.shape)) validate(*sphere);

  Eigen::Vector3d center;
  double radius;
  boundingSphere(body.shape, &center, &radius);
  sphere_centers_.push_back(center);
  sphere_radii_.push_back(radius);
  Eigen::Vector3d box_center, box_half;
  boundingBox(body.shape, &box_center, &box_half);
  box_centers_.push_back(box_center);
  box_halves_.push_back(box_half);
  bodies_.push_back(std::move(body));
  version_ = nextVersion();
  return static_cast<int>(bodies_.size()) - 1;
}

std::size_t Scene::triangleCount() const {
  std::size_t n = 0;
  for (const Body& body : bodies_) {
    if (const auto* mesh = std::get_if<std::shared_ptr<const Mesh>>(&body.shape)) {
      n += (*mesh)->triangles().size();
    }
  }
  return n;
}

FramePoses FramePoses::identity(const Scene& scene) {
  FramePoses poses;
  poses.pose.assign(scene.frames().size(), Eigen::Isometry3d::Identity());
  poses.valid.assign(scene.frames().size(), 1);
  return poses;
}

int resolveFramePoses(const Scene& scene, const PoseLookup& lookup, FramePoses* poses) {
  const std::size_t n = scene.frames().size();
  poses->pose.resize(n);
  poses->valid.assign(n, 0);
  int missing = 0;
  for (std::size_t i = 0; i < n; ++i) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    const bool ok = lookup(scene.frames()[i], pose) && isValidPose(pose);
    poses->pose[i] = pose;
    poses->valid[i] = ok ? 1 : 0;
    if (!ok) ++missing;
  }
  return missing;
}

}  // namespace core
}  // namespace laser_raycast
