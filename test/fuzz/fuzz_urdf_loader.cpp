// libFuzzer harness: URDF text -> SceneLoader::addUrdfString, meshes and all (relative paths and
// package://laser_raycast/ URIs reach the package's test meshes). The invariants: a model or a
// SceneLoadError, never a crash or another exception; a model's counts match what it added to the
// scene; a refused model leaves the scene as it was. docs/testing.md says how to run it.
#include <console_bridge/console.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>

#include "laser_raycast/loader/scene_loader.h"

namespace {

using laser_raycast::LoaderOptions;
using laser_raycast::SceneLoader;

const std::string kSourceDir = LASER_RAYCAST_SOURCE_DIR;

[[noreturn]] void fail(const std::string& what) {
  std::fprintf(stderr, "fuzz_urdf_loader: invariant broken: %s\n", what.c_str());
  std::abort();
}

std::optional<std::string> resolve(const std::string& package) {
  if (package == "laser_raycast") return kSourceDir;
  return std::nullopt;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // urdfdom reports every malformed input through console_bridge; the loader finds what it drops
  // without it.
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_NONE);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // One loader (and so one mesh importer process) for many inputs; a new one now and then drops
  // its cache, which grows with every new mesh scale.
  static std::unique_ptr<SceneLoader> loader;
  static std::uint64_t count = 0;
  if (!loader || count++ % 256 == 0) loader = std::make_unique<SceneLoader>(resolve);
  const std::string xml(reinterpret_cast<const char*>(data), size);
  // The second half of the options come from the input's length, so that every option is reached.
  LoaderOptions options;
  options.geometry =
      size % 2 ? laser_raycast::GeometrySource::kCollision : laser_raycast::GeometrySource::kVisual;
  options.skip_bad_geometry = size % 3 == 0;
  options.tf_prefix = size % 5 == 0 ? "p/" : "";
  options.mesh_import.max_memory_mb = 256;
  options.mesh_import.max_seconds = 2;
  laser_raycast::core::Scene scene;
  scene.addFrame("before");  // so that "unchanged" is not just "empty"
  try {
    const laser_raycast::LoadedModel model =
        loader->addUrdfString(xml, kSourceDir + "/test/data", options, &scene, "fuzz input");
    if (scene.bodies().size() != model.bodies) fail("the model's body count is not the scene's");
    if (model.link_frames.size() != model.links) fail("a link without a frame");
    if (model.root_link.compare(0, options.tf_prefix.size(), options.tf_prefix) != 0) {
      fail("the root link lacks the prefix");
    }
  } catch (const laser_raycast::SceneLoadError&) {
    if (!scene.bodies().empty() || scene.frames().size() != 1)
      fail("a refused model changed the scene");
  }
  return 0;
}
