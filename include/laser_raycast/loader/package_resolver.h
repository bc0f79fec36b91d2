// package:// URIs: the scene loader finds a package's directory through a resolver it is given, so
// tests pass their own look-up; rosPackagePath is the one for real use.
#pragma once

#include <functional>
#include <optional>
#include <string>

namespace laser_raycast {

// Returns the directory of a ROS package, or nullopt if it is unknown.
using PackageResolver = std::function<std::optional<std::string>(const std::string& package)>;

// The directory of a ROS package on ROS_PACKAGE_PATH, through roslib's ros::package::getPath,
// which needs no roscore and no roscpp; nullopt if it is not there.
std::optional<std::string> rosPackagePath(const std::string& package);

// Whether uri starts with package://.
bool isPackageUri(const std::string& uri);

// The local path that package://PACKAGE/PATH names: PATH in the directory resolver gives for
// PACKAGE. Throws SceneLoadError with the problem (no package name or path, no resolver, an unknown
// package); the caller names the URI.
std::string resolvePackageUri(const std::string& uri, const PackageResolver& resolver);

}  // namespace laser_raycast
