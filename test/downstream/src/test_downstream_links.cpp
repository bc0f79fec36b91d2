// A downstream package's view of laser_raycast: each exported library is linked through catkin and
// used once. A library that is installed but not exported fails here at link time ("undefined
// reference"), as it would in a user's package.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <variant>

#include "laser_raycast/core/scan_pattern.h"
#include "laser_raycast/core/scene.h"
#include "laser_raycast/loader/kinematics.h"
#include "laser_raycast/loader/package_resolver.h"
#include "laser_raycast/loader/scene_loader.h"
#include "laser_raycast/node/node_params.h"

TEST(Downstream, UsesTheCore) {
  laser_raycast::core::FanSpec fan;
  fan.samples = 5;
  const laser_raycast::core::ScanPattern pattern(fan);
  EXPECT_EQ(pattern.size(), 5);
}

// SceneLoader::addUrdfString is defined in the loader's library (parseGeometrySource alone is an
// inline function of its header, which links without the library).
TEST(Downstream, UsesTheLoader) {
  laser_raycast::LoaderOptions options;
  EXPECT_TRUE(laser_raycast::parseGeometrySource("collision", &options.geometry));
  EXPECT_EQ(options.geometry, laser_raycast::GeometrySource::kCollision);
  const std::string urdf =
      "<robot name=\"r\"><link name=\"l\"><visual><geometry><box size=\"1 1 1\"/></geometry>"
      "</visual><collision><geometry><sphere radius=\"2\"/></geometry></collision></link></robot>";
  laser_raycast::SceneLoader loader(nullptr);
  laser_raycast::core::Scene scene;
  EXPECT_EQ(loader.addUrdfString(urdf, "", options, &scene).bodies, 1u);
  ASSERT_EQ(scene.bodies().size(), 1u);
  const auto* sphere = std::get_if<laser_raycast::core::Sphere>(&scene.bodies()[0].shape);
  ASSERT_NE(sphere, nullptr);  // the collision element, as options.geometry asks
  EXPECT_EQ(sphere->radius, 2.0);
}

// Meshes are read by laser_raycast's importer executable, which the loader finds beside its own
// library: from another package too.
TEST(Downstream, LoadsAMeshThroughTheImporter) {
  laser_raycast::SceneLoader loader(laser_raycast::rosPackagePath);
  const auto mesh = loader.loadMesh("package://laser_raycast/test/data/meshes/cuboid.obj", "",
                                    Eigen::Vector3d::Ones(), {});
  EXPECT_EQ(mesh->triangles().size(), 12u);
}

TEST(Downstream, UsesTheKinematics) {
  const Eigen::Isometry3d pose = laser_raycast::poseFromXyzRpy(1, 2, 3, 0, 0, M_PI / 2);
  EXPECT_NEAR(pose.translation().y(), 2.0, 1e-12);
  EXPECT_NEAR(pose.linear()(1, 0), 1.0, 1e-12);
}

TEST(Downstream, LinksTheNode) {
  // Reading parameters needs a ROS master; the address is enough to make the linker resolve it.
  void* volatile address = reinterpret_cast<void*>(&laser_raycast::readNodeParams);
  EXPECT_NE(address, nullptr);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
