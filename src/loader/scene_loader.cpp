#include "laser_raycast/loader/scene_loader.h"

#include <malloc.h>
#include <urdf_model/model.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "import_process.h"
#include "mesh_file.h"
#include "stl_reader.h"
#include "urdf_model.h"
#include "urdf_parse.h"

namespace laser_raycast {

using urdf_model::commitBodies;
using urdf_model::inQuotes;
using urdf_model::linkBodies;
using urdf_model::LinkFrames;
using urdf_model::mergeFixedJoints;
using urdf_model::MeshLoader;
using urdf_model::modelJoints;
using urdf_model::requirePositive;

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The bytes the process has allocated and not freed: glibc's count over every arena, plus the
// blocks it maps on their own (every large vector).
std::size_t heapBytes() {
  const struct mallinfo2 info = mallinfo2();
  return info.uordblks + info.hblkhd;
}

}  // namespace

MeshImportBounds MeshImportBounds::forFile(std::uintmax_t bytes, MeshReader reader) const {
  const double mb = static_cast<double>(bytes) / (1024 * 1024);
  const auto stepUp = [](double value, double step) { return std::ceil(value / step) * step; };
  MeshImportBounds out = *this;
  if (out.max_memory_mb == 0) {
    const double per_byte = reader == MeshReader::kStl ? kStlMemoryPerFileByte : kMemoryPerFileByte;
    out.max_memory_mb = std::max(kBaseMemoryMb, stepUp(per_byte * mb, kMemoryStepMb));
  }
  if (out.max_seconds == 0) {
    out.max_seconds = std::max(kBaseSeconds, stepUp(kSecondsPerFileMb * mb, kSecondsStep));
  }
  return out;
}

void MeshImportBounds::validate(const std::string& memory_name,
                                const std::string& time_name) const {
  std::ostringstream msg;
  // Written so that NaN fails.
  if (!(std::isfinite(max_memory_mb) && (max_memory_mb == 0 || max_memory_mb >= kMinMemoryMb))) {
    msg << memory_name << " must be 0 (from the file's size) or finite and >= " << kMinMemoryMb
        << " MB, got " << max_memory_mb;
  } else if (!(std::isfinite(max_seconds) && max_seconds >= 0)) {
    msg << time_name << " must be 0 (from the file's size) or finite and > 0 s, got "
        << max_seconds;
  } else {
    return;
  }
  throw std::invalid_argument(msg.str());
}

SceneLoader::SceneLoader(PackageResolver resolver) : resolver_(std::move(resolver)) {}
SceneLoader::~SceneLoader() = default;
SceneLoader::SceneLoader(SceneLoader&&) noexcept = default;
SceneLoader& SceneLoader::operator=(SceneLoader&&) noexcept = default;

std::shared_ptr<const core::Mesh> SceneLoader::loadMesh(const std::string& uri,
                                                        const std::string& base_dir,
                                                        const Eigen::Vector3d& scale,
                                                        const core::BvhConfig& bvh,
                                                        const MeshImportBounds& bounds) {
  last_bvh_seconds_ = 0;
  last_mesh_bytes_ = 0;
  std::string where = "mesh " + inQuotes(uri);
  try {
    requirePositive("the mesh scale", scale);
    try {
      bounds.validate();
    } catch (const std::invalid_argument& e) {
      throw SceneLoadError(e.what());
    }
    const std::string path = mesh_file::resolveUri(uri, base_dir, resolver_);
    if (path != uri) where += " (" + path + ")";

    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    if (!fs::exists(status)) throw SceneLoadError("file not found");
    if (!fs::is_regular_file(status)) throw SceneLoadError("not a regular file");
    // The cache key: the same file reached through different URIs is read once.
    fs::path canonical = fs::weakly_canonical(path, ec);
    if (ec) canonical = fs::absolute(path, ec);
    const auto key =
        std::make_pair(canonical.string(), std::array<double, 3>{scale.x(), scale.y(), scale.z()});
    const auto cached = cache_.find(key);
    if (cached != cache_.end()) {
      if (std::shared_ptr<const core::Mesh> mesh = cached->second.lock()) return mesh;
      cache_.erase(cached);  // every holder let it go: read the file anew
    }

    if (!std::ifstream(path, std::ios::binary).good()) {
      throw SceneLoadError("file cannot be opened for reading");
    }
    const std::uintmax_t size = fs::file_size(path, ec);
    if (size == 0 && !ec) throw SceneLoadError("file is empty (0 bytes)");

    if (!importer_) importer_ = std::make_unique<import_process::MeshImporter>();
    const MeshReader reader = mesh_file::isStlPath(path) ? MeshReader::kStl : MeshReader::kAssimp;
    mesh_file::MeshData data =
        importer_->import(path, scale, bounds.forFile(ec ? 0 : size, reader));
    // What the mesh holds: its input, and what the build allocated and kept.
    const std::size_t input_bytes = data.vertices.capacity() * sizeof(data.vertices[0]) +
                                    data.triangles.capacity() * sizeof(data.triangles[0]);
    const std::size_t heap_before = heapBytes();
    const Clock::time_point start = Clock::now();
    std::shared_ptr<const core::Mesh> mesh;
    try {
      auto built = std::make_shared<core::Mesh>(std::move(data.vertices), std::move(data.triangles),
                                                bvh, scale);
      built->setSurface(std::move(data.surface));
      mesh = std::move(built);
    } catch (const std::invalid_argument& e) {
      throw SceneLoadError(e.what());
    }
    last_bvh_seconds_ = secondsSince(start);
    last_mesh_bytes_ = input_bytes + std::max<std::size_t>(heapBytes(), heap_before) - heap_before;
    cache_.emplace(key, mesh);
    ++meshes_built_;
    return mesh;
  } catch (const SceneLoadError& e) {
    rethrowWithContext(e, where);
  }
}

