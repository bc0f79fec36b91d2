// The errors the scene loader throws for bad input.
#pragma once

#include <stdexcept>
#include <string>

namespace laser_raycast {

// A bad model: the message names the file, the link and the problem.
class SceneLoadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A mesh file whose import was stopped at a bound (MeshImportBounds): a corrupt or hostile file on
// which assimp allocates without limit or does not finish. The message names the file, the bound
// and its value.
class MeshImportBoundError : public SceneLoadError {
 public:
  enum class Bound { kMemory, kTime };

  // limit: the bound's value, in MB for kMemory and seconds for kTime.
  MeshImportBoundError(const std::string& what, Bound bound, double limit)
      : SceneLoadError(what), bound_(bound), limit_(limit) {}

  Bound bound() const { return bound_; }
  double limit() const { return limit_; }

 private:
  Bound bound_;
  double limit_;
};

// Rethrows e with context + ": " prepended to its message, keeping its type (a bound error stays
// one).
[[noreturn]] inline void rethrowWithContext(const SceneLoadError& e, const std::string& context) {
  const std::string what = context + ": " + e.what();
  if (const auto* bound = dynamic_cast<const MeshImportBoundError*>(&e)) {
    throw MeshImportBoundError(what, bound->bound(), bound->limit());
  }
  throw SceneLoadError(what);
}

}  // namespace laser_raycast
