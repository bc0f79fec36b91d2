// The warehouse scene: a closed building with 313 bays of pallet racking (one shared mesh, as the
// loader shares a mesh file), drums on pallets and stacks of empty pallets as URDF primitives, seen
// by a forklift's safety laser from the aisles.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bench_scene_builder.h"

namespace laser_raycast {
namespace bench {
namespace {

// The building's inside (m): x in [-kHalfX, kHalfX], y in [-kHalfY, kHalfY], floor at z = 0.
constexpr double kHalfX = 31.7, kHalfY = 21.7, kWall = 0.3, kHeight = 8.0;
// A bay of racking: x along the aisle, y across it (front at +y), z up from the floor.
constexpr double kBayLength = 2.7, kBayDepth = 1.1;
constexpr int kBayTriangles = 3840, kCartons = 262;
// Rows along x: 2 x 10 bays either side of a 3 m cross aisle; 16 rows across y (a single row
// against each long wall, 7 back-to-back pairs with a 0.1 m flue); 7 bays of the last row left
// free for a staging area: 16 x 20 - 7 = 313 bays.
constexpr int kBaysPerSection = 10, kDoublePairs = 7, kFreeBays = 7;
constexpr double kCrossAisle = 3.0, kWallGap = 0.1, kFlue = 0.1;
// A Euro pallet and a 200 l steel drum; two drums fit on a pallet along its 1.2 m side.
const Eigen::Vector3d kPallet(0.8, 1.2, 0.144);
constexpr double kDrumRadius = 0.29, kDrumHeight = 0.88;
constexpr int kDrumPallets = 75, kPalletStacks = 5, kStackHeight = 5;
// A safety laser scanner's height on a forklift: it sees uprights, bracing, the lowest cartons,
// drums and pallet stacks.
constexpr double kLaserZ = 0.35;

Eigen::Isometry3d placeAt(const Eigen::Vector3d& centre,
                          const Eigen::Matrix3d& rotation = Eigen::Matrix3d::Identity()) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = rotation;
  pose.translation() = centre;
  return pose;
}

// The steel: four 90 x 70 mm C-profile uprights (2.5 mm thick, open towards the bay) on foot
// plates, the two side frames braced by 30 mm tubes (5 horizontal, 4 diagonal), and per level two
// beams and four wire decking panels. 58 boxes.
void addRackSteel(const std::vector<double>& levels, MeshData* m) {
  auto box = [m](const Eigen::Vector3d& centre, const Eigen::Vector3d& size,
                 const Eigen::Matrix3d& rotation = Eigen::Matrix3d::Identity()) {
    m->append(boxMesh(size, placeAt(centre, rotation)));
  };
  const double ux = 1.30, uy = 0.50, web = 0.09, flange = 0.07, t = 0.0025, h = 4.0;
  for (const double sx : {-1.0, 1.0}) {
    for (const double sy : {-1.0, 1.0}) {
      const double x = sx * ux, y = sy * uy;
      box({x + sx * (flange - t) / 2, y, h / 2}, {t, web, h});
      box({x, y - (web - t) / 2, h / 2}, {flange, t, h});
      box({x, y + (web - t) / 2, h / 2}, {flange, t, h});
      box({x, y, 0.005}, {0.15, 0.15, 0.01});
    }
    const double span = 2 * (uy - web / 2);
    const std::vector<double> braces = {0.3, 1.3, 2.3, 3.3, 3.9};
    for (std::size_t k = 0; k < braces.size(); ++k) {
      box({sx * ux, 0, braces[k]}, {0.03, span, 0.03});
      if (k + 1 == braces.size()) continue;
      const double rise = braces[k + 1] - braces[k];
      const double angle = (k % 2 ? -1 : 1) * std::atan2(rise, span);
      box({sx * ux, 0, (braces[k] + braces[k + 1]) / 2}, {0.03, std::hypot(span, rise), 0.03},
          Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitX()).toRotationMatrix());
    }
  }
  for (const double top : levels) {
    for (const double sy : {-1.0, 1.0}) box({0, sy * 0.52, top - 0.05}, {2.53, 0.05, 0.10});
    for (const double x : {-0.945, -0.315, 0.315, 0.945}) {
      box({x, 0, top + 0.015}, {0.6, 1.04, 0.03});
    }
  }
}

// One bay, 2.7 x 1.1 x 4.0 m: the steel and 262 cartons (0.30 x 0.25 x 0.20 m) in stacks of up
// to three on an 8 x 4 grid on each of the four decks, where a fixed seed puts them. 320 boxes of
// 12 triangles: 3,840.
MeshData rackMesh() {
  const std::vector<double> levels = {0.25, 1.20, 2.15, 3.10};  // beam tops
  MeshData m;
  addRackSteel(levels, &m);
  constexpr int kColumns = 8, kRows = 4, kMaxStack = 3;
  std::vector<int> stack(levels.size() * kColumns * kRows, 0);
  std::mt19937_64 rng(7340);
  for (int placed = 0; placed < kCartons;) {
    int& cell = stack[rng() % stack.size()];
    if (cell < kMaxStack) {
      ++cell;
      ++placed;
    }
  }
  for (std::size_t c = 0; c < stack.size(); ++c) {
    const double deck = levels[c / (kColumns * kRows)] + 0.03;
    const int column = static_cast<int>(c % kColumns), row = static_cast<int>(c / kColumns % kRows);
    for (int k = 0; k < stack[c]; ++k) {
      m.append(boxMesh({0.30, 0.25, 0.20}, placeAt({-1.085 + 0.31 * column, -0.39 + 0.26 * row,
                                                    deck + 0.1 + 0.2 * k})));
    }
  }
  if (m.triangles.size() != static_cast<std::size_t>(kBayTriangles)) {
    throw std::logic_error("warehouse: the rack has " + std::to_string(m.triangles.size()) +
                           " triangles, not 3840");
  }
  return m;
}

// The rows' bay centres (y) and facing (yaw 0: front to +y), from the -y wall; aisle_centres gets
// the y of each aisle between them.
std::vector<std::pair<double, double>> rackRows(std::vector<double>* aisle_centres) {
  const double depth = 2 * kWallGap + 2 * kBayDepth + kDoublePairs * (2 * kBayDepth + kFlue);
  const double aisle = (2 * kHalfY - depth) / (kDoublePairs + 1);
  std::vector<std::pair<double, double>> rows;
  double y = -kHalfY + kWallGap;
  rows.emplace_back(y + kBayDepth / 2, 0.0);
  y += kBayDepth;
  for (int pair = 0; pair <= kDoublePairs; ++pair) {
    aisle_centres->push_back(y + aisle / 2);
    y += aisle;
    rows.emplace_back(y + kBayDepth / 2, M_PI);
    y += kBayDepth;
    if (pair == kDoublePairs) break;  // the last row, against the +y wall, is single
    y += kFlue;
    rows.emplace_back(y + kBayDepth / 2, 0.0);
    y += kBayDepth;
  }
  return rows;
}

// Pallet places (centre x, y; the 1.2 m side along y): a strip along each end wall, and the free
// bays of the last row.
std::vector<Eigen::Vector2d> palletSlots(double free_from_x) {
  std::vector<Eigen::Vector2d> slots;
  const double wall_x = kHalfX - kWallGap - kPallet.x() / 2;
  for (const double y : steps(-20.25, 20.25, 0.9)) {
    slots.emplace_back(-wall_x, y);
    slots.emplace_back(wall_x, y);
  }
  const double row_y = kHalfY - kWallGap - kPallet.y() / 2;
  const double row_end = kCrossAisle / 2 + kBaysPerSection * kBayLength;
  for (int k = 0; free_from_x + 0.1 + 0.9 * k + kPallet.x() <= row_end; ++k) {
    slots.emplace_back(free_from_x + 0.1 + 0.9 * k + kPallet.x() / 2, row_y);
  }
  return slots;
}

void addRacks(SceneBuilder* b, std::vector<double>* aisle_centres, double* free_from_x) {
  const MeshData rack = rackMesh();
  const auto mesh = meshAsRead(rack);
  const auto rows = rackRows(aisle_centres);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    for (const double side : {-1.0, 1.0}) {
      for (int k = 0; k < kBaysPerSection; ++k) {
        const bool free = r + 1 == rows.size() && side > 0 && k >= kBaysPerSection - kFreeBays;
        const double x = side * (kCrossAisle / 2 + kBayLength / 2 + kBayLength * k);
        if (free) {
          *free_from_x = std::min(*free_from_x, x - kBayLength / 2);
          continue;
        }
        b->add(mesh, poseFromParams(x, rows[r].first, 0, 0, 0, rows[r].second), "rack");
      }
    }
  }
}

