// laser_raycast_mesh_import: reads mesh files for the scene loader (STL with the loader's own
// streaming reader, stl_reader.h; OBJ of plain triangles with obj_reader.h; every other format and
// OBJ that is more than that with assimp), under the bounds it is given: a
// request (a file and a scale) on standard input, the triangles or why not on standard output
// (import_protocol.h), until the input ends. The loader runs it as a child process
// (import_process.cpp says why); it is not meant to be run by hand.
//
//   laser_raycast_mesh_import --max-memory-mb MB --max-seconds S
//
// Exit status: 0 the input ended, 1 a malformed request, 2 bad arguments or a terminal for output,
// 3 out of memory under the bound (after an out-of-memory reply), 4 the loader went away.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iostream>
#include <new>
#include <optional>
#include <string>

#include "import_protocol.h"
#include "mesh_import.h"
#include "obj_reader.h"
#include "ply_reader.h"
#include "stl_reader.h"

namespace {

using laser_raycast::import_protocol::Status;

constexpr int kExitEndOfInput = 0, kExitBadRequest = 1, kExitUsage = 2, kExitOutOfMemory = 3,
              kExitLoaderGone = 4;

struct Args {
  double max_memory_mb = 0, max_seconds = 0;
};

bool parseNumber(const char* text, double* value) {
  char* end = nullptr;
  *value = std::strtod(text, &end);
  return end != text && *end == '\0' && std::isfinite(*value) && *value > 0;
}

bool parseArgs(int argc, char** argv, Args* args) {
  if (argc != 5) return false;
  bool memory = false, seconds = false;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--max-memory-mb") {
      memory = parseNumber(argv[i + 1], &args->max_memory_mb);
    } else if (flag == "--max-seconds") {
      seconds = parseNumber(argv[i + 1], &args->max_seconds);
    }
  }
  return memory && seconds;
}

// A soft limit of value (lowered to the hard limit if that is smaller) and a hard one `extra` above
// it; a failure leaves the inherited limits, which are only tighter.
void setLimit(int resource, rlim_t value, rlim_t extra) {
  rlimit current{};
  if (getrlimit(resource, &current) != 0) return;
  rlimit wanted{std::min(value, current.rlim_max), std::min(value + extra, current.rlim_max)};
  setrlimit(resource, &wanted);
}

// The memory bound is the address space: every allocation past it fails (and operator new then
// calls onOutOfMemory). No core files: a crash on a corrupt file is an expected outcome, reported
// by the loader.
void limitResources(const Args& args) {
  setLimit(RLIMIT_AS, static_cast<rlim_t>(args.max_memory_mb * 1024 * 1024), 0);
  setLimit(RLIMIT_CORE, 0, 0);
}

// CPU time is a backstop for the time bound, which the loader enforces with a wall-clock deadline:
// should the loader be gone, a file that makes assimp loop still ends this process (SIGXCPU).
void limitCpuForOneFile(const Args& args) {
  rusage used{};
  getrusage(RUSAGE_SELF, &used);
  const auto seconds = static_cast<rlim_t>(used.ru_utime.tv_sec + used.ru_stime.tv_sec);
  setLimit(RLIMIT_CPU, seconds + static_cast<rlim_t>(std::ceil(args.max_seconds)) + 2, 1);
}

// Called by operator new when an allocation fails: reports and exits at once. assimp would
// otherwise catch the std::bad_alloc and report a generic read error.
void onOutOfMemory() {
  laser_raycast::import_protocol::writeFailure(STDOUT_FILENO, Status::kOutOfMemory,
                                               "an allocation failed under the memory bound");
  _exit(kExitOutOfMemory);
}

// Imports one file and writes the reply. False if the loader has gone away.
bool serve(const std::string& path, const Eigen::Vector3d& scale) {
  using laser_raycast::import_protocol::writeFailure;
  try {
    namespace mesh_file = laser_raycast::mesh_file;
    const auto read = [&]() -> mesh_file::MeshData {
      if (mesh_file::isStlPath(path)) return mesh_file::readStl(path, scale);
      if (mesh_file::isObjPath(path)) {
        std::optional<mesh_file::MeshData> plain = mesh_file::readPlainObj(path, scale);
        if (plain) return std::move(*plain);
      }
      if (mesh_file::isPlyPath(path)) {
        std::optional<mesh_file::MeshData> plain = mesh_file::readPlainPly(path, scale);
        if (plain) return std::move(*plain);
      }
      return mesh_file::importMeshInProcess(path, scale);
    };
    const mesh_file::MeshData mesh = read();
    return laser_raycast::import_protocol::writeMesh(STDOUT_FILENO, mesh);
  } catch (const laser_raycast::SceneLoadError& e) {
    return writeFailure(STDOUT_FILENO, Status::kError, e.what());
  } catch (const std::exception& e) {
    const std::string message = std::string("reading it failed: ") + e.what();
    return writeFailure(STDOUT_FILENO, Status::kError, message.c_str());
  }
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  if (!parseArgs(argc, argv, &args)) {
    std::cerr << "usage: laser_raycast_mesh_import --max-memory-mb MB --max-seconds S\n"
                 "(the scene loader runs this: requests on standard input, binary replies on "
                 "standard output)\n";
    return kExitUsage;
  }
  if (isatty(STDOUT_FILENO)) {
    std::cerr << "laser_raycast_mesh_import: writes binary replies for the scene loader, not for a "
                 "terminal\n";
    return kExitUsage;
  }
  closefrom(STDERR_FILENO + 1);  // what the parent left open is not the importer's business
  limitResources(args);
  std::set_new_handler(onOutOfMemory);
  std::string path;
  Eigen::Vector3d scale;
  for (;;) {
    try {
      if (!laser_raycast::import_protocol::readRequest(STDIN_FILENO, &path, &scale)) {
        return kExitEndOfInput;
      }
    } catch (const laser_raycast::SceneLoadError& e) {
      std::cerr << "laser_raycast_mesh_import: " << e.what() << "\n";
      return kExitBadRequest;
    }
    limitCpuForOneFile(args);
    // Memory the last file freed stays with the allocator for the next one (returning it with
    // malloc_trim made every later file fault its pages in again: a third slower on the
    // TurtleBot3 tires). A process whose address space that fragments is replaced: the loader
    // retries a failed file once in a new one (import_process.cpp).
    if (!serve(path, scale)) return kExitLoaderGone;
  }
}
