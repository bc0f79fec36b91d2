// The peers, on the same soup and the same float rays as the core's float methods, single-threaded:
// Embree 3 (rtcIntersect1; default scene flags and RTC_SCENE_FLAG_ROBUST) and Bullet
// (btBvhTriangleMeshShape::performRaycast with a btTriangleRaycastCallback). Each is compiled in
// only when CMake found it (LASER_RAYCAST_HAVE_EMBREE, LASER_RAYCAST_HAVE_BULLET); without it there
// are simply no rows for it.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "bench_methods.h"
#include "laser_raycast/core/mesh.h"

namespace laser_raycast {
namespace bench {

// The peers' rows for a soup, those wanted (each holds its own acceleration structure, built
// here); the Embree rows are paired with the pipeline for timing. Throws std::runtime_error if a
// peer reports an error.
std::vector<Method> peerMethods(const MeshData& soup, const MethodFilter& wanted);
// Their names, in the same order, for --list-methods.
std::vector<std::string> peerMethodNames();
// The peers compiled in, with their versions (e.g. "Embree 3.13.5, Bullet 3.24"), or "none".
std::string peerVersions();
// The bytes Embree holds for the mesh (in its own frame) built alone as the embree_default row
// builds the soup (default flags, float vertices, one geometry), as its device's memory monitor
// counts them: its BVH with triangle leaves and its vertex and index buffers. Nullopt without
// Embree. Throws std::runtime_error if Embree reports an error.
std::optional<std::size_t> embreeMeshBytes(const core::Mesh& mesh);
// Wall clock seconds for assimp to read the mesh file (with the mesh importer's post-processing)
// and Embree to build its BVH (default flags, one build thread, its meshes as geometries of one
// scene, their float vertices copied straight into Embree's buffers). Nullopt without Embree.
// Throws std::runtime_error if assimp cannot read the file or Embree reports an error.
std::optional<double> assimpEmbreeLoadSeconds(const std::string& path);

}  // namespace bench
}  // namespace laser_raycast
