#include "laser_raycast/core/triangle.h"

namespace laser_raycast {
namespace core {

const char* toString(TriangleMethod method) {
  switch (method) {
    case TriangleMethod::kSeedPlane:
      return "seed_plane";
    case TriangleMethod::kSeedUv:
      return "seed_uv";
    case TriangleMethod::kCramer:
      return "cramer";
    case TriangleMethod::kMollerTrumbore:
      return "moller_trumbore";
    case TriangleMethod::kWatertight:
      return "watertight";
  }
  return "unknown";
}

bool parseTriangleMethod(const std::string& name, TriangleMethod* method) {
  for (const TriangleMethod m : kAllTriangleMethods) {
    if (name == toString(m)) {
      *method = m;
      return true;
    }
  }
  return false;
}

}  // namespace core
}  // namespace laser_raycast
