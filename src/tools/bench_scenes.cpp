#include "bench_scenes.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <random>
#include <stdexcept>

#include "bench_scene_builder.h"
#include "laser_raycast/loader/kinematics.h"
#include "laser_raycast/loader/package_resolver.h"
#include "laser_raycast/loader/scene_loader.h"

namespace laser_raycast {
namespace bench {
namespace {

// Tessellation of primitives for the soup. The error columns do not depend on it (each method is
// compared with a reference on the geometry it was given), nor does the pipeline's agreement with
// a peer (bench_run.cpp takes the difference of the two geometries out).
constexpr int kSphereSegments = 192, kSphereStacks = 96;
constexpr int kCylinderSegments = 96;

// The soup: every body's triangles (primitives tessellated) placed in the world in long double and
// rounded once. Vertices a body's triangles share stay shared.
MeshData flattenToSoup(const BenchScene& s) {
  MeshData soup;
  for (std::size_t b = 0; b < s.scene.bodies().size(); ++b) {
    const core::Shape& shape = s.scene.bodies()[b].shape;
    MeshData local;
    if (const auto* mesh = std::get_if<std::shared_ptr<const core::Mesh>>(&shape)) {
      local.vertices = (*mesh)->vertices().toVector();
      local.triangles = (*mesh)->triangles();
    } else if (const auto* box = std::get_if<core::Box>(&shape)) {
      local = boxMesh(box->size);
    } else if (const auto* cylinder = std::get_if<core::Cylinder>(&shape)) {
      local = cylinderMesh(cylinder->radius, {-cylinder->length / 2, cylinder->length / 2},
                           kCylinderSegments, true);
    } else {
      local = uvSphereMesh(std::get<core::Sphere>(shape).radius, kSphereSegments, kSphereStacks);
    }
    for (auto& v : local.vertices) v = s.body_poses[b].apply(v.cast<Real>()).cast<double>();
    soup.append(local);
  }
  return soup;
}

bool hasTb3Data(const std::string& dir) {
  return !dir.empty() &&
         std::filesystem::exists(dir + "/tb3_world_data/urdf/turtlebot3_world.urdf");
}

// One analytic sphere; half the poses inside it, half outside looking at it.
void buildSphere(BenchScene* s) {
  s->note = "an analytic sphere, r = 4.5 m; the soup is a 192 x 96 UV sphere";
  SceneBuilder(s).add(core::Sphere{4.5}, poseFromParams(0.3, -0.2, 1.1, 0, 0, 0), "sphere");
  s->sensor_poses = {{0.9, 0.4, 1.4, 0, 0, 0.4},     {8.7, 2.1, 1.6, 0, 0, 3.4},
                     {-1.7, 1.1, 0.6, 0, 0.08, 2.2}, {-6.5, -7.0, 0.9, 0, 0, 0.85},
                     {2.2, -2.4, 2.0, 0.1, 0, -2.0}, {1.0, 9.5, 1.3, 0, 0, -1.6}};
}

// A room (an analytic box seen from inside) with box furniture, some of it turned.
void buildBoxRoom(BenchScene* s) {
  s->note = "a 9 x 7 x 2.8 m room and 7 pieces of furniture, all analytic boxes";
  SceneBuilder b(s);
  b.add(core::Box{Eigen::Vector3d(9.0, 7.0, 2.8)}, poseFromParams(0.25, -0.4, 1.4, 0, 0, 0.15),
        "room");
  struct Furniture {
    double x, y, z, sx, sy, sz, yaw;
  };
  const Furniture furniture[] = {
      {2.1, 1.3, 0.375, 1.6, 0.8, 0.75, 0.15}, {-2.6, -1.9, 0.45, 0.9, 2.1, 0.9, 0.7},
      {-3.2, 2.0, 1.0, 0.4, 1.8, 2.0, 1.7208}, {1.0, -2.5, 0.25, 0.5, 0.5, 0.5, 0.3},
      {3.4, -1.4, 0.6, 0.7, 0.7, 1.2, -0.4},   {-0.8, 0.9, 2.5, 1.2, 1.2, 0.3, 0.15},
      {0.2, 2.6, 0.9, 2.4, 0.3, 1.8, 0.2}};
  for (const Furniture& f : furniture) {
    b.add(core::Box{Eigen::Vector3d(f.sx, f.sy, f.sz)}, poseFromParams(f.x, f.y, f.z, 0, 0, f.yaw),
          "furniture");
  }
  s->sensor_poses = {{0.1, -0.6, 0.41, 0, 0, 0.3},  {-1.3, 0.2, 1.1, 0.05, 0.1, 2.4},
                     {2.6, -0.3, 0.62, 0, 0, -2.2}, {-1.0, -1.0, 1.5, 0, -0.06, 1.0},
                     {0.9, 1.0, 0.33, 0, 0, -0.7},  {-2.2, 1.3, 0.8, 0, 0, -1.3}};
}

// The TurtleBot3 world (pillars analytic, hexagons and wall as meshes) and a parked Waffle (visual
// meshes), seen at the height of a Waffle's laser from six places in the arena.
void buildTb3(BenchScene* s, const std::string& shared_dir) {
  s->note = "the TurtleBot3 world and a Waffle's visual meshes (" + shared_dir + ")";
  const std::string data = shared_dir + "/tb3_world_data";
  SceneLoader loader([data](const std::string& package) -> std::optional<std::string> {
    if (package == "tb3_world_data") return data;
    return rosPackagePath(package);
  });
  loader.addUrdfFile(data + "/urdf/turtlebot3_world.urdf", LoaderOptions{}, &s->scene);
  LoaderOptions waffle_options;
  waffle_options.tf_prefix = "waffle/";
  const LoadedModel waffle =
      loader.addUrdfFile(data + "/urdf/turtlebot3_waffle.urdf", waffle_options, &s->scene);
  auto link_poses = forwardKinematics(waffle, poseFromXyzRpy(0.55, 0.55, 0, 0, 0, 0.7), {});
  link_poses["tb3_world"] = Eigen::Isometry3d::Identity();
  s->frame_poses = framePosesFromLinks(s->scene, link_poses);
  for (const core::Body& body : s->scene.bodies()) {
    if (!s->frame_poses.valid[body.frame]) throw std::runtime_error("tb3: a frame has no pose");
    s->body_poses.push_back(fromIsometry(s->frame_poses.pose[body.frame]) *
                            fromIsometry(body.frame_from_body));
  }
  const double z = 0.132;  // a Waffle's base_scan above the floor
  s->sensor_poses = {{1.25, 0.35, z, 0, 0, 2.6},    {-0.55, 0.6, z, 0, 0, -0.4},
                     {0.35, -1.6, z, 0, 0, 1.3},    {2.0, 0.05, z, 0, 0, 3.0},
                     {-1.6, -0.5, z, 0, 0.05, 0.2}, {0.6, 1.5, z, 0, 0, -1.9}};
}

// A forest of about a million triangles: a terrain and 118 trees (three trunk and three crown
// meshes, each shared by many trees, as the loader shares a mesh file), seen from a vehicle's roof.
void buildMillion(BenchScene* s) {
  s->note = "a forest: 256 x 256 terrain and 118 trees of 7424 triangles (6 shared meshes)";
  auto ground = [](double x, double y) {
    return 0.4 * std::sin(x / 9) * std::cos(y / 7) + 0.15 * std::sin((x + 2 * y) / 5);
  };
  SceneBuilder b(s);
  b.add(heightFieldMesh(-50, 50, -50, 50, 256, 256, ground), PoseL{}, "terrain");
  std::vector<std::shared_ptr<const core::Mesh>> trunks, crowns;
  const double trunk_radii[] = {0.18, 0.27, 0.4}, crown_radii[] = {1.6, 2.1, 2.6};
  for (int k = 0; k < 3; ++k) {
    const MeshData trunk = cylinderMesh(trunk_radii[k], steps(-0.5, 6.0, 0.25), 64, true);
    const MeshData crown = uvSphereMesh(crown_radii[k], 64, 32);
    trunks.push_back(meshAsRead(trunk));
    crowns.push_back(meshAsRead(crown));
  }

  auto vehicle = [&](double x, double y, double roll, double pitch, double yaw) {
    return SensorPose{x, y, ground(x, y) + 1.8, roll, pitch, yaw};
  };
  s->sensor_poses = {vehicle(0.5, -0.3, 0, 0, 0.2),         vehicle(12.3, 7.7, 0.02, -0.03, 2.5),
                     vehicle(-15.2, 4.4, 0, 0.01, -1.1),    vehicle(3.3, -18.6, -0.02, 0, 1.4),
                     vehicle(-7.7, -9.9, 0.01, 0.02, -2.6), vehicle(20.1, -3.2, 0, 0, 3.0)};

  std::mt19937_64 rng(20240611);
  std::vector<Eigen::Vector2d> placed;
  for (int attempt = 0; placed.size() < 118 && attempt < 100000; ++attempt) {
    const Eigen::Vector2d p(uniform(rng, -42, 42), uniform(rng, -42, 42));
    bool free = p.norm() <= 42;
    for (const auto& q : placed) free = free && (p - q).norm() >= 3.2;
    for (const auto& v : s->sensor_poses)
      free = free && (p - Eigen::Vector2d(v.x, v.y)).norm() >= 3.5;
    if (!free) continue;
    const int kind = static_cast<int>(placed.size() % 3);
    const double yaw = uniform(rng, -M_PI, M_PI);
    const double z = ground(p.x(), p.y());
    b.add(trunks[kind], poseFromParams(p.x(), p.y(), z, 0, 0, yaw), "trunk");
    b.add(crowns[kind], poseFromParams(p.x(), p.y(), z + 6.0 + 0.7 * crown_radii[kind], 0, 0, yaw),
          "crown");
    placed.push_back(p);
  }
  if (placed.size() < 118) throw std::runtime_error("million: could not place the trees");
}

// An octagonal room whose walls, and ten tree trunks, have rows of vertices at the laser's height
// (0.5 m above the floor), with sensors on the floor's frame: the scan plane runs exactly through
// the rows' shared edges. `place` puts the room in the world.
void addVertexRowsRoom(SceneBuilder* b, const PoseL& place, std::vector<SensorPose>* sensors) {
  const std::vector<double> rows = steps(0.0, 2.5, 0.125);
  std::vector<Eigen::Vector2d> corners;
  const double corner_radius = 6.0 / std::cos(M_PI / 8);
  for (int k = 0; k < 8; ++k) {
    const double a = M_PI / 8 + k * M_PI / 4;
    corners.emplace_back(corner_radius * std::cos(a), corner_radius * std::sin(a));
  }
  b->add(wallBandMesh(corners, 16, rows), place, "walls");
  // Floor and ceiling reach under the walls, so the room is closed without shared edges.
  b->add(heightFieldMesh(-7, 7, -7, 7, 14, 14, [](double, double) { return 0.0; }), place, "floor");
  b->add(heightFieldMesh(-7, 7, -7, 7, 14, 14, [](double, double) { return 2.5; }), place,
         "ceiling");
  const double trunks[][3] = {{1.7, 0.9, 0.2},   {-2.3, 1.8, 0.35},  {0.4, -2.6, 0.12},
                              {3.1, -1.5, 0.25}, {-3.4, -1.2, 0.3},  {-0.9, 3.6, 0.15},
                              {2.6, 3.0, 0.28},  {-1.6, -3.9, 0.22}, {4.2, 1.1, 0.18},
                              {-4.3, 1.9, 0.33}};
  for (int k = 0; k < 10; ++k) {
    // Translated only (within the room): the rows stay at the room's row heights.
    b->add(cylinderMesh(trunks[k][2], rows, k % 2 ? 24 : 40, false),
           place * poseFromParams(trunks[k][0], trunks[k][1], 0, 0, 0, 0), "trunk");
  }
  const double z = 0.5;
  const SensorPose level[] = {{0.3, 0.2, z, 0, 0, 0.1},   {-1.1, -0.7, z, 0, 0, 2.3},
                              {2.2, 1.9, z, 0, 0, -2.8},  {-2.8, 0.4, z, 0, 0, 0.9},
                              {1.2, -1.3, z, 0, 0, -1.2}, {-0.4, 2.1, z, 0, 0, 1.7}};
  for (SensorPose p : level) {
    p.base = place;
    sensors->push_back(p);
  }
}

// Two such rooms: one on the world's axes, where the coincidence is exact in every coordinate (the
// beams' z component is exactly 0 and the rows' z exactly the sensor's), and one tilted (on a
// slope), where it is exact only before rounding: the beams then pass within an ulp of the shared
// edges, on either side, which is where tests that are not watertight let them through. The
// sensor poses alternate between the rooms, tilted first.
void buildVertexRows(BenchScene* s) {
  s->note =
      "two octagonal rooms (one tilted) with 10 trunks each, vertex rows at the laser's height";
  SceneBuilder b(s);
  std::vector<SensorPose> level, tilted;
  addVertexRowsRoom(&b, PoseL{}, &level);
  addVertexRowsRoom(&b, poseFromParams(40, 0, 3, 0.25, -0.15, 0.6), &tilted);
  for (std::size_t k = 0; k < 3; ++k) {
    s->sensor_poses.push_back(tilted[k]);
    s->sensor_poses.push_back(level[k]);
  }
}

// One mesh of slightly tapered trunks (a single body, as one STL file holding many objects loads),
// 2,500 triangles each, scattered over a disc: 354 stems per hectare, a managed forest's density,
// so that a laser in the middle sees near and far trunks within 30 m and many beams between them.
// Every trunk has rings of vertices at the same heights (every 0.5 m) and every laser is level at
// a ring's height: the fan's scan plane runs exactly along the rings' shared edges, the worst case
// for watertightness. forest: 400 trunks on a disc of 60 m radius (1M triangles); forest_10m:
// 4,000 on one of 190 m (10M triangles, a 1 GB STL's worth), the same density.
void buildForest(BenchScene* s, std::size_t trunks, double disc_radius) {
  constexpr int kSegments = 50;
  constexpr double kSpacing = 1.5, kLaserZ = 1.0;
  const std::vector<double> rings = steps(0.0, 12.5, 0.5);  // 25 bands x 50 segments x 2
  s->note = "a forest: one mesh of " + std::to_string(trunks) + " trunks of 2500 triangles on a " +
            std::to_string(std::lround(disc_radius)) + " m disc, laser at a ring";
  s->range_max = 30;
  const double z = kLaserZ;  // rings[2], exactly
  s->sensor_poses = {{0.0, 0.0, z, 0, 0, 0.3},    {8.4, -5.1, z, 0, 0, 2.2},
                     {-13.7, 9.2, z, 0, 0, -0.8}, {17.5, 12.6, z, 0, 0, -2.6},
                     {-5.9, -19.3, z, 0, 0, 1.2}, {22.4, -2.8, z, 0, 0, 3.0}};

  std::mt19937_64 rng(20250301);
  MeshData forest;
  std::vector<Eigen::Vector2d> placed;
  for (int attempt = 0; placed.size() < trunks && attempt < 1000000; ++attempt) {
    const Eigen::Vector2d p(uniform(rng, -disc_radius, disc_radius),
                            uniform(rng, -disc_radius, disc_radius));
    bool free = p.norm() <= disc_radius;
    for (const auto& q : placed) free = free && (p - q).norm() >= kSpacing;
    for (const auto& v : s->sensor_poses) {
      free = free && (p - Eigen::Vector2d(v.x, v.y)).norm() >= kSpacing;
    }
    if (!free) continue;
    // Breast-height diameters of 20 to 60 cm, 40% thinner at the top.
    const double radius = uniform(rng, 0.10, 0.30);
    MeshData trunk = taperedCylinderMesh(radius, 0.6 * radius, rings, kSegments, false);
    for (auto& v : trunk.vertices) v.head<2>() += p;  // z, the ring heights, untouched
    forest.append(trunk);
    placed.push_back(p);
  }
  if (placed.size() < trunks) throw std::runtime_error("forest: could not place the trunks");
  SceneBuilder(s).add(forest, PoseL{}, "forest");
}

}  // namespace

const std::vector<std::string>& sceneNames() {
  static const std::vector<std::string> names = {
      "sphere", "box_room", "tb3", "million", "vertex_rows", "forest", "warehouse", "forest_10m"};
  return names;
}

bool isLargeScene(const std::string& name) { return name == "forest_10m"; }

std::string findSharedData() {
  const char* env = std::getenv("LASER_RAYCAST_SHARED_DATA");
  if (env && *env) return hasTb3Data(env) ? std::string(env) : std::string();
  if (const auto path = rosPackagePath("tb3_world_data")) {
    const std::string parent = std::filesystem::path(*path).parent_path().string();
    if (hasTb3Data(parent)) return parent;
  }
  const std::string beside = std::string(LASER_RAYCAST_SOURCE_DIR) + "/../shared/data";
  return hasTb3Data(beside) ? beside : std::string();
}

std::optional<BenchScene> makeScene(const std::string& name, const std::string& shared_data_dir) {
  BenchScene s;
  s.name = name;
  if (name == "sphere") {
    buildSphere(&s);
  } else if (name == "box_room") {
    buildBoxRoom(&s);
  } else if (name == "tb3") {
    if (!hasTb3Data(shared_data_dir)) return std::nullopt;
    buildTb3(&s, shared_data_dir);
  } else if (name == "million") {
    buildMillion(&s);
  } else if (name == "vertex_rows") {
    buildVertexRows(&s);
  } else if (name == "forest") {
    buildForest(&s, 400, 60);
  } else if (name == "forest_10m") {
    buildForest(&s, 4000, 190);
  } else if (name == "warehouse") {
    buildWarehouse(&s);
  } else {
    throw std::runtime_error("unknown scene '" + name + "'");
  }
  if (s.frame_poses.pose.empty()) s.frame_poses = core::FramePoses::identity(s.scene);
  s.soup = flattenToSoup(s);
  return s;
}

}  // namespace bench
}  // namespace laser_raycast