void addBuilding(SceneBuilder* b) {
  const double outer_x = 2 * (kHalfX + kWall), outer_y = 2 * (kHalfY + kWall);
  const double mid_z = kHeight / 2;
  auto box = [b](double x, double y, double z, double sx, double sy, double sz) {
    b->add(core::Box{Eigen::Vector3d(sx, sy, sz)}, poseFromParams(x, y, z, 0, 0, 0), "building");
  };
  box(0, 0, -0.1, outer_x, outer_y, 0.2);           // floor
  box(0, 0, kHeight + 0.1, outer_x, outer_y, 0.2);  // roof
  for (const double s : {-1.0, 1.0}) {
    box(0, s * (kHalfY + kWall / 2), mid_z, outer_x, kWall, kHeight);
    box(s * (kHalfX + kWall / 2), 0, mid_z, kWall, 2 * kHalfY, kHeight);
  }
}

// 75 pallets with two drums each and 5 stacks of 5 empty pallets, on slots a fixed seed picks.
void addPalletsAndDrums(SceneBuilder* b, std::vector<Eigen::Vector2d> slots) {
  std::mt19937_64 rng(4096);
  for (std::size_t i = slots.size() - 1; i > 0; --i) std::swap(slots[i], slots[rng() % (i + 1)]);
  const std::size_t needed = kDrumPallets + kPalletStacks;
  if (slots.size() < needed) throw std::logic_error("warehouse: too few pallet slots");
  const core::Box pallet{kPallet};
  for (std::size_t i = 0; i < needed; ++i) {
    const Eigen::Vector2d& p = slots[i];
    const int pallets = i < kDrumPallets ? 1 : kStackHeight;
    for (int k = 0; k < pallets; ++k) {
      b->add(pallet, poseFromParams(p.x(), p.y(), kPallet.z() * (k + 0.5), 0, 0, 0), "pallet");
    }
    if (i >= kDrumPallets) continue;
    for (const double side : {-1.0, 1.0}) {
      b->add(core::Cylinder{kDrumRadius, kDrumHeight},
             poseFromParams(p.x(), p.y() + side * 0.3, kPallet.z() + kDrumHeight / 2, 0, 0, 0),
             "drum");
    }
  }
}

}  // namespace

void buildWarehouse(BenchScene* s) {
  s->note =
      "a 64 x 44 x 8 m warehouse: 313 racks of 3840 triangles (one shared mesh), 150 drums and 100 "
      "pallets as primitives";
  s->range_max = 40;
  SceneBuilder b(s);
  addBuilding(&b);
  std::vector<double> aisles;
  double free_from_x = kHalfX;
  addRacks(&b, &aisles, &free_from_x);
  addPalletsAndDrums(&b, palletSlots(free_from_x));
  // In the aisles (one in the cross aisle, one in an end aisle), mostly looking along them.
  const double z = kLaserZ;
  s->sensor_poses = {{-14.2, aisles[3], z, 0, 0, 0.05},
                     {0.0, 1.3, z, 0, 0, M_PI / 2 + 0.1},
                     {17.9, aisles[6], z, 0, 0, M_PI - 0.03},
                     {-25.3, aisles[0], z, 0, 0, 0.4},
                     {29.6, -3.7, z, 0, 0, 1.9},
                     {6.6, aisles[4], z, 0, 0, -3.0}};
}

}  // namespace bench
}  // namespace laser_raycast
