// The node as a nodelet (laser_raycast/RaycastNodelet): the same class, in a nodelet manager.
#include <nodelet/nodelet.h>

#include <memory>
#include <pluginlib/class_list_macros.hpp>
#include <stdexcept>

#include "laser_raycast/node/raycast_node.h"

namespace laser_raycast {

class RaycastNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    node_ = std::make_unique<RaycastNode>(getNodeHandle(), getPrivateNodeHandle());
    // The manager reports a nodelet whose onInit throws as failed to load, but logs the exception
    // only at debug level: say what it was.
    bool ok = false;
    try {
      ok = node_->init();
    } catch (const std::exception& e) {
      ROS_FATAL("laser_raycast: %s", e.what());
      throw;
    }
    if (!ok) throw std::runtime_error("laser_raycast: bad configuration (see above)");
  }

  std::unique_ptr<RaycastNode> node_;
};

}  // namespace laser_raycast

PLUGINLIB_EXPORT_CLASS(laser_raycast::RaycastNodelet, nodelet::Nodelet)
