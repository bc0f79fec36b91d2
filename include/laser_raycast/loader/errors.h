// The error the scene loader throws for bad input.
#pragma once

#include <stdexcept>

namespace laser_raycast {

// A bad model: the message names the file, the link and the problem.
class SceneLoadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace laser_raycast
