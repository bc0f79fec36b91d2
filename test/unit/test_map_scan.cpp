// Scans of a map world (map_walls.h's boxes through the caster) against distances computed here,
// in long double, by brute force over the occupied cells as closed boxes: beams aimed exactly at
// every corner of every occupied cell (where diagonal neighbours touch at one point, a beam between
// them meets both there) and along cell boundaries (the faces two boxes share), from sensors on
// the grid, level and through kept slices; random fans, and rings looking down on the walls' tops.
// Every range is within 1e-6 m of the exact walls' distance: no beam leaks between boxes.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "laser_raycast/core/caster.h"
#include "laser_raycast/loader/map_walls.h"
#include "random.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast;
using Real = long double;
using Vec = Eigen::Matrix<Real, 3, 1>;

constexpr double kResolution = 0.05;  // m
constexpr double kHeight = 1.0;       // m
constexpr Real kInf = std::numeric_limits<Real>::infinity();

// The test's map, in cells: a border, a diagonal line of single cells, a checkerboard, an L and
// random cells.
OccupancyMap testMap() {
  OccupancyMap map;
  map.width = 30;
  map.height = 24;
  map.resolution = kResolution;
  map.occupied.assign(static_cast<std::size_t>(map.width) * map.height, 0);
  const auto set = [&](int i, int j) {
    map.occupied[static_cast<std::size_t>(j) * map.width + i] = 1;
  };
  for (int i = 0; i < map.width; ++i) set(i, 0), set(i, map.height - 1);
  for (int j = 0; j < map.height; ++j) set(0, j), set(map.width - 1, j);
  for (int k = 5; k < 12; ++k) set(k, k);
  for (int i = 18; i < 24; ++i) {
    for (int j = 4; j < 10; ++j) {
      if ((i + j) % 2 == 0) set(i, j);
    }
  }
  for (int i = 5; i < 12; ++i) set(i, 18);
  for (int j = 15; j < 18; ++j) set(5, j);
  Rng rng(2024);
  for (int i = 16; i < 27; ++i) {
    for (int j = 13; j < 20; ++j) {
      if (uniform(rng, 0, 1) < 0.3) set(i, j);
    }
  }
  map.origin =
      Eigen::Translation3d(-0.7, 0.3, 0.0) * Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ());
  return map;
}

// The nearest t >= 0 at which o + t d (in cells, z in m / resolution) meets a closed occupied cell
// grown by `grow` cells in x and y, from 0 to the wall height: the slab test, exact to long double.
Real referenceDistance(const OccupancyMap& map, const Vec& o, const Vec& d, Real grow) {
  Real best = kInf;
  const Real top = Real(kHeight) / Real(kResolution);
  for (int j = 0; j < map.height; ++j) {
    for (int i = 0; i < map.width; ++i) {
      if (!map.at(i, j)) continue;
      const Real lo[3] = {i - grow, j - grow, 0}, hi[3] = {i + 1 + grow, j + 1 + grow, top};
      Real enter = 0, leave = kInf;
      bool miss = false;
      for (int k = 0; k < 3 && !miss; ++k) {
        if (d[k] == 0) {
          miss = o[k] < lo[k] || o[k] > hi[k];
          continue;
        }
        Real t0 = (lo[k] - o[k]) / d[k], t1 = (hi[k] - o[k]) / d[k];
        if (t0 > t1) std::swap(t0, t1);
        enter = std::max(enter, t0);
        leave = std::min(leave, t1);
        miss = enter > leave;
      }
      if (!miss && enter < best) best = enter;
    }
  }
  return best;
}

// The scene: the map's walls on frame "map", which lies at kMapPose in the world.
struct World {
  OccupancyMap map = testMap();
  core::Scene scene;
  core::FramePoses poses;
  Eigen::Isometry3d world_from_cells;  // the frame's pose and the map's origin, scaled to cells
  double widening = 0;                 // m
  core::Caster caster;

