// Turns URDF models and their meshes into a core::Scene (urdfdom + assimp; no roscpp). package://
// URIs are resolved through a callback: rosPackagePath (package_resolver.h) for ROS_PACKAGE_PATH,
// or a test's own look-up.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "laser_raycast/core/enum_names.h"
#include "laser_raycast/core/scene.h"
#include "laser_raycast/loader/errors.h"
#include "laser_raycast/loader/package_resolver.h"

namespace laser_raycast {

// Which URDF geometry becomes the scene.
enum class GeometrySource {
  kVisual,  // "visual": each link's visual elements; a link without any uses its collision elements
  kCollision,  // "collision": collision elements only
};
inline const core::EnumNames<GeometrySource, 2> kGeometrySourceNames{{{
    {GeometrySource::kVisual, "visual"},
    {GeometrySource::kCollision, "collision"},
}}};
inline const char* toString(GeometrySource source) { return kGeometrySourceNames.name(source); }
inline bool parseGeometrySource(const std::string& name, GeometrySource* source) {
  return kGeometrySourceNames.parse(name, source);
}

// Which reader a mesh file goes to: the loader's own streaming reader for STL files (*.stl), which
// holds little more than the mesh it reads, assimp for every other format.
enum class MeshReader { kAssimp, kStl };

// What one mesh file's import may use. Meshes are imported in a child process
// (laser_raycast_mesh_import, installed with the package) under these bounds: some corrupt files
// make assimp allocate without limit, loop, or crash, and the child's failure is then a
// SceneLoadError (MeshImportBoundError for a bound) instead of the caller's.
struct MeshImportBounds {
  // MB of address space for the importing process (assimp, its libraries and the mesh), and s of
  // wall-clock time for one file, start-up included (a few ms). 0 (the default): each file's bound
  // follows its size (forFile), so that a large mesh loads and a small one cannot take much.
  double max_memory_mb = 0;
  double max_seconds = 0;

  // The bounds for a file of `bytes` bytes read by `reader`: those set, and for each one left 0 the
  // larger of a base and a multiple of the file's size, rounded up to a whole step (so that files
  // of similar sizes share one importer process): memory kBaseMemoryMb, or kMemoryPerFileByte
  // (assimp) or kStlMemoryPerFileByte (the STL reader) bytes of address space per byte of file, in
  // steps of kMemoryStepMb; time kBaseSeconds, or kSecondsPerFileMb per MB of file, in steps of
  // kSecondsStep. Measured (docs/faults.md): assimp needs 512-768 MB for a binary STL of 500,000
  // triangles (24 MB) and 6-8 GB for one of 4 million (191 MB); the STL reader 768-896 MB for 4
  // million triangles whose 12 million corners all differ (its worst case), well under 64 MB for
  // the 500,000. A 5 KB file gets 512 MB and 5 s; a 1 GB STL 6,144 MB and 205 s; a 1 GB file of
  // another format 48 GB.
  MeshImportBounds forFile(std::uintmax_t bytes, MeshReader reader = MeshReader::kAssimp) const;