LoadedModel SceneLoader::addUrdfFile(const std::string& uri, const LoaderOptions& options,
                                     core::Scene* scene) {
  // A package:// URI is named with the file it resolved to, as a mesh is.
  std::string path = uri, source = uri;
  if (isPackageUri(uri)) {
    try {
      path = resolvePackageUri(uri, resolver_);
    } catch (const SceneLoadError& e) {
      throw SceneLoadError(uri + ": " + e.what());
    }
    source = uri + " (" + path + ")";
  }
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw SceneLoadError(source + ": a directory, not a URDF file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneLoadError(source + ": cannot open the URDF file for reading");
  std::ostringstream xml;
  xml << in.rdbuf();
  if (!in && !in.eof()) throw SceneLoadError(source + ": error reading the URDF file");
  std::string dir = fs::path(path).parent_path().string();
  if (dir.empty()) dir = ".";  // a bare file name: relative meshes are next to it
  return addUrdf(xml.str(), dir, source, options, scene);
}

LoadedModel SceneLoader::addUrdfString(const std::string& urdf_xml, const std::string& base_dir,
                                       const LoaderOptions& options, core::Scene* scene,
                                       const std::string& source) {
  return addUrdf(urdf_xml, base_dir, source, options, scene);
}

LoadedModel SceneLoader::addUrdf(const std::string& urdf_xml, const std::string& base_dir,
                                 const std::string& source, const LoaderOptions& options,
                                 core::Scene* scene) {
  const Clock::time_point start = Clock::now();
  try {
    options.bvh.validate();
    options.mesh_import.validate();
  } catch (const std::invalid_argument& e) {
    throw SceneLoadError(source + ": " + e.what());
  }

  DroppedElements dropped;
  const urdf::ModelInterfaceSharedPtr model = parseUrdf(urdf_xml, source, &dropped);
  const urdf::LinkConstSharedPtr root = model->getRoot();
  if (!root) throw SceneLoadError(source + ": malformed URDF (no root link)");
  const std::string& prefix = options.tf_prefix;

  LoadedModel out;
  out.name = model->getName();
  out.root_link = prefix + root->name;
  out.links = model->links_.size();
  out.joints = modelJoints(*model, prefix, source);
  const LinkFrames frames = mergeFixedJoints(*model, root);
  // urdfdom accepts a joint whose parent is its own child; that link hangs from nothing (found by
  // test/fuzz/fuzz_urdf_loader).
  for (const auto& [name, link] : model->links_) {
    if (!frames.frame_of.count(name)) {
      // Such a link holds itself (child_links): break the cycle, or the model leaks.
      for (const auto& entry : model->links_) entry.second->child_links.clear();
      throw SceneLoadError(source + ": link '" + name + "' is not connected to the root link '" +
                           root->name + "' (a joint that makes it its own parent, or a cycle)");
    }
  }
  for (const auto& [link, placement] : frames.frame_of) {
    out.link_frames[prefix + link] = {prefix + placement.first, placement.second};
  }

  double bvh_seconds = 0;
  const MeshLoader load_mesh = [&](const urdf::Mesh& mesh) {
    const auto loaded =
        loadMesh(mesh.filename, base_dir, Eigen::Vector3d(mesh.scale.x, mesh.scale.y, mesh.scale.z),
                 options.bvh, options.mesh_import);
    bvh_seconds += last_bvh_seconds_;
    if (last_mesh_bytes_ > 0) {
      out.mesh_triangles_built += loaded->triangles().size();
      out.mesh_bytes_built += last_mesh_bytes_;
    }
    return loaded;
  };
  commitBodies(linkBodies(frames, dropped, options, source, load_mesh, &out.warnings), prefix,
               source, scene, &out);
  out.bvh_build_seconds = bvh_seconds;
  out.load_seconds = std::max(0.0, secondsSince(start) - bvh_seconds);
  return out;
}

}  // namespace laser_raycast
