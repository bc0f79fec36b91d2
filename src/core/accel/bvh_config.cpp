#include "laser_raycast/core/bvh_config.h"

#include <sstream>
#include <stdexcept>

namespace laser_raycast {
namespace core {

void BvhConfig::validate() const {
  std::ostringstream msg;
  if (max_leaf_size < 1) {
    msg << "BvhConfig.max_leaf_size must be >= 1, got " << max_leaf_size;
  } else if (bins < 2 || bins > 256) {
    msg << "BvhConfig.bins must be in [2, 256], got " << bins;
  } else if (!(traversal_cost >= 0 && traversal_cost < 1e6)) {
    msg << "BvhConfig.traversal_cost must be in [0, 1e6), got " << traversal_cost;
  } else if (max_depth < 1 || max_depth > 62) {
    msg << "BvhConfig.max_depth must be in [1, 62] (the traversal stack holds 64), got "
        << max_depth;
  } else if (threads < 0 || threads > 1024) {
    msg << "BvhConfig.threads must be in [0, 1024] (0: every core), got " << threads;
  } else {
    return;
  }
  throw std::invalid_argument(msg.str());
}

}  // namespace core
}  // namespace laser_raycast
