// STL files read without assimp, for meshes of tens of millions of triangles: assimp holds the
// whole file, then a vertex per corner with its facet's normal, then the joined copy (a 4M-triangle
// binary STL took 5.8 GB and 28 s). This reader streams the file in chunks and joins identical
// vertices as it goes, so it holds little more than the mesh it returns. The importer executable
// (laser_raycast_mesh_import) calls it for *.stl files, under the same bounds as assimp (with a
// smaller memory bound per file byte: MeshImportBounds::forFile). Private to the loader.
#pragma once

#include <Eigen/Geometry>
#include <string>

#include "mesh_file.h"

namespace laser_raycast {
namespace mesh_file {

// Whether the path names an STL file (extension .stl in any case), which readStl reads rather than
// assimp: assimp chooses its importer by the extension too.
bool isStlPath(const std::string& path);

// The file's triangles, binary or ASCII, as assimp's STL importer tells them apart: binary when the
// file is exactly 84 + 50 N bytes for the N triangles its header counts, else ASCII when it starts
// with "solid". Triangles in file order, scaled (v' = scale ⊙ v, rounded as the assimp path's);
// vertices with equal coordinates are one vertex (the first one's index), across the whole file.
// Degenerate triangles are kept (core::Mesh leaves them out of its BVH). Throws SceneLoadError
// with the problem (neither binary nor ASCII, truncated, a non-finite vertex, no triangles, a
// malformed ASCII line, with its number); the caller names the file.
MeshData readStl(const std::string& path, const Eigen::Vector3d& scale);

}  // namespace mesh_file
}  // namespace laser_raycast
