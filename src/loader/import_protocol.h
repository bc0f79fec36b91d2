// How the loader and its mesh importer process (laser_raycast_mesh_import) talk over a socket: the
// loader sends a request per mesh file, the importer replies with the triangles it read or why it
// could not. Both ends are this package's code on the same machine, so numbers are in the
// machine's own representation; each end still checks every size and index, so that a truncated or
// garbled message is an error, not a bad mesh. Private to the loader.
//
//   request:  "LRMQ" u32 version, u32 N, N bytes (the file's path), 3 double (the scale)
//   reply:    "LRMI" u32 version, u32 status, then
//     status kMesh:  u64 V, u64 T, u64 A, V x 3 double (vertices), T x 3 u32 (triangles' vertex
//                    indices), A bytes of surface attributes (none if A is 0):
//                      u64 C, u64 U, u64 N, u64 M, u32 K, C x 3 float (colours), U x 2 float
//                      (texture coordinates), N x 3 float (normals), M x u32 (triangles'
//                      materials), then K materials: u8 has_diffuse, 3 double (diffuse),
//                      u32 width, u32 height, width x height x 3 bytes (RGB texture; 0 x 0: none)
//     otherwise:     u32 N, N bytes (the message)
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>

#include "mesh_file.h"

namespace laser_raycast {
namespace import_protocol {

enum class Status : std::uint32_t {
  kMesh = 0,         // the triangles follow
  kError = 1,        // the file is bad: the message says why
  kOutOfMemory = 2,  // an allocation failed under the process's memory bound
};

// Writes are blocking and retried on partial writes; on a socket they raise no SIGPIPE. Each
// returns false if the write failed (the other end went away).
bool writeRequest(int fd, const std::string& path, const Eigen::Vector3d& scale);
bool writeMesh(int fd, const mesh_file::MeshData& mesh);
// The reply for a failure. Allocates nothing, so that it can be written when memory has run out.
bool writeFailure(int fd, Status status, const char* message);

// Reads one request (blocking). False at a clean end of input (no bytes); throws SceneLoadError
// for a malformed or truncated one.
bool readRequest(int fd, std::string* path, Eigen::Vector3d* scale);

// The size of the reply that starts with prefix, once prefix holds enough of it to tell (its
// header, and the counts or the message length); nullopt until then. Throws SceneLoadError for a
// prefix that is not a reply's.
std::optional<std::uint64_t> replySize(const std::string& prefix);

struct Reply {
  Status status = Status::kError;
  mesh_file::MeshData mesh;  // kMesh
  std::string message;       // otherwise
};

// Parses a complete reply. Throws SceneLoadError naming what is wrong with it (truncated, trailing
// bytes, an index out of range, a non-finite vertex, an unknown status).
Reply parseReply(const std::string& bytes);

}  // namespace import_protocol
}  // namespace laser_raycast
