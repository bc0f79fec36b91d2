// Map worlds: walls of a given height over the occupied cells of a 2D occupancy map (a map_server
// map file, map_file.h, or a grid the node receives), as few axis-aligned core::Box bodies on one
// frame. Cells that are free or unknown get no wall.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "laser_raycast/core/scene.h"
#include "laser_raycast/loader/errors.h"

namespace laser_raycast {

// Which cells of a 2D map are occupied, and where the map lies in its frame.
struct OccupancyMap {
  int width = 0, height = 0;  // cells along the origin's x and y
  double resolution = 0;      // m, the side of a cell
  // The pose, in the map's frame, of the outer corner of cell (0, 0) (the lower left of the map):
  // cell (i, j) covers [i, i + 1] x [j, j + 1] times resolution along the origin's x and y.
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
  std::vector<std::uint8_t> occupied;  // width * height, row j = 0 first (lowest y); 1: occupied

  bool at(int i, int j) const { return occupied[static_cast<std::size_t>(j) * width + i] != 0; }
  std::size_t occupiedCount() const;
};

// A rectangle of cells: [x, x + width) x [y, y + height).
struct CellRect {
  int x = 0, y = 0, width = 0, height = 0;
};

// Rectangles that cover exactly the occupied cells, none overlapping another: from the lowest row
// up, each cell not yet covered starts a rectangle that takes the longest run of uncovered occupied
// cells to its right, then grows upwards while the whole run above is occupied and uncovered.
// Linear in the cells; a room's straight walls become one rectangle each.
std::vector<CellRect> coverOccupiedCells(const OccupancyMap& map);

// Walls as MapWalls builds them.
struct MapWallOptions {
  static constexpr double kDefaultHeight = 2.0;  // m
  double height = kDefaultHeight;                // m, > 0: walls from z = 0 to height
  std::string frame = "map";  // the scene frame (a TF frame) the map's origin is given in
  std::string label;          // what a hit on a wall reports; "" for the frame's name
};

// What one map added to the scene.
struct LoadedMap {
  int width = 0, height = 0;  // cells
  double resolution = 0;      // m
  std::size_t occupied_cells = 0, boxes = 0;
  double widening = 0;                // m, wallWidening(map)
  double read_seconds = 0;            // reading the file (map_file.h; 0 for a grid)
  double build_seconds = 0;           // covering the cells with boxes and adding them to the scene
  std::vector<std::string> warnings;  // things in the file that were ignored
};

// How far each wall box reaches beyond its cells on every side in x and y, so that boxes that
// touch overlap. A beam is tested against each box in the box's own coordinates, after roundings
// of a few double epsilons (2^-52) times the coordinates involved; without the overlap, a beam that
// runs exactly along the face two boxes share, or through the corner where two occupied cells meet
// diagonally, could find itself just outside both and pass through the wall. The widening is
// 2^-40 of the distance from the frame's origin to the map's farthest corner plus 1 km (the
// sensor's distance from the walls, at most a lidar's range): hundreds of times those roundings,
// and 1e-9 m for a map within 100 m of its frame's origin. A beam's range to a wall is short by at
// most the widening over the cosine of its incidence angle.
double wallWidening(const OccupancyMap& map);

// Adds a box for each rectangle of coverOccupiedCells(map), widened by wallWidening(map), from z =
// 0 to options.height in the origin's frame, on frame options.frame. Throws SceneLoadError naming
// the problem: a height or resolution that is not finite and > 0, an origin that is not a rigid
// transform, a map whose occupied cells do not match its size.
LoadedMap addMapWalls(const OccupancyMap& map, const MapWallOptions& options, core::Scene* scene);

}  // namespace laser_raycast
