#include "beams/beam_set.h"

namespace laser_raycast {
namespace core {

void BeamSet::reset(const ScanPattern& pattern, const CastConfig& config, ScanResult* result,
                    const Bundle* bundle) {
  grid_.reset(pattern, config);
  result_ = result;
  bundle_ = bundle;
  with_normals_ = bundle ? !bundle->results.front()->normal.empty() : !result->normal.empty();
  occlusion_culling_ = config.occlusion_culling;
  // resetResult left every range +inf (or NaN for a sensor pose that is not valid, and then
  // nothing is cast): the farthest hit a beam keeps is tmax.
  tiles_.reset(grid_.rows(), grid_.cols(), floatAbove(config.tmax));
}

}  // namespace core
}  // namespace laser_raycast
