// Walls over a map's occupied cells (map_walls.h): the rectangles cover exactly the occupied cells,
// checked cell by cell on random maps and literal ones; rooms take few of them; the boxes in the
// scene sit where their cells are, widened as documented; bad input is refused without touching
// the scene.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "laser_raycast/loader/map_walls.h"
#include "random.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast;

// A map from rows of '#' (occupied) and '.', the top row (highest y) first.
OccupancyMap mapOf(const std::vector<std::string>& rows, double resolution = 1.0) {
  OccupancyMap map;
  map.height = static_cast<int>(rows.size());
  map.width = static_cast<int>(rows[0].size());
  map.resolution = resolution;
  map.occupied.resize(static_cast<std::size_t>(map.width) * map.height);
  for (int j = 0; j < map.height; ++j) {
    for (int i = 0; i < map.width; ++i) {
      map.occupied[static_cast<std::size_t>(j) * map.width + i] =
          rows[map.height - 1 - j][i] == '#';
    }
  }
  return map;
}

// How many rectangles cover each cell.
std::vector<int> coverCounts(const OccupancyMap& map, const std::vector<CellRect>& rects) {
  std::vector<int> counts(map.occupied.size(), 0);
  for (const CellRect& r : rects) {
    EXPECT_GT(r.width, 0);
    EXPECT_GT(r.height, 0);
    EXPECT_GE(r.x, 0);
    EXPECT_GE(r.y, 0);
    EXPECT_LE(r.x + r.width, map.width);
    EXPECT_LE(r.y + r.height, map.height);
    for (int j = r.y; j < r.y + r.height; ++j) {
      for (int i = r.x; i < r.x + r.width; ++i)
        ++counts[static_cast<std::size_t>(j) * map.width + i];
    }
  }
  return counts;
}

// Every occupied cell in exactly one rectangle, every other cell in none.
void expectExactCover(const OccupancyMap& map, const std::vector<CellRect>& rects) {
  const std::vector<int> counts = coverCounts(map, rects);
  int wrong = 0;
  for (int j = 0; j < map.height; ++j) {
    for (int i = 0; i < map.width; ++i) {
      const int expected = map.at(i, j) ? 1 : 0;
      const int got = counts[static_cast<std::size_t>(j) * map.width + i];
      if (got != expected && ++wrong <= 5) {
        ADD_FAILURE() << "cell (" << i << ", " << j << ") is in " << got << " rectangles, expected "
                      << expected;
      }
    }
  }
  EXPECT_EQ(wrong, 0);
}

TEST(CoverOccupiedCells, LiteralShapes) {
  // An L, a T, a diagonal of single cells, a cell at each corner.
  const std::vector<std::vector<std::string>> maps = {
      {"#...", "#...", "####"},
      {"#####", "..#..", "..#.."},
      {"#...", ".#..", "..#.", "...#"},
      {"#..#", "....", "#..#"},
      {"####", "####"},
      {"....", "...."},
      {"#"},
  };
  const std::vector<std::size_t> rect_counts = {2, 3, 4, 4, 1, 0, 1};
  for (std::size_t k = 0; k < maps.size(); ++k) {
    SCOPED_TRACE(k);
    const OccupancyMap map = mapOf(maps[k]);
    const std::vector<CellRect> rects = coverOccupiedCells(map);
    expectExactCover(map, rects);
    EXPECT_EQ(rects.size(), rect_counts[k]);
  }
}

TEST(CoverOccupiedCells, RandomMapsAreCoveredExactly) {
  Rng rng(24);
  for (int trial = 0; trial < 60; ++trial) {
    OccupancyMap map;
    map.width = 1 + static_cast<int>(rng() % 90);
    map.height = 1 + static_cast<int>(rng() % 90);
    map.resolution = 0.05;
    const double density = uniform(rng, 0.0, 1.0);
    map.occupied.resize(static_cast<std::size_t>(map.width) * map.height);
    for (auto& c : map.occupied) c = uniform(rng, 0, 1) < density;
    SCOPED_TRACE(trial);
    const std::vector<CellRect> rects = coverOccupiedCells(map);
    expectExactCover(map, rects);
    EXPECT_LE(rects.size(), map.occupiedCount());
  }
}

// A room with 2-cell walls, a door, an inner wall and a pillar: a rectangle for each straight
// piece.
TEST(CoverOccupiedCells, RoomsTakeFewRectangles) {
  std::vector<std::string> rows(60, std::string(80, '.'));
  for (int i = 0; i < 80; ++i) rows[0][i] = rows[1][i] = rows[58][i] = rows[59][i] = '#';
  for (int j = 0; j < 60; ++j) rows[j][0] = rows[j][1] = rows[j][78] = rows[j][79] = '#';
  for (int j = 2; j < 58; ++j) rows[j][40] = rows[j][41] = '#';   // inner wall
  for (int j = 25; j < 32; ++j) rows[j][40] = rows[j][41] = '.';  // its door
  for (int j = 10; j < 14; ++j) rows[j].replace(60, 4, "####");   // a pillar
  const OccupancyMap map = mapOf(rows);
  const std::vector<CellRect> rects = coverOccupiedCells(map);
  expectExactCover(map, rects);
  // From the bottom up: the bottom wall, the two sides to the top, the inner wall's two pieces
  // (the upper one to the top), the pillar, the rest of the top wall on each side of the inner
  // wall.
  EXPECT_EQ(rects.size(), 8u);
}