  World() {
    MapWallOptions options;
    options.height = kHeight;
    widening = addMapWalls(map, options, &scene).widening;
    const Eigen::Isometry3d world_from_map =
        Eigen::Translation3d(10.0, -20.0, 0.3) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ());
    poses = core::FramePoses::identity(scene);
    poses.pose[0] = world_from_map;
    world_from_cells = world_from_map * map.origin;
  }

  // The sensor at cell coordinates (x, y), height z (m above the map's floor), turned by yaw from
  // the map's x axis and pitched by pitch.
  Eigen::Isometry3d sensorAt(double x, double y, double z, double yaw, double pitch = 0) const {
    return world_from_cells * Eigen::Translation3d(x * kResolution, y * kResolution, z) *
           Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
           Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY());
  }

  const core::ScanResult& cast(const Eigen::Isometry3d& sensor, const core::ScanPattern& pattern) {
    return caster.cast(scene, poses, sensor, pattern, core::CastConfig());
  }
};

// A fan whose beam 0 looks along the sensor's x axis exactly.
const core::ScanPattern& aheadPattern() {
  static const core::ScanPattern pattern([] {
    core::FanSpec fan;
    fan.angle_min = 0;
    fan.angle_max = 0.1;
    fan.samples = 2;
    return fan;
  }());
  return pattern;
}

// Sensors where the four cells around a grid point are free: (x, y) in cells.
std::vector<Eigen::Vector2i> freeGridPoints(const OccupancyMap& map) {
  std::vector<Eigen::Vector2i> points;
  for (int j = 1; j < map.height; ++j) {
    for (int i = 1; i < map.width; ++i) {
      if (!map.at(i - 1, j - 1) && !map.at(i, j - 1) && !map.at(i - 1, j) && !map.at(i, j)) {
        points.emplace_back(i, j);
      }
    }
  }
  return points;
}

// Beams from sensors at free grid points aimed exactly at every corner of an occupied cell in
// view: the cast range against the exact walls' distance along the ideal beam (sensor to corner).
TEST(MapScan, BeamsAtEveryCellCornerLeakNowhere) {
  World world;
  const OccupancyMap& map = world.map;
  const std::vector<Eigen::Vector2i> free = freeGridPoints(map);
  ASSERT_GT(free.size(), 100u);
  const double z = 0.4 * kHeight;
  int beams = 0, through_corners = 0;
  double worst = 0;
  for (const std::size_t s : {std::size_t(0), free.size() / 3, free.size() / 2, free.size() - 1}) {
    const Eigen::Vector2i sensor = free[s];
    for (int j = 0; j <= map.height; ++j) {
      for (int i = 0; i <= map.width; ++i) {
        // A corner of an occupied cell.
        bool corner = false;
        for (int a = i - 1; a <= i; ++a) {
          for (int b = j - 1; b <= j; ++b) {
            corner |= a >= 0 && b >= 0 && a < map.width && b < map.height && map.at(a, b);
          }
        }
        if (!corner || (Eigen::Vector2i(i, j) == sensor)) continue;
        const Vec o(sensor.x(), sensor.y(), z / kResolution);
        const Vec d(i - sensor.x(), j - sensor.y(), 0);
        const Real exact = referenceDistance(map, o, d / d.norm(), 0) * kResolution;
        const double yaw = std::atan2(double(d.y()), double(d.x()));
        const double range =
            world.cast(world.sensorAt(sensor.x(), sensor.y(), z, yaw), aheadPattern()).range[0];
        ++beams;
        through_corners += std::abs(exact - d.norm() * kResolution) < 1e-12;
        const double error = std::abs(range - double(exact));
        worst = std::max(worst, error);
        EXPECT_LE(error, 1e-6) << "sensor (" << sensor.x() << ", " << sensor.y() << ") to corner ("
                               << i << ", " << j << "): " << range << " m, exact " << double(exact);
      }
    }
  }
  // Many beams reach their corner (the others meet a wall before it).
  EXPECT_GT(through_corners, 300);
  std::printf("%d beams at cell corners (%d reaching theirs), worst error %.3g m\n", beams,
              through_corners, worst);
}

