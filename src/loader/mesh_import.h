// A mesh file's triangles read with assimp, in this process. Only the importer executable
// (laser_raycast_mesh_import) calls it: the loader runs that under MeshImportBounds
// (import_process.h), because assimp can allocate without limit, loop or crash on corrupt files.
// Private to the loader.
#pragma once

#include <Eigen/Geometry>
#include <string>

#include "mesh_file.h"

namespace laser_raycast {
namespace mesh_file {

// The file's triangles as v' = scale ⊙ (unit · node_transform · v): the Collada <unit> applied,
// the node transforms accumulated from the root's children down, the root's own transformation
// (assimp's unit and up-axis conversion) ignored, as RViz and geometric_shapes do. Points and
// lines are left out. Throws SceneLoadError with the problem (no vertices, no triangles, a
// non-finite vertex, what assimp could not read); the caller names the file.
MeshData importMeshInProcess(const std::string& path, const Eigen::Vector3d& scale);

}  // namespace mesh_file
}  // namespace laser_raycast
