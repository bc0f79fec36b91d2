// Mesh files for the scene loader: where a URDF mesh URI points, and what reading one gives.
// Private to the loader library.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "laser_raycast/core/bvh.h"
#include "laser_raycast/core/surface.h"
#include "laser_raycast/loader/errors.h"
#include "laser_raycast/loader/package_resolver.h"

namespace laser_raycast {
namespace mesh_file {

// The local path a mesh URI names: package://pkg/path (through resolver), file:///abs/path, an
// absolute path, or a path relative to base_dir (an error if base_dir is ""). Any other scheme is
// an error. Throws SceneLoadError with the problem; the caller names the URI.
std::string resolveUri(const std::string& uri, const std::string& base_dir,
                       const PackageResolver& resolver);

// The path's extension in lower case (".stl" for "a/B.STL"): assimp chooses its importer by it, in
// any case, and so do the loader's own readers.
inline std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// A file the loader's own readers read (stl_reader, obj_reader, ply_reader), closed when it goes.
using File = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;

// The file at path opened for reading; throws SceneLoadError saying why if it cannot be.
inline File openMeshFile(const std::string& path) {
  File file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw SceneLoadError(std::string("cannot open it: ") + std::strerror(errno));
  return file;
}

// A mesh file's triangles (import_process.h reads them), in link-local coordinates.
struct MeshData {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<core::TriangleIndices> triangles;
  // Colours, texture coordinates, normals and materials, when the file has any (assimp formats).
  std::shared_ptr<core::SurfaceAttributes> surface;
};

}  // namespace mesh_file
}  // namespace laser_raycast
