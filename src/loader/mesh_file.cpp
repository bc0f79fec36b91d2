#include "mesh_file.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "laser_raycast/loader/errors.h"

namespace laser_raycast {
namespace mesh_file {
namespace {

namespace fs = std::filesystem;

std::string inQuotes(const std::string& s) { return "'" + s + "'"; }

// ---------------------------------------------------------------------------------------------------
// Mesh URIs

// "package", "file", "http"... for "scheme://rest"; empty for a plain path.
std::string uriScheme(const std::string& uri) {
  const std::size_t sep = uri.find("://");
  if (sep == std::string::npos || sep == 0) return "";
  const std::string scheme = uri.substr(0, sep);
  const bool is_scheme =
      std::isalpha(static_cast<unsigned char>(scheme[0])) &&
      std::all_of(scheme.begin(), scheme.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '+' || c == '-' || c == '.';
      });
  return is_scheme ? scheme : "";
}

}  // namespace

std::string resolveUri(const std::string& uri, const std::string& base_dir,
                       const PackageResolver& resolver) {
  if (uri.empty()) throw SceneLoadError("the mesh filename is empty");
  const std::string scheme = uriScheme(uri);
  const std::string rest = scheme.empty() ? uri : uri.substr(scheme.size() + 3);
  if (scheme == "package") return resolvePackageUri(uri, resolver);
  if (scheme == "file") {
    // file:///abs/path; a host part (file://host/...) is not a local file.
    if (rest.empty() || rest[0] != '/') {
      throw SceneLoadError("a file:// URI must hold an absolute path (file:///dir/mesh.stl)");
    }
    return rest;
  }
  if (!scheme.empty()) {
    throw SceneLoadError("unsupported URI scheme " + inQuotes(scheme + "://") +
                         " (use package://, file://, or a path)");
  }
  if (fs::path(uri).is_absolute()) return uri;
  if (base_dir.empty()) {
    throw SceneLoadError(
        "a relative mesh path needs the URDF's directory, but this URDF came from a string "
        "without one");
  }
  return (fs::path(base_dir) / uri).string();
}

}  // namespace mesh_file
}  // namespace laser_raycast
