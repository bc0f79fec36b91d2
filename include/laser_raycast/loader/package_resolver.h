// package:// URIs: the scene loader finds a package's directory through a resolver it is given, so
// tests pass their own look-up.
#pragma once

#include <functional>
#include <optional>
#include <string>

namespace laser_raycast {

// Returns the directory of a ROS package, or nullopt if it is unknown.
using PackageResolver = std::function<std::optional<std::string>(const std::string& package)>;

}  // namespace laser_raycast
