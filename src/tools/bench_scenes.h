// The benchmark's scenes. Each is held twice, as the same geometry:
// - a core::Scene as the node holds it (meshes in their own frames, shared between instances; URDF
//   primitives analytic), for the pipeline row;
// - one triangle soup in the world frame (primitives tessellated), for the triangle methods and
//   the peers.
// Every body also carries its pose in long double, so that the reference can place it without the
// rounding the double pose has.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "bench_meshes.h"
#include "laser_raycast/core/scene.h"

namespace laser_raycast {
namespace bench {

// A sensor pose as parameters: metres and radians, URDF roll/pitch/yaw, in the frame `base`.
struct SensorPose {
  double x, y, z, roll, pitch, yaw;
  PoseL base = PoseL{};
  PoseL exact() const { return base * poseFromParams(x, y, z, roll, pitch, yaw); }
};

struct BenchScene {
  std::string name;
  core::Scene scene;
  core::FramePoses frame_poses;
  // Per body: world_from_body in long double (from the parameters where the benchmark made the
  // scene, otherwise the loaded double poses composed exactly).
  std::vector<PoseL> body_poses;
  // The sensor poses, most varied first: --quick uses the first few.
  std::vector<SensorPose> sensor_poses;
  MeshData soup;           // world frame
  std::string note;        // one line on what the scene is, for the log
  double range_max = 100;  // m: every method's tmax on this scene
};

// The scene names, in output order.
const std::vector<std::string>& sceneNames();
// Whether a scene is left out of a --quick run unless named (forest_10m: its build alone takes
// about a minute).
bool isLargeScene(const std::string& name);

// Builds the named scene. tb3 needs the directory holding tb3_world_data (shared_data_dir) and
// returns nullopt without it; every other scene is generated. Throws std::runtime_error if
// something cannot be built.
std::optional<BenchScene> makeScene(const std::string& name, const std::string& shared_data_dir);

// The directory holding tb3_world_data: $LASER_RAYCAST_SHARED_DATA, else the parent of the ROS
// package tb3_world_data, else <source dir>/../shared/data; empty if none of them has it.
std::string findSharedData();

}  // namespace bench
}  // namespace laser_raycast
