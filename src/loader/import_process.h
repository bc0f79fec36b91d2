// Runs the mesh importer (laser_raycast_mesh_import) as a child process under MeshImportBounds and
// takes its triangles back through a socket. Private to the loader.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <string>

#include "laser_raycast/loader/scene_loader.h"
#include "mesh_file.h"

namespace laser_raycast {
namespace import_process {

// The importer's file name, and the environment variable that overrides where it is looked for.
inline constexpr const char* kImporterName = "laser_raycast_mesh_import";
inline constexpr const char* kImporterEnv = "LASER_RAYCAST_MESH_IMPORT";

// The importer: the path in $LASER_RAYCAST_MESH_IMPORT if set; else, beside the library (or
// executable) this code is linked into, laser_raycast/laser_raycast_mesh_import (catkin puts
// libraries in lib/ and the package's executables in lib/laser_raycast/, in devel and install space
// alike) or laser_raycast_mesh_import. Throws SceneLoadError naming the places it looked.
std::string importerPath();

// One importer process, started at the first file and reused for the next ones (a process start
// costs more than importing a small mesh), until a bound is exceeded or it fails, or the bounds
// change; then the next file starts a new one. Not thread-safe (nor is SceneLoader).
class MeshImporter {
 public:
  MeshImporter();
  ~MeshImporter();  // ends the process
  MeshImporter(const MeshImporter&) = delete;
  MeshImporter& operator=(const MeshImporter&) = delete;

  // The triangles of the mesh file at path, scaled, read by the importer under bounds (validated
  // by the caller). Throws MeshImportBoundError if the import exceeded a bound, SceneLoadError for
  // anything else (the file is bad, the importer crashed on it or cannot be started); the caller
  // names the file.
  mesh_file::MeshData import(const std::string& path, const Eigen::Vector3d& scale,
                             const MeshImportBounds& bounds);

 private:
  class Process;
  std::unique_ptr<Process> process_;
};

}  // namespace import_process
}  // namespace laser_raycast
