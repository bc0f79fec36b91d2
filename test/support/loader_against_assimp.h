// A check shared by the tests of the loader's own mesh readers (test_obj_reader, test_ply_reader):
// a file loaded through the scene loader, whose importer process reads it, against assimp reading
// it in the test's process. Needs src/loader on the include path and assimp linked.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <string>

#include "laser_raycast/core/mesh.h"
#include "laser_raycast/loader/scene_loader.h"
#include "mesh_import.h"

namespace laser_raycast_test {

// The loader's mesh of path, scaled, has assimp's vertices and triangles, bit for bit.
inline void expectLoaderGivesAssimpsMesh(const std::string& path, const Eigen::Vector3d& scale) {
  SCOPED_TRACE(path);
  laser_raycast::SceneLoader loader(nullptr);
  const auto mesh = loader.loadMesh(path, "", scale, {});
  const laser_raycast::mesh_file::MeshData theirs =
      laser_raycast::mesh_file::importMeshInProcess(path, scale);
  EXPECT_EQ(mesh->vertices().toVector(), theirs.vertices);
  EXPECT_EQ(mesh->triangles(), theirs.triangles);
}

}  // namespace laser_raycast_test
