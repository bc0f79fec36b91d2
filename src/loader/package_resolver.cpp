#include "laser_raycast/loader/package_resolver.h"

#include <ros/package.h>

#include <exception>
#include <filesystem>

#include "laser_raycast/loader/errors.h"

namespace laser_raycast {
namespace {

const std::string kScheme = "package://";

std::string inQuotes(const std::string& s) { return "'" + s + "'"; }

}  // namespace

std::optional<std::string> rosPackagePath(const std::string& package) {
  const std::string path = ros::package::getPath(package);
  if (path.empty()) return std::nullopt;
  return path;
}

bool isPackageUri(const std::string& uri) { return uri.compare(0, kScheme.size(), kScheme) == 0; }

std::string resolvePackageUri(const std::string& uri, const PackageResolver& resolver) {
  const std::string rest = isPackageUri(uri) ? uri.substr(kScheme.size()) : "";
  const std::size_t slash = rest.find('/');
  if (slash == 0 || slash == std::string::npos || slash + 1 == rest.size()) {
    throw SceneLoadError("a package:// URI needs a package name and a path");
  }
  const std::string package = rest.substr(0, slash);
  if (!resolver) throw SceneLoadError("no package resolver to find package " + inQuotes(package));
  std::optional<std::string> dir;
  try {
    dir = resolver(package);
  } catch (const std::exception& e) {
    throw SceneLoadError("resolving package " + inQuotes(package) + " failed: " + e.what());
  }
  if (!dir || dir->empty()) throw SceneLoadError("unknown package " + inQuotes(package));
  return (std::filesystem::path(*dir) / rest.substr(slash + 1)).string();
}

}  // namespace laser_raycast
