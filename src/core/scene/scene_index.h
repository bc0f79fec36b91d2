// The bodies of a scene grouped by the frame that moves them, each group with a 4-wide BVH over its
// bodies' boxes in that frame: the caster's top level. Bodies on one frame keep their relative
// poses, so the trees are built once per scene (Scene::version()) and each scan places a whole
// group with its frame's pose.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "laser_raycast/core/bvh.h"
#include "laser_raycast/core/scene.h"
#include "accel/wide_bvh.h"

namespace laser_raycast {
namespace core {

class SceneIndex {
 public:
  struct Group {
    int frame;
    std::vector<int> bodies;  // the group's bodies (indices into Scene::bodies())
    Bvh tree;                 // over the bodies' boxes in the frame: item i is bodies[i]
    WideBvh wide;             // the caster's layout of tree
  };

  explicit SceneIndex(const Scene& scene);
  SceneIndex(const SceneIndex&) = delete;
  SceneIndex& operator=(const SceneIndex&) = delete;

  std::uint64_t sceneVersion() const { return version_; }
  // One per frame that has bodies, in frame order. A group's WideBvh refers to its Bvh, so the
  // groups stay where they were built.
  const std::vector<std::unique_ptr<Group>>& groups() const { return groups_; }

 private:
  std::uint64_t version_;
  std::vector<std::unique_ptr<Group>> groups_;
};

}  // namespace core
}  // namespace laser_raycast
