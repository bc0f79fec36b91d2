// SceneLoader on the real TurtleBot3 data (../shared), counted independently of the loader.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "laser_raycast/loader/scene_loader.h"
#include "scene_loader_fixture.h"
#include "shared_data.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast;

using Eigen::Vector3d;

std::string sharedData() { return tb3WorldData(); }

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

// A binary STL's triangle count, from its header.
std::size_t stlTriangles(const std::string& path) {
  const std::string bytes = readText(path);
  std::uint32_t count = 0;
  std::memcpy(&count, bytes.data() + 80, 4);
  EXPECT_EQ(bytes.size(), 84 + 50 * std::size_t(count)) << path;
  return count;
}

// A Collada file's triangles: the sum of its <triangles count>, valid for files whose only
// triangle primitives are <triangles> and whose every geometry is instanced once (checked).
std::size_t colladaTriangles(const std::string& path) {
  const std::string text = readText(path);
  for (const char* other : {"<polylist", "<polygons", "<tristrips", "<trifans"}) {
    EXPECT_EQ(text.find(other), std::string::npos) << path << " has " << other;
  }
  const auto count = [&text](const std::regex& re) {
    return std::distance(std::sregex_iterator(text.begin(), text.end(), re),
                         std::sregex_iterator());
  };
  EXPECT_EQ(count(std::regex("<instance_geometry ")), count(std::regex("<geometry ")));
  std::size_t sum = 0;
  const std::regex re("<triangles[^>]*count=\"([0-9]+)\"");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), re); it != std::sregex_iterator();
       ++it) {
    sum += std::stoul((*it)[1]);
  }
  return sum;
}

class SharedDataTest : public SceneLoaderTest {
 protected:
  SharedDataTest()
      : tb3_loader_([](const std::string& package) -> std::optional<std::string> {
          if (package == "tb3_world_data") return sharedData();
          return std::nullopt;
        }) {}
  SceneLoader tb3_loader_;
};

TEST_F(SharedDataTest, TurtleBot3World) {
  REQUIRE_SHARED_DATA();
  const LoadedModel model =
      tb3_loader_.addUrdfFile(sharedData() + "/urdf/turtlebot3_world.urdf", {}, &scene_);
  EXPECT_EQ(model.name, "turtlebot3_world");
  EXPECT_EQ(model.links, 1u);
  EXPECT_EQ(model.bodies, 15u);
  EXPECT_TRUE(model.warnings.empty());
  EXPECT_EQ(scene_.frames(), std::vector<std::string>{"tb3_world"});
  // hexagon.dae at two scales and wall.dae.
  EXPECT_EQ(tb3_loader_.meshesLoaded(), 3u);
  const std::string meshes = sharedData() + "/meshes/";
  EXPECT_EQ(model.triangles,
            5 * colladaTriangles(meshes + "hexagon.dae") + colladaTriangles(meshes + "wall.dae"));

  int cylinders = 0, meshes_found = 0, heads = 0;
  for (int b = 0; b < static_cast<int>(scene_.bodies().size()); ++b) {
    const core::Body& body = scene_.bodies()[b];
    if (const auto* c = std::get_if<core::Cylinder>(&body.shape)) {
      ++cylinders;
      EXPECT_EQ(c->radius, 0.15);
      EXPECT_EQ(c->length, 0.5);
      EXPECT_EQ(body.frame_from_body.translation().z(), 0.25);
    } else if (const MeshPtr mesh = meshOf(scene_, b)) {
      ++meshes_found;
      if (body.frame_from_body.translation().isApprox(Vector3d(3.5, 0, -0.5))) {
        ++heads;
        // The "head" hexagon, by hand from the Collada numbers: radius 57.735 in, flats at
        // +-50 in, 100 in tall; inches to metres; URDF scale 0.8.
        const double s = 0.0254 * 0.8;
        expectBounds(*mesh, Vector3d(-57.735 * s, -50 * s, 0),
                     Vector3d(57.735 * s, 50 * s, 100 * s), 1e-6);
      }
    }
  }
  EXPECT_EQ(cylinders, 9);
  EXPECT_EQ(meshes_found, 6);
  EXPECT_EQ(heads, 1);
}

