#include "laser_raycast/loader/map_walls.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "laser_raycast/core/pose.h"

namespace laser_raycast {
namespace {

// The sensor's distance from the walls that wallWidening allows for (the longest lidar ranges are
// a few hundred metres).
constexpr double kSensorReach = 1000.0;  // m

std::string formatValue(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

void checkMap(const OccupancyMap& map, const MapWallOptions& options) {
  // Written so that NaN fails.
  if (!(std::isfinite(options.height) && options.height > 0)) {
    throw SceneLoadError("wall height must be finite and > 0 m, got " +
                         formatValue(options.height));
  }
  if (!(std::isfinite(map.resolution) && map.resolution > 0)) {
    throw SceneLoadError("resolution must be finite and > 0 m, got " + formatValue(map.resolution));
  }
  if (map.width < 0 || map.height < 0 ||
      map.occupied.size() != static_cast<std::size_t>(map.width) * map.height) {
    throw SceneLoadError("a map of " + std::to_string(map.width) + " x " +
                         std::to_string(map.height) + " cells with " +
                         std::to_string(map.occupied.size()) + " cell values");
  }
  if (!core::isValidPose(map.origin)) {
    throw SceneLoadError("the map's origin is not a finite rigid transform");
  }
  if (options.frame.empty()) throw SceneLoadError("the map's frame is empty");
}

}  // namespace

std::size_t OccupancyMap::occupiedCount() const {
  return static_cast<std::size_t>(
      std::count_if(occupied.begin(), occupied.end(), [](std::uint8_t c) { return c != 0; }));
}

std::vector<CellRect> coverOccupiedCells(const OccupancyMap& map) {
  std::vector<CellRect> rects;
  // Cells still to cover: occupied and in no rectangle yet.
  std::vector<std::uint8_t> open(map.occupied.size());
  std::transform(map.occupied.begin(), map.occupied.end(), open.begin(),
                 [](std::uint8_t c) { return c != 0; });
  const auto row = [&](int j) { return open.data() + static_cast<std::size_t>(j) * map.width; };
  for (int j = 0; j < map.height; ++j) {
    std::uint8_t* cells = row(j);
    for (int i = 0; i < map.width; ++i) {
      if (!cells[i]) continue;
      CellRect r{i, j, 1, 1};
      while (r.x + r.width < map.width && cells[r.x + r.width]) ++r.width;
      // Up while the run above is open, cell for cell. Each cell read here is covered by r, except
      // at most a run's width in the row that stops it: linear over all rectangles.
      while (r.y + r.height < map.height) {
        const std::uint8_t* above = row(r.y + r.height) + r.x;
        if (!std::all_of(above, above + r.width, [](std::uint8_t c) { return c != 0; })) break;
        ++r.height;
      }
      for (int k = 0; k < r.height; ++k) std::fill_n(row(r.y + k) + r.x, r.width, 0);
      rects.push_back(r);
      i += r.width - 1;
    }
  }
  return rects;
}

double wallWidening(const OccupancyMap& map) {
  const double reach = map.origin.translation().norm() +
                       map.resolution * std::hypot(double(map.width), double(map.height));
  return std::ldexp(reach + kSensorReach, -40);
}

LoadedMap addMapWalls(const OccupancyMap& map, const MapWallOptions& options, core::Scene* scene) {
  const auto start = std::chrono::steady_clock::now();
  checkMap(map, options);
  LoadedMap out;
  out.width = map.width;
  out.height = map.height;
  out.resolution = map.resolution;
  out.occupied_cells = map.occupiedCount();
  out.widening = wallWidening(map);
  const std::vector<CellRect> rects = coverOccupiedCells(map);
  // Every box is made and checked before the scene is touched, so that a failure leaves it as it
  // was.
  std::vector<core::Body> bodies;
  bodies.reserve(rects.size());
  const double r = map.resolution, h = options.height;
  for (const CellRect& rect : rects) {
    core::Body body;
    const core::Box box{
        Eigen::Vector3d(rect.width * r + 2 * out.widening, rect.height * r + 2 * out.widening, h)};
    const Eigen::Vector3d center((rect.x + 0.5 * rect.width) * r, (rect.y + 0.5 * rect.height) * r,
                                 0.5 * h);
    body.shape = box;
    body.frame_from_body = map.origin * Eigen::Translation3d(center);
    try {
      core::validate(box);
    } catch (const std::invalid_argument& e) {
      throw SceneLoadError(std::string("the wall over cells from (") + std::to_string(rect.x) +
                           ", " + std::to_string(rect.y) + "): " + e.what());
    }
    if (!core::isValidPose(body.frame_from_body)) {
      throw SceneLoadError("the wall over cells from (" + std::to_string(rect.x) + ", " +
                           std::to_string(rect.y) + ") is not at a finite pose");
    }
    bodies.push_back(std::move(body));
  }
  if (!bodies.empty()) {
    const int frame = scene->addFrame(options.frame);
    const int label = scene->addLabel(options.label.empty() ? options.frame : options.label);
    for (core::Body& body : bodies) {
      body.frame = frame;
      body.label = label;
      scene->addBody(std::move(body));
    }
  }
  out.boxes = rects.size();
  out.build_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace laser_raycast
