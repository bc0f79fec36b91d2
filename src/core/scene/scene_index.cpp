#include "scene/scene_index.h"

#include <cmath>

namespace laser_raycast {
namespace core {
namespace {

// A body's box (Scene::boxCenter/boxHalf, body frame) as a box in its frame: the corners' hull,
// computed with the box view's bound |R| e, widened for the rounding of the pose's product.
Aabb boxInFrame(const Scene& scene, int body) {
  const Eigen::Isometry3d& pose = scene.bodies()[body].frame_from_body;
  const Eigen::Vector3d center = pose * scene.boxCenter(body);
  Eigen::Vector3d half = pose.linear().cwiseAbs() * scene.boxHalf(body);
  half += 4 * std::numeric_limits<double>::epsilon() *
          (pose.linear().cwiseAbs() * scene.boxCenter(body).cwiseAbs() +
           pose.translation().cwiseAbs() + half);
  Aabb box;
  box.lo = center - half;
  box.hi = center + half;
  return box;
}

}  // namespace

SceneIndex::SceneIndex(const Scene& scene) : version_(scene.version()) {
  std::vector<Group*> by_frame(scene.frames().size(), nullptr);
  for (std::size_t b = 0; b < scene.bodies().size(); ++b) {
    const int frame = scene.bodies()[b].frame;
    if (!by_frame[frame]) {
      groups_.push_back(std::make_unique<Group>());
      groups_.back()->frame = frame;
      by_frame[frame] = groups_.back().get();
    }
    by_frame[frame]->bodies.push_back(static_cast<int>(b));
  }
  std::sort(groups_.begin(), groups_.end(),
            [](const auto& a, const auto& b) { return a->frame < b->frame; });
  for (auto& group : groups_) {
    std::vector<Aabb> boxes;
    for (const int body : group->bodies) boxes.push_back(boxInFrame(scene, body));
    group->tree = Bvh::buildOverBoxes(boxes);
    group->wide = WideBvh(group->tree, {});
  }
}

}  // namespace core
}  // namespace laser_raycast
