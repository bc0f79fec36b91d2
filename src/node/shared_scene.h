// The scene the cast thread casts, shared with what changes it while the node runs (scene_editor.h:
// a service call, or a new grid on a map topic). A scene is never changed in place: a new one is
// built beside it and swapped in whole, and the cast thread takes one at the start of each job and
// casts every sensor of the job with it, so no scan mixes the old scene and the new.
#pragma once

#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "laser_raycast/core/scene.h"

namespace laser_raycast {

// A scene and what the measurement model needs of it.
struct CastScene {
  core::Scene scene;
  std::vector<double> reflectivity;  // by label
  std::vector<char> reflectivity_fixed;  // by label: labelReflectivityFixed (scene_source.h)
};

class SharedScene {
 public:
  std::shared_ptr<const CastScene> current() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return current_;
  }
  void set(std::shared_ptr<const CastScene> scene) {
    std::lock_guard<std::mutex> lock(mutex_);
    current_ = std::move(scene);
  }

 private:
  mutable std::mutex mutex_;
  std::shared_ptr<const CastScene> current_;
};

}  // namespace laser_raycast
