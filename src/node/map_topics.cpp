#include "map_topics.h"

#include <chrono>
#include <utility>

namespace laser_raycast {

OccupancyMap occupancyOf(const nav_msgs::OccupancyGrid& grid) {
  OccupancyMap map;
  map.width = static_cast<int>(grid.info.width);
  map.height = static_cast<int>(grid.info.height);
  map.resolution = grid.info.resolution;
  const auto& p = grid.info.origin.position;
  const auto& q = grid.info.origin.orientation;
  // Divided by its norm, not normalized(), which leaves a zero quaternion as it is (the identity's
  // rotation matrix): a zero quaternion becomes NaN, which addMapWalls refuses.
  const Eigen::Vector4d coeffs(q.x, q.y, q.z, q.w);
  map.origin = Eigen::Translation3d(p.x, p.y, p.z) * Eigen::Quaterniond(coeffs / coeffs.norm());
  map.occupied.resize(grid.data.size());
  for (std::size_t k = 0; k < grid.data.size(); ++k) {
    map.occupied[k] = grid.data[k] > MapTopics::kOccupiedAbove;
  }
  return map;
}

MapTopics::MapTopics(ros::NodeHandle nh, const NodeParams& params, WallsOut out)
    : params_(params), out_(std::move(out)) {
  for (const ModelSource& m : params.models) {
    if (!m.map_topic.empty()) entries_.push_back({m, ros::Subscriber(), nullptr});
  }
  pending_.resize(entries_.size());
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    entries_[i].sub = nh.subscribe<nav_msgs::OccupancyGrid>(
        entries_[i].source.map_topic, 1,
        [this, i](const nav_msgs::OccupancyGrid::ConstPtr& grid) { onGrid(i, grid); });
    ROS_INFO("map topic %s: its walls (%g m high) come with its first grid",
             entries_[i].sub.getTopic().c_str(), entries_[i].source.height);
  }
  // Grids that came meanwhile wait in pending_.
  thread_ = std::thread([this] { run(); });
}

MapTopics::~MapTopics() {
  for (Entry& e : entries_) e.sub.shutdown();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void MapTopics::onGrid(std::size_t entry, const nav_msgs::OccupancyGrid::ConstPtr& grid) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_[entry] = grid;  // a newer grid replaces one not yet built
  }
  wake_.notify_all();
}

void MapTopics::run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    wake_.wait(lock, [this] {
      if (stop_) return true;
      for (const auto& grid : pending_) {
        if (grid) return true;
      }
      return false;
    });
    if (stop_) return;
    for (std::size_t i = 0; i < pending_.size(); ++i) {
      if (!pending_[i]) continue;
      nav_msgs::OccupancyGrid::ConstPtr grid = std::move(pending_[i]);
      pending_[i].reset();
      lock.unlock();
      const nav_msgs::OccupancyGrid::ConstPtr previous = entries_[i].grid;
      entries_[i].grid = grid;
      if (!rebuild(i)) entries_[i].grid = previous;
      lock.lock();
    }
  }
}

bool MapTopics::rebuild(std::size_t changed) {
  const auto start = std::chrono::steady_clock::now();
  core::Scene walls;
  LoadedMap made;
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    const Entry& e = entries_[i];
    if (!e.grid) continue;
    MapWallOptions options;
    options.height = e.source.height;
    options.frame = e.grid->header.frame_id;
    // tf2 frame ids do not start with '/'; older publishers still write one.
    if (!options.frame.empty() && options.frame[0] == '/') options.frame.erase(0, 1);
    try {
      if (e.grid->data.size() != std::size_t(e.grid->info.width) * e.grid->info.height) {
        throw SceneLoadError("a grid of " + std::to_string(e.grid->info.width) + " x " +
                             std::to_string(e.grid->info.height) + " cells with " +
                             std::to_string(e.grid->data.size()) + " values");
      }
      if (options.frame.empty()) throw SceneLoadError("the grid's header.frame_id is empty");
      const LoadedMap loaded = addMapWalls(occupancyOf(*e.grid), options, &walls);
      if (i == changed) made = loaded;
    } catch (const SceneLoadError& error) {
      ROS_ERROR_STREAM("map topic " << e.sub.getTopic() << ": the grid stamped "
                                    << e.grid->header.stamp << " is refused (" << error.what()
                                    << "); the walls stay as they were");
      return false;
    }
  }
  out_(std::move(walls));
  const Entry& e = entries_[changed];
  ROS_INFO(
      "map topic %s: %d x %d cells of %g m in frame '%s', %zu occupied, walls %g m high as %zu "
      "boxes; the scene rebuilt in %.3f s",
      e.sub.getTopic().c_str(), made.width, made.height, made.resolution,
      e.grid->header.frame_id.c_str(), made.occupied_cells, e.source.height, made.boxes,
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return true;
}

}  // namespace laser_raycast