TEST_F(SharedDataTest, TurtleBot3Waffle) {
  REQUIRE_SHARED_DATA();
  const LoadedModel model =
      tb3_loader_.addUrdfFile(sharedData() + "/urdf/turtlebot3_waffle.urdf", {}, &scene_);
  EXPECT_TRUE(model.warnings.empty());
  EXPECT_EQ(model.root_link, "base_footprint");
  EXPECT_EQ(model.links, 13u);
  EXPECT_EQ(model.joints.size(), 12u);
  // Visual meshes for base, wheels, lidar and camera; the casters have only collision boxes.
  EXPECT_EQ(model.bodies, 7u);
  const std::string waffle = sharedData() + "/meshes/waffle/";
  EXPECT_EQ(model.triangles,
            colladaTriangles(waffle + "waffle_base.dae") + stlTriangles(waffle + "left_tire.stl") +
                stlTriangles(waffle + "right_tire.stl") + stlTriangles(waffle + "lds.stl") +
                colladaTriangles(waffle + "r200.dae"));
  // Everything but the wheels is fixed to base_footprint.
  std::set<std::string> frames(scene_.frames().begin(), scene_.frames().end());
  EXPECT_EQ(frames,
            (std::set<std::string>{"base_footprint", "wheel_left_link", "wheel_right_link"}));
  EXPECT_EQ(model.link_frames.at("camera_rgb_optical_frame").first, "base_footprint");

  // The STL meshes (float coordinates, URDF scale 0.001) keep their BVH slots in float, giving
  // back the very vertices the loader read.
  int stl_bodies = 0;
  for (int b = 0; b < static_cast<int>(scene_.bodies().size()); ++b) {
    const std::string label = labelOf(scene_, b);
    if (label != "wheel_left_link" && label != "wheel_right_link" && label != "base_scan") continue;
    ++stl_bodies;
    const MeshPtr mesh = meshOf(scene_, b);
    ASSERT_TRUE(mesh);
    EXPECT_TRUE(mesh->bvh().triangleVertices().packed()) << label;
    const auto& ids = mesh->bvh().triangleIds();
    for (std::uint32_t slot = 0; slot < ids.size(); ++slot) {
      const auto tri = mesh->bvh().triangleVertices()[slot];
      for (int k = 0; k < 3; ++k) {
        ASSERT_EQ(tri[k], mesh->vertices()[mesh->triangles()[ids[slot]][k]])
            << label << " " << slot;
      }
    }
  }
  EXPECT_EQ(stl_bodies, 3);

  int base_bodies = 0;
  for (int b = 0; b < static_cast<int>(scene_.bodies().size()); ++b) {
    if (labelOf(scene_, b) != "base_link") continue;
    ++base_bodies;
    const MeshPtr mesh = meshOf(scene_, b);
    ASSERT_TRUE(mesh);
    // By hand from waffle_base.dae (millimetres): node Cube.001 scales the [-1,1] cube by
    // (132.5, 132.5, 46) and lifts it by 46.12724; node Cube is the [-1,1] cube itself. The root's
    // Z_UP rotation is ignored, so z stays up.
    expectBounds(*mesh, Vector3d(-0.1325, -0.1325, -0.001), Vector3d(0.1325, 0.1325, 0.09212724),
                 1e-7);
    EXPECT_EQ(frameOf(scene_, b), "base_footprint");
    expectPose(scene_.bodies()[b].frame_from_body, pose({-0.064, 0, 0.010}));
  }
  EXPECT_EQ(base_bodies, 1);
}

}  // namespace
}  // namespace laser_raycast_test
