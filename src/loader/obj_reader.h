// Wavefront OBJ files of plain triangles read without assimp. assimp's OBJ importer and its
// post-processing took 3.5 s on a mesh of a million triangles, two to three times the BVH build's
// 1.0-1.7 s (this reader: 0.7-0.9 s). This reader reads what such a file holds, vertices and
// triangles, and gives the result the assimp path gives: the vertices that faces use, in the order
// of their first use, joined where their coordinates are equal. Whatever else a file holds
// (texture coordinates, normals, materials, polygons of more than three corners, lines, points,
// more than one group of faces, anything malformed) it leaves to assimp, which reads those and
// reports what is wrong. The importer executable (laser_raycast_mesh_import) calls it for *.obj
// files. Private to the loader.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>

#include "mesh_file.h"

namespace laser_raycast {
namespace mesh_file {

// Whether the path names an OBJ file (extension .obj in any case), as assimp tells its importer.
bool isObjPath(const std::string& path);

// The file's triangles if it holds nothing but what this reader reads (nullopt otherwise: read it
// with assimp):
//   v x y z        a vertex, three finite numbers
//   f a b c        a triangle, three vertex numbers (from 1; negative: counted back from the last
//                  vertex so far), each naming a vertex of the file
//   # ...          comments, blank lines, and 's' (smoothing groups, which only normals use)
//   o name, g name the object's or group's name, before the first face only
// Vertices scaled as readStl's (v' = scale ⊙ v, rounded as the assimp path's), numbers parsed
// correctly rounded to float (assimp's parser is off by one bit in some). Throws SceneLoadError
// when the file cannot be read.
std::optional<MeshData> readPlainObj(const std::string& path, const Eigen::Vector3d& scale);

}  // namespace mesh_file
}  // namespace laser_raycast
