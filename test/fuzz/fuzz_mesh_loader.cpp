// libFuzzer harness: mesh file bytes -> SceneLoader::loadMesh, the whole path a mesh takes (the
// importer process under its bounds, the reply's checks, core::Mesh and its BVH). The invariant:
// a mesh whose vertices are finite and whose triangles index them, or a SceneLoadError; never a
// crash, another exception or a hang (libFuzzer's -timeout). The importer runs as its own process,
// so assimp itself is not instrumented here: what it does wrong is what the bounds are for.
// docs/testing.md says how to run it.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "laser_raycast/loader/scene_loader.h"

namespace {

namespace fs = std::filesystem;
using laser_raycast::MeshImportBounds;
using laser_raycast::SceneLoader;

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "fuzz_mesh_loader: invariant broken: %s\n", what.c_str());
  std::abort();
}

bool startsWith(const std::uint8_t* data, std::size_t size, const char* prefix) {
  const std::size_t n = std::strlen(prefix);
  return size >= n && std::memcmp(data, prefix, n) == 0;
}

// assimp picks a reader by the file's extension first: the one the content looks like.
std::string extensionFor(const std::uint8_t* data, std::size_t size) {
  const std::string head(reinterpret_cast<const char*>(data), std::min<std::size_t>(size, 512));
  if (startsWith(data, size, "ply")) return ".ply";
  if (head.find("<COLLADA") != std::string::npos) return ".dae";
  if (startsWith(data, size, "solid")) return ".stl";
  if (startsWith(data, size, "OFF")) return ".off";
  if (size >= 84) {
    std::uint32_t count = 0;
    std::memcpy(&count, data + 80, sizeof(count));
    if (size == 84 + 50 * std::uint64_t{count}) return ".stl";
  }
  return ".obj";
}

// Small bounds keep the inputs on which assimp allocates without end, or loops, quick to refuse.
MeshImportBounds fuzzBounds() {
  MeshImportBounds bounds;
  bounds.max_memory_mb = 256;
  bounds.max_seconds = 2;
  return bounds;
}

// Where an input is written (removed after it is loaded): a file of its own in the temporary
// directory. libFuzzer may end the process without running atexit handlers, so nothing is left
// for them to remove.
fs::path inputFile(std::uint64_t count, const std::string& extension) {
  return fs::temp_directory_path() /
         ("fuzz_mesh_loader_" + std::to_string(getpid()) + "_" + std::to_string(count) + extension);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // One loader (and so one importer process) for many inputs; a new one now and then drops its
  // cache, which keeps every file it has loaded.
  static std::unique_ptr<SceneLoader> loader;
  static std::uint64_t count = 0;
  if (!loader || count % 256 == 0) loader = std::make_unique<SceneLoader>(nullptr);
  const fs::path file = inputFile(count++, extensionFor(data, size));
  std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(data), size);
  try {
    const auto mesh =
        loader->loadMesh(file.string(), "", Eigen::Vector3d::Ones(), {}, fuzzBounds());
    if (!mesh || mesh->triangles().empty()) fail("a mesh without triangles");
    for (std::size_t i = 0; i < mesh->vertices().size(); ++i) {
      if (!mesh->vertices()[i].allFinite()) fail("a vertex that is not finite");
    }
    for (const auto& triangle : mesh->triangles()) {
      for (const std::uint32_t index : triangle) {
        if (index >= mesh->vertices().size()) fail("a triangle index out of range");
      }
    }
  } catch (const laser_raycast::SceneLoadError&) {
    // refused: fine
  }
  std::error_code ec;
  fs::remove(file, ec);
  return 0;
}
