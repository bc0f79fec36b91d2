// A nav_msgs/OccupancyGrid's cells as walls (map_topics.h, without roscore): which values are
// occupied (above 65, as a map file's default occupied_thresh of 0.65 reads a grid value), unknown
// (-1) free, the origin's full pose, and the walls addMapWalls then raises on the grid's frame.
#include <gtest/gtest.h>

#include <cmath>

#include "map_topics.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast;

TEST(MapTopics, OccupiedAboveSixtyFiveUnknownFree) {
  nav_msgs::OccupancyGrid grid;
  grid.header.frame_id = "odom";
  grid.info.width = 4;
  grid.info.height = 2;
  grid.info.resolution = 0.1f;
  grid.data = {-1, 0, 65, 66, 100, 50, 99, -1};
  const OccupancyMap map = occupancyOf(grid);
  EXPECT_EQ(map.width, 4);
  EXPECT_EQ(map.height, 2);
  EXPECT_EQ(map.resolution, double(0.1f));
  // Row 0 first, as the grid's data: (0, 0) -1, (1, 0) 0, (2, 0) 65, (3, 0) 66; (0, 1) 100 ...
  const std::vector<std::uint8_t> expected = {0, 0, 0, 1, 1, 0, 1, 0};
  EXPECT_EQ(map.occupied, expected);
}

TEST(MapTopics, TheOriginsFullPose) {
  nav_msgs::OccupancyGrid grid;
  grid.info.width = grid.info.height = 1;
  grid.info.resolution = 1;
  grid.data = {100};
  grid.info.origin.position.x = 2;
  grid.info.origin.position.y = -3;
  grid.info.origin.position.z = 0.5;
  // A quarter turn about z, given unnormalised.
  grid.info.origin.orientation.z = 2 * std::sin(M_PI / 4);
  grid.info.origin.orientation.w = 2 * std::cos(M_PI / 4);
  const OccupancyMap map = occupancyOf(grid);
  const Eigen::Vector3d x = map.origin * Eigen::Vector3d(1, 0, 0);
  EXPECT_NEAR((x - Eigen::Vector3d(2, -2, 0.5)).norm(), 0, 1e-12);
  // The walls: one box from z = 0.5 to 1.5 in the frame, centred over the cell.
  core::Scene scene;
  MapWallOptions options;
  options.height = 1;
  options.frame = "odom";
  addMapWalls(map, options, &scene);
  ASSERT_EQ(scene.bodies().size(), 1u);
  EXPECT_NEAR(
      (scene.bodies()[0].frame_from_body.translation() - Eigen::Vector3d(1.5, -2.5, 1.0)).norm(), 0,
      1e-12);
  // A zero quaternion is no pose: addMapWalls refuses it.
  grid.info.origin.orientation.z = grid.info.origin.orientation.w = 0;
  EXPECT_THROW(addMapWalls(occupancyOf(grid), options, &scene), SceneLoadError);
}

}  // namespace
}  // namespace laser_raycast_test