// Beams along every grid line between cells, from the free grid points on it, both ways: they run
// along the faces that neighbouring boxes share, and past the corners of cells on either side.
TEST(MapScan, BeamsAlongCellBoundariesLeakNowhere) {
  World world;
  const OccupancyMap& map = world.map;
  const double z = 0.7 * kHeight;
  int beams = 0;
  double worst = 0;
  for (const Eigen::Vector2i& p : freeGridPoints(map)) {
    for (int k = 0; k < 4; ++k) {
      const Vec o(p.x(), p.y(), z / kResolution);
      const Vec d(k == 0 ? 1 : k == 2 ? -1 : 0, k == 1 ? 1 : k == 3 ? -1 : 0, 0);
      const Real exact = referenceDistance(map, o, d, 0) * kResolution;
      const double range =
          world.cast(world.sensorAt(p.x(), p.y(), z, k * M_PI / 2), aheadPattern()).range[0];
      ++beams;
      const double error = std::abs(range - double(exact));
      worst = std::max(worst, error);
      EXPECT_LE(error, 1e-6) << "from (" << p.x() << ", " << p.y() << ") along axis " << k << ": "
                             << range << " m, exact " << double(exact);
    }
  }
  std::printf("%d beams along cell boundaries, worst error %.3g m\n", beams, worst);
}

// Fans and rings from random poses: every beam against the walls as the scene holds them (widened),
// to rounding, and against the exact walls within 1e-6 m wherever the two differ by less (the
// others, counted, pass within the widening of a corner or graze a wall within a degree).
TEST(MapScan, RandomFansAndRingsMatchTheWalls) {
  World world;
  const OccupancyMap& map = world.map;
  Rng rng(7);
  const core::ScanPattern fan([] {
    core::FanSpec f;
    f.samples = 720;
    return f;
  }());
  core::FanSpec ring_fan;
  ring_fan.samples = 360;
  const core::ScanPattern rings(ring_fan, {-0.9, -0.5, -0.2, 0.0, 0.3});
  int beams = 0, near = 0;
  double worst_widened = 0, worst_exact = 0;
  for (int pose = 0; pose < 16; ++pose) {
    const bool ringed = pose % 4 == 3;
    // A free point (inside a free cell), in cells.
    double x, y;
    do {
      x = uniform(rng, 1, map.width - 1);
      y = uniform(rng, 1, map.height - 1);
    } while (map.at(int(x), int(y)));
    const double z = ringed ? 1.3 * kHeight : uniform(rng, 0.1, 0.9) * kHeight;
    const double yaw = uniform(rng, -M_PI, M_PI);
    const double pitch = ringed ? uniform(rng, -0.2, 0.2) : 0;
    const core::ScanPattern& pattern = ringed ? rings : fan;
    const core::ScanResult& result = world.cast(world.sensorAt(x, y, z, yaw, pitch), pattern);
    const Eigen::Matrix3d rot = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()))
                                    .toRotationMatrix();
    for (int b = 0; b < pattern.size(); ++b) {
      const Vec o(x, y, z / kResolution);
      const Vec d = (rot * pattern.directions()[b]).cast<Real>();
      const Real exact = referenceDistance(map, o, d, 0) * kResolution;
      const Real widened =
          referenceDistance(map, o, d, Real(world.widening) / kResolution) * kResolution;
      const double range = result.range[b];
      ++beams;
      if (std::isinf(widened)) {
        EXPECT_TRUE(std::isinf(range)) << "pose " << pose << " beam " << b << ": " << range;
        continue;
      }
      ASSERT_TRUE(std::isfinite(range))
          << "pose " << pose << " beam " << b << ": widened walls at " << double(widened) << " m";
      worst_widened = std::max(worst_widened, double(std::abs(range - widened)));
      EXPECT_LE(std::abs(range - widened), 1e-9) << "pose " << pose << " beam " << b;
      if (std::abs(exact - widened) > 1e-6) {
        ++near;
        continue;
      }
      worst_exact = std::max(worst_exact, double(std::abs(range - exact)));
      EXPECT_LE(std::abs(range - exact), 1e-6) << "pose " << pose << " beam " << b;
    }
  }
  EXPECT_LE(near, 2);
  std::printf(
      "%d beams: worst %.3g m from the widened walls, %.3g m from the exact ones; %d more than "
      "1e-6 m apart\n",
      beams, worst_widened, worst_exact, near);
}

}  // namespace
}  // namespace laser_raycast_test
