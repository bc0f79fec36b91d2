// Binary PLY files of plain triangles read without assimp, as obj_reader.h does for OBJ: assimp's
// PLY importer and its post-processing take longer than the BVH build on a mesh of a million
// triangles. This reader reads a binary little-endian file whose vertices have x, y, z in float and
// nothing else, and whose faces have only their vertex indices, three a face, and gives the result
// the assimp path gives: the vertices that faces use, in the file's order, joined where their
// coordinates are equal, and no surface attributes. Every other PLY (ASCII or big-endian, double
// coordinates, colours, normals, texture coordinates, other elements or properties, polygons,
// anything malformed or out of range) it leaves to assimp, which reads those and reports what is
// wrong. The importer executable (laser_raycast_mesh_import) calls it for *.ply files. Private to
// the loader.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>

#include "mesh_file.h"

namespace laser_raycast {
namespace mesh_file {

// Whether the path names a PLY file (extension .ply in any case), as assimp tells its importer.
bool isPlyPath(const std::string& path);

// The file's triangles if it is a plain binary PLY (nullopt otherwise: read it with assimp):
//   ply
//   format binary_little_endian 1.0
//   comment ... / obj_info ...                  (any number, anywhere in the header)
//   element vertex N
//   property float x / float y / float z        (float or float32, in this order, nothing else)
//   element face M
//   property list C I vertex_indices            (or vertex_index; C an unsigned 8-, 16- or 32-bit
//                                                count, I an 8-, 16- or 32-bit index)
//   end_header
// then N vertices and M faces, every face of three indices, each naming one of the N vertices,
// every coordinate finite (of used vertices and unused ones alike, as the assimp path checks).
// Vertices scaled as readStl's (v' = scale ⊙ v, rounded as the assimp path's). Throws
// SceneLoadError when the file cannot be read.
std::optional<MeshData> readPlainPly(const std::string& path, const Eigen::Vector3d& scale);

}  // namespace mesh_file
}  // namespace laser_raycast
