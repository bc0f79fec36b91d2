// Map worlds from topics: for each ~models entry {map_topic: TOPIC, height: H}, the walls over the
// occupied cells of the newest nav_msgs/OccupancyGrid on TOPIC (map_server latches its map), in the
// grid's header.frame_id at its info.origin. Each new grid rebuilds the walls off the node's
// threads: the walls of every topic's newest grid, in a scene of their own, go to the scene editor
// (scene_editor.h), which composes them with the models and swaps the result in whole.
#pragma once

#include <nav_msgs/OccupancyGrid.h>
#include <ros/ros.h>

#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "laser_raycast/core/scene.h"
#include "laser_raycast/loader/map_walls.h"
#include "laser_raycast/node/node_params.h"

namespace laser_raycast {

// A grid's cells: occupied where the value is above 65 (an occupancy above 0.65, map_server's
// default occupied_thresh, as map files are read; map_server publishes 100 for occupied cells),
// free elsewhere, unknown (-1) included. Its resolution, size and origin as given: addMapWalls
// checks them.
OccupancyMap occupancyOf(const nav_msgs::OccupancyGrid& grid);

class MapTopics {
 public:
  // The value above which a grid's cell is occupied.
  static constexpr int kOccupiedAbove = 65;

  // Where the walls of every topic's newest grid go, from the builder thread.
  using WallsOut = std::function<void(core::Scene walls)>;

  // Subscribes to the topic of every map_topic entry of params (none: nothing to do).
  MapTopics(ros::NodeHandle nh, const NodeParams& params, WallsOut out);
  ~MapTopics();  // stops the builder

 private:
  struct Entry {
    ModelSource source;
    ros::Subscriber sub;
    nav_msgs::OccupancyGrid::ConstPtr grid;  // the newest that made walls
  };

  void onGrid(std::size_t entry, const nav_msgs::OccupancyGrid::ConstPtr& grid);
  void run();
  // The walls of every entry's grid; false (after ROS_ERROR) if the new grid
  // of entry `changed` is bad: it is dropped, and that entry's previous grid stays.
  bool rebuild(std::size_t changed);

  const NodeParams params_;
  const WallsOut out_;
  std::vector<Entry> entries_;  // the builder thread's own, but for the subscribers
  std::mutex mutex_;            // pending_ and stop_
  std::condition_variable wake_;
  std::vector<nav_msgs::OccupancyGrid::ConstPtr> pending_;  // per entry, the newest not yet built
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace laser_raycast