TEST(MapWalls, BoxesWhereTheirCellsAreWidened) {
  OccupancyMap map = mapOf({"##.", "..#"}, 0.05);
  map.origin =
      Eigen::Translation3d(1.0, -2.0, 0.0) * Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ());
  core::Scene scene;
  scene.addFrame("base");
  MapWallOptions options;
  options.height = 1.5;
  options.frame = "world";
  const LoadedMap loaded = addMapWalls(map, options, &scene);
  EXPECT_EQ(loaded.boxes, 2u);
  EXPECT_EQ(loaded.occupied_cells, 3u);
  EXPECT_EQ(loaded.width, 3);
  EXPECT_EQ(loaded.height, 2);
  // 2^-40 (the origin's distance + the map's diagonal + 1 km).
  const double widening = std::ldexp(std::sqrt(5.0) + 0.05 * std::sqrt(13.0) + 1000.0, -40);
  EXPECT_DOUBLE_EQ(loaded.widening, widening);
  EXPECT_DOUBLE_EQ(wallWidening(map), widening);
  ASSERT_EQ(scene.bodies().size(), 2u);
  ASSERT_EQ(scene.frames().size(), 2u);
  EXPECT_EQ(scene.frames()[1], "world");
  EXPECT_EQ(scene.labels()[scene.bodies()[0].label], "world");
  // Cell row 0 holds cell (2, 0); row 1 cells (0, 1) and (1, 1).
  struct Expected {
    Eigen::Vector3d center, size;
  };
  const Expected expected[2] = {
      {{0.125, 0.025, 0.75}, {0.05 + 2 * widening, 0.05 + 2 * widening, 1.5}},
      {{0.05, 0.075, 0.75}, {0.1 + 2 * widening, 0.05 + 2 * widening, 1.5}},
  };
  for (int b = 0; b < 2; ++b) {
    const core::Body& body = scene.bodies()[b];
    EXPECT_EQ(body.frame, 1);
    const auto& box = std::get<core::Box>(body.shape);
    EXPECT_NEAR((box.size - expected[b].size).norm(), 0, 1e-15);
    const Eigen::Vector3d center = map.origin * expected[b].center;
    EXPECT_NEAR((body.frame_from_body.translation() - center).norm(), 0, 1e-15);
    EXPECT_NEAR((body.frame_from_body.linear() - map.origin.linear()).norm(), 0, 1e-15);
  }
  // A label of its own.
  options.label = "walls";
  addMapWalls(map, options, &scene);
  EXPECT_EQ(scene.labels()[scene.bodies()[2].label], "walls");
}

TEST(MapWalls, AnEmptyMapAddsNothing) {
  core::Scene scene;
  const std::size_t frames = scene.frames().size();
  const LoadedMap loaded = addMapWalls(mapOf({"...", "..."}), MapWallOptions(), &scene);
  EXPECT_EQ(loaded.boxes, 0u);
  EXPECT_EQ(scene.bodies().size(), 0u);
  EXPECT_EQ(scene.frames().size(), frames);
}

TEST(MapWalls, BadInputIsRefusedAndLeavesTheScene) {
  const auto refused = [](OccupancyMap map, MapWallOptions options,
                          const std::vector<std::string>& words) {
    core::Scene scene;
    const std::uint64_t version = scene.version();
    std::string message = "(accepted)";
    try {
      addMapWalls(map, options, &scene);
    } catch (const SceneLoadError& e) {
      message = e.what();
    }
    for (const std::string& word : words) {
      EXPECT_NE(message.find(word), std::string::npos) << message;
    }
    EXPECT_EQ(scene.version(), version);
    EXPECT_TRUE(scene.bodies().empty());
  };
  const OccupancyMap good = mapOf({"#.", ".#"}, 0.1);
  MapWallOptions options;
  for (const double h : {0.0, -1.0, std::nan("")}) {
    options.height = h;
    refused(good, options, {"wall height", "> 0"});
  }
  options.height = 1;
  for (const double r : {0.0, -0.05, HUGE_VAL}) {
    OccupancyMap map = good;
    map.resolution = r;
    refused(map, options, {"resolution", "> 0"});
  }
  OccupancyMap wrong_size = good;
  wrong_size.occupied.resize(3);
  refused(wrong_size, options, {"2 x 2 cells with 3 cell values"});
  OccupancyMap bad_origin = good;
  bad_origin.origin.linear() *= 2;
  refused(bad_origin, options, {"origin", "rigid"});
  OccupancyMap overflow = good;
  overflow.resolution = 1e308;
  refused(overflow, options, {"wall over cells"});
  options.frame = "";
  refused(good, options, {"frame", "empty"});
}

}  // namespace
}  // namespace laser_raycast_test