  // Throws std::invalid_argument naming the field and its value: each must be finite,
  // max_memory_mb 0 or >= kMinMemoryMb and max_seconds >= 0. The fields are named as given (a
  // node's parameters, a tool's flags), by default "MeshImportBounds.max_memory_mb" and so on.
  void validate(const std::string& memory_name = "MeshImportBounds.max_memory_mb",
                const std::string& time_name = "MeshImportBounds.max_seconds") const;
  // The importer itself (its libraries, unused) maps about 40 MB of address space.
  static constexpr double kMinMemoryMb = 64;
  static constexpr double kBaseMemoryMb = 512;
  static constexpr double kMemoryPerFileByte = 48;
  static constexpr double kStlMemoryPerFileByte = 6;
  static constexpr double kMemoryStepMb = 256;
  static constexpr double kBaseSeconds = 5;
  static constexpr double kSecondsPerFileMb = 0.2;
  static constexpr double kSecondsStep = 5;
};

struct LoaderOptions {
  GeometrySource geometry = GeometrySource::kVisual;  // which elements to load
  bool skip_bad_geometry = false;  // a bad element is skipped with a warning instead of an error
  std::string tf_prefix;  // prepended to every link name (frames and labels), e.g. "robot2/"
  std::vector<std::string> ignore_links;  // links (without prefix) whose geometry is not loaded
  core::BvhConfig bvh;                    // BVH build settings for the meshes
  MeshImportBounds mesh_import;           // per mesh file
};

// A joint of the model, for forward kinematics (the CLI places links by joint values; the node uses
// TF).
struct ModelJoint {
  enum class Type { kFixed, kRevolute, kContinuous, kPrismatic, kOther };
  std::string name;
  Type type = Type::kFixed;
  std::string parent_link, child_link;                                  // with the tf_prefix
  Eigen::Isometry3d parent_from_joint = Eigen::Isometry3d::Identity();  // the joint's <origin>
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();                      // unit, in the joint frame
};

// What one model contributed to the scene.
struct LoadedModel {
  std::string name;       // the URDF's robot name
  std::string root_link;  // with the tf_prefix
  std::vector<ModelJoint> joints;
  // Every link (with the tf_prefix) -> the scene frame it moves with and its pose in that frame.
  // Links joined by fixed joints share the frame of the topmost link of their fixed chain.
  std::map<std::string, std::pair<std::string, Eigen::Isometry3d>> link_frames;
  std::size_t links = 0, bodies = 0, triangles = 0;  // triangles over all mesh bodies
  double load_seconds = 0;                           // parsing and reading meshes
  double bvh_build_seconds = 0;       // building BVHs (meshes already in the cache cost nothing)
  // The meshes this model's load read and built (not those it found in the cache): their
  // triangles, and the bytes they hold (vertices, triangles, BVHs and what the caster keeps per
  // triangle), as glibc's allocator counts them: another thread allocating meanwhile would count
  // too, and under AddressSanitizer, whose allocator replaces glibc's, only the meshes' input is.
  std::size_t mesh_triangles_built = 0, mesh_bytes_built = 0;
  std::vector<std::string> warnings;  // elements skipped under skip_bad_geometry
};

namespace import_process {
class MeshImporter;
}

class SceneLoader {
 public:
  // resolver finds the packages of package:// URIs, of URDF files and meshes alike.
  explicit SceneLoader(PackageResolver resolver);
  ~SceneLoader();  // ends the mesh importer's process
  SceneLoader(SceneLoader&&) noexcept;
  SceneLoader& operator=(SceneLoader&&) noexcept;

  // Adds the model's geometry to scene: frames named after the (merged) links, labels after the
  // links. base_dir is where relative mesh paths are looked up ("" for a URDF that came from a
  // parameter: then a relative path is an error). source names the URDF in error messages (e.g.
  // "parameter /robot_description"). Throws SceneLoadError.
  LoadedModel addUrdfString(const std::string& urdf_xml, const std::string& base_dir,
                            const LoaderOptions& options, core::Scene* scene,
                            const std::string& source = "<URDF string>");
  // The same for a file, given as a path or a package:// URI (found through the resolver);
  // relative mesh paths are relative to the file's directory.
  LoadedModel addUrdfFile(const std::string& uri, const LoaderOptions& options, core::Scene* scene);

  // The mesh at uri (package://, file://, absolute, or relative to base_dir), with the URDF scale
  // and the Collada <unit> applied, imported under bounds. Each (file, scale) is read and its BVH
  // built once; later calls share it. Throws SceneLoadError naming the file and the problem
  // (MeshImportBoundError if the import exceeded a bound).
  std::shared_ptr<const core::Mesh> loadMesh(const std::string& uri, const std::string& base_dir,
                                             const Eigen::Vector3d& scale,
                                             const core::BvhConfig& bvh,
                                             const MeshImportBounds& bounds = {});

  // Files read and BVHs built so far: each (file, scale) once while a mesh of it is held (by a
  // scene, or by the caller), again once every holder has let it go.
  std::size_t meshesLoaded() const { return meshes_built_; }

 private:
  // Both public add functions end here; source names the URDF in messages.
  LoadedModel addUrdf(const std::string& urdf_xml, const std::string& base_dir,
                      const std::string& source, const LoaderOptions& options, core::Scene* scene);

  PackageResolver resolver_;
  std::unique_ptr<import_process::MeshImporter> importer_;  // started at the first mesh file
  // The meshes built, by (file, scale), as long as something else holds them: a node that spawns
  // and deletes models of many files keeps only the meshes of the models it has.
  std::map<std::pair<std::string, std::array<double, 3>>, std::weak_ptr<const core::Mesh>> cache_;
  std::size_t meshes_built_ = 0;
  double last_bvh_seconds_ = 0;
  std::size_t last_mesh_bytes_ = 0;  // of the last mesh built, 0 if it came from the cache
};

}  // namespace laser_raycast
