// laser_raycast_node: constructs the node, fails fast on a bad configuration, spins.
#include <ros/ros.h>

#include "laser_raycast/node/raycast_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "laser_raycast");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  laser_raycast::RaycastNode node(nh, pnh);
  if (!node.init()) return 1;
  ros::spin();
  return 0;
}
