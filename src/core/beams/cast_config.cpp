#include "laser_raycast/core/cast_config.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace laser_raycast {
namespace core {

void CastConfig::validate() const {
  std::ostringstream msg;
  if (!(std::isfinite(tmin) && tmin >= 0)) {
    msg << "tmin must be finite and >= 0, got " << tmin;
  } else if (!(tmax > tmin)) {
    msg << "tmax (" << tmax << " m) must be greater than tmin (" << tmin << " m)";
  } else if (threads < 0 || threads > CastConfig::kMaxThreads) {
    msg << "threads must be in [0, " << CastConfig::kMaxThreads << "] (0: every core), got "
        << threads;
  } else {
    return;
  }
  throw std::invalid_argument(msg.str());
}

bool CastConfig::operator==(const CastConfig& o) const {
  return method == o.method && cull_backfaces == o.cull_backfaces && tmin == o.tmin &&
         tmax == o.tmax && planar_fast_path == o.planar_fast_path &&
         raster_fast_path == o.raster_fast_path && occlusion_culling == o.occlusion_culling &&
         keep_slices == o.keep_slices && compute_incidence == o.compute_incidence;
}

}  // namespace core
}  // namespace laser_raycast
