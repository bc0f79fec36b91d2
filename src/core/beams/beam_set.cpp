#include "beams/beam_set.h"

namespace laser_raycast {
namespace core {

void BeamSet::reset(const ScanPattern& pattern, const CastConfig& config, ScanResult* result) {
  grid_.reset(pattern, config);
  result_ = result;
  with_normals_ = !result->normal.empty();
  occlusion_culling_ = config.occlusion_culling;
  // resetResult left every range +inf (or NaN for a sensor pose that is not valid, and then
  // nothing is cast): the farthest hit a beam keeps is tmax.
  tiles_.reset(grid_.rows(), grid_.cols(), floatAbove(config.tmax));
}

}  // namespace core
}  // namespace laser_raycast
