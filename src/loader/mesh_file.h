// Mesh files for the scene loader: where a URDF mesh URI points, and the triangles a file holds
// (through assimp) in link-local geometry coordinates. Private to the loader library.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "laser_raycast/core/bvh.h"
#include "laser_raycast/loader/errors.h"
#include "laser_raycast/loader/package_resolver.h"

namespace laser_raycast {
namespace mesh_file {

// The local path a mesh URI names: package://pkg/path (through resolver), file:///abs/path, an
// absolute path, or a path relative to base_dir (an error if base_dir is ""). Any other scheme is
// an error. Throws SceneLoadError with the problem; the caller names the URI.
std::string resolveUri(const std::string& uri, const std::string& base_dir,
                       const PackageResolver& resolver);

struct MeshData {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<core::TriangleIndices> triangles;
};

// The file's triangles as v' = scale ⊙ (unit · node_transform · v): the Collada <unit> applied,
// the node transforms accumulated from the root's children down, the root's own transformation
// (assimp's unit and up-axis conversion) ignored, as RViz and geometric_shapes do. Points and
// lines are left out. Throws SceneLoadError with the problem (no vertices, no triangles, a
// non-finite vertex, what assimp could not read); the caller names the file.
MeshData readMeshFile(const std::string& path, const Eigen::Vector3d& scale);

}  // namespace mesh_file
}  // namespace laser_raycast
