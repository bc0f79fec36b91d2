// SceneLoader: URIs, mesh formats, Collada, links and joints, geometry selection, the mesh cache.
// Expected numbers come from the test files' own contents, never from the loader.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "laser_raycast/loader/package_resolver.h"
#include "laser_raycast/loader/scene_loader.h"
#include "scene_loader_fixture.h"
#include "temp_files.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast;

namespace fs = std::filesystem;
using Eigen::Vector3d;

// Every test mesh holds this cuboid in its file's units: [0,1] x [0,2] x [0,3], 12 triangles.
const Vector3d kCuboidHi(1, 2, 3);
const std::vector<Vector3d> kCuboidVertices = {{0, 0, 0}, {1, 0, 0}, {1, 2, 0}, {0, 2, 0},
                                               {0, 0, 3}, {1, 0, 3}, {1, 2, 3}, {0, 2, 3}};
const std::vector<std::array<int, 4>> kCuboidQuads = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                                      {3, 7, 6, 2}, {0, 4, 7, 3}, {1, 2, 6, 5}};

// The cuboid as a binary STL (80-byte header, count, 50 bytes per facet), little-endian as x86.
std::string writeBinaryStl(const std::string& name) {
  std::string bytes(80, ' ');
  const auto put = [&bytes](const void* p, std::size_t n) {
    bytes.append(static_cast<const char*>(p), n);
  };
  const std::uint32_t count = 12;
  put(&count, 4);
  for (const auto& q : kCuboidQuads) {
    for (const std::array<int, 3>& t :
         {std::array<int, 3>{q[0], q[1], q[2]}, std::array<int, 3>{q[0], q[2], q[3]}}) {
      const float normal[3] = {0, 0, 0};
      put(normal, sizeof normal);
      for (int i : t) {
        const float v[3] = {float(kCuboidVertices[i].x()), float(kCuboidVertices[i].y()),
                            float(kCuboidVertices[i].z())};
        put(v, sizeof v);
      }
      const std::uint16_t attributes = 0;
      put(&attributes, 2);
    }
  }
  return writeFile(name, bytes);
}

TEST(GeometrySource, NamesRoundTrip) {
  for (GeometrySource s : {GeometrySource::kVisual, GeometrySource::kCollision}) {
    GeometrySource parsed =
        s == GeometrySource::kVisual ? GeometrySource::kCollision : GeometrySource::kVisual;
    ASSERT_TRUE(parseGeometrySource(toString(s), &parsed));
    EXPECT_EQ(parsed, s);
  }
  EXPECT_STREQ(toString(GeometrySource::kVisual), "visual");
  EXPECT_STREQ(toString(GeometrySource::kCollision), "collision");
  GeometrySource s = GeometrySource::kCollision;
  EXPECT_FALSE(parseGeometrySource("Visual", &s));
  EXPECT_FALSE(parseGeometrySource("", &s));
  EXPECT_EQ(s, GeometrySource::kCollision);
}

// ---------------------------------------------------------------------------------------------------
// Mesh formats and URIs

TEST_F(SceneLoaderTest, EveryFormatGivesTheCuboid) {
  const std::vector<std::string> files = {kMeshes + "/cuboid_ascii.stl", writeBinaryStl("b.stl"),
                                          kMeshes + "/cuboid.obj", kMeshes + "/cuboid.ply",
                                          kMeshes + "/cuboid.dae"};
  for (const std::string& file : files) {
    SCOPED_TRACE(file);
    const MeshPtr mesh = loader_.loadMesh(file, "", Vector3d::Ones(), {});
    ASSERT_TRUE(mesh);
    EXPECT_EQ(mesh->triangles().size(), 12u);
    EXPECT_EQ(mesh->degenerateTriangleCount(), 0u);
    // Small integers: exact in float and double.
    expectBounds(*mesh, Vector3d::Zero(), kCuboidHi, 0.0);
    expectOutwardFaces(*mesh);
  }
  EXPECT_EQ(loader_.meshesLoaded(), files.size());
}

// A mesh is shared while something holds it; once every holder has let it go (a deleted model of
// a node that edits its scene) it is freed, and the next load reads the file anew.
TEST_F(SceneLoaderTest, AMeshNoLongerHeldIsFreedAndReadAgain) {
  const std::string abs = kMeshes + "/cuboid.obj";
  std::shared_ptr<const laser_raycast::core::Mesh> held =
      loader_.loadMesh(abs, "", Vector3d::Ones(), {});
  std::weak_ptr<const laser_raycast::core::Mesh> watch = held;
  EXPECT_EQ(loader_.loadMesh(abs, "", Vector3d::Ones(), {}), held);
  EXPECT_EQ(loader_.meshesLoaded(), 1u);
  held.reset();
  EXPECT_TRUE(watch.expired());  // the loader does not keep it alive
  const auto again = loader_.loadMesh(abs, "", Vector3d::Ones(), {});
  ASSERT_NE(again, nullptr);
  EXPECT_EQ(loader_.meshesLoaded(), 2u);
  expectBounds(*again, Vector3d::Zero(), kCuboidHi, 0.0);
}

TEST_F(SceneLoaderTest, EveryUriFormReachesTheSameFile) {
  const std::string abs = kMeshes + "/cuboid.obj";
  const LoadedModel model =
      load(robot(meshLink("pkg", "package://test_pkg/meshes/cuboid.obj") +
                 meshLink("file", "file://" + abs) + meshLink("abs", abs) +
                 meshLink("rel", "meshes/cuboid.obj") + joint("j1", "fixed", "pkg", "file") +
                 joint("j2", "fixed", "pkg", "abs") + joint("j3", "fixed", "pkg", "rel")),
           {}, kSourceDir + "/test/data");
  EXPECT_EQ(resolved_, std::vector<std::string>{"test_pkg"});
  ASSERT_EQ(model.bodies, 4u);
  // One file, however it is named: read once, shared.
  EXPECT_EQ(loader_.meshesLoaded(), 1u);
  for (int b = 1; b < 4; ++b) EXPECT_EQ(meshOf(scene_, b), meshOf(scene_, 0));
  expectBounds(*meshOf(scene_, 0), Vector3d::Zero(), kCuboidHi, 0.0);
}

TEST_F(SceneLoaderTest, RelativePathIsRelativeToTheUrdfFile) {
  const LoadedModel model =
      loader_.addUrdfFile(kSourceDir + "/test/data/urdf/relative_mesh.urdf", {}, &scene_);
  EXPECT_EQ(model.name, "relative_mesh");
  ASSERT_EQ(model.bodies, 1u);
  EXPECT_EQ(meshOf(scene_, 0)->triangles().size(), 12u);
}

TEST_F(SceneLoaderTest, UrdfFileAsPackageUriGoesThroughTheResolver) {
  // Its mesh path is relative: relative to the file the URI resolved to.
  const LoadedModel model =
      loader_.addUrdfFile("package://test_pkg/urdf/relative_mesh.urdf", {}, &scene_);
  EXPECT_EQ(resolved_, std::vector<std::string>{"test_pkg"});
  EXPECT_EQ(model.name, "relative_mesh");
  ASSERT_EQ(model.bodies, 1u);
  expectBounds(*meshOf(scene_, 0), Vector3d::Zero(), kCuboidHi, 0.0);
}

TEST_F(SceneLoaderTest, UrdfFileAsPackageUriIsNamedWithItsFile) {
  const std::string uri = "package://test_pkg/malformed.urdf";
  try {
    loader_.addUrdfFile(uri, {}, &scene_);
    FAIL() << "no exception";
  } catch (const SceneLoadError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind(uri + " (" + kSourceDir + "/test/data/malformed.urdf): malformed URDF", 0),
              0u)
        << msg;
  }
  // An unknown package, and a URI without a path, are errors that name the URI.
  for (const auto& [bad, problem] :
       {std::pair<std::string, std::string>{"package://no_pkg/robot.urdf",
                                            "unknown package 'no_pkg'"},
        {"package://test_pkg", "a package:// URI needs a package name and a path"}}) {
    try {
      loader_.addUrdfFile(bad, {}, &scene_);
      ADD_FAILURE() << bad << ": no exception";
    } catch (const SceneLoadError& e) {
      EXPECT_EQ(std::string(e.what()), bad + ": " + problem);
    }
  }
  EXPECT_TRUE(scene_.bodies().empty());
}

TEST(RosPackagePath, FindsThisPackageOnRosPackagePath) {
  // catkin runs the tests with the workspace's ROS_PACKAGE_PATH, which holds this package.
  const std::optional<std::string> dir = rosPackagePath("laser_raycast");
  ASSERT_TRUE(dir) << "laser_raycast is not on ROS_PACKAGE_PATH="
                   << (std::getenv("ROS_PACKAGE_PATH") ? std::getenv("ROS_PACKAGE_PATH") : "");
  EXPECT_TRUE(fs::equivalent(*dir, kSourceDir)) << *dir;
  EXPECT_FALSE(rosPackagePath("laser_raycast_no_such_package"));

  SceneLoader loader(rosPackagePath);
  core::Scene scene;
  const LoadedModel model =
      loader.addUrdfFile("package://laser_raycast/test/data/urdf/relative_mesh.urdf", {}, &scene);
  EXPECT_EQ(model.bodies, 1u);
}

TEST_F(SceneLoaderTest, RelativePathInAStringWithoutBaseDirIsAnError) {
  try {
    load(robot(meshLink("body", "meshes/cuboid.obj")));
    FAIL() << "no exception";
  } catch (const SceneLoadError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("meshes/cuboid.obj"), std::string::npos) << msg;
    EXPECT_NE(msg.find("'body'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("relative"), std::string::npos) << msg;
  }
  EXPECT_TRUE(scene_.bodies().empty());
}

TEST_F(SceneLoaderTest, MeshScaleUniformAndNonUniform) {
  const std::string file = kMeshes + "/cuboid_ascii.stl";
  load(robot(meshLink("a", file, "2 2 2") + meshLink("b", file, "1 0.5 2") +
             joint("j", "fixed", "a", "b")));
  expectBounds(*meshOf(scene_, 0), Vector3d::Zero(), Vector3d(2, 4, 6), 0.0);
  expectBounds(*meshOf(scene_, 1), Vector3d::Zero(), Vector3d(1, 1, 6), 0.0);
  expectOutwardFaces(*meshOf(scene_, 1));
}

// ---------------------------------------------------------------------------------------------------
// Collada, the ROS way

TEST_F(SceneLoaderTest, ColladaUnitIsAppliedAndYUpIgnored) {
  const MeshPtr mesh = loader_.loadMesh(kMeshes + "/cuboid_inch_yup.dae", "", Vector3d::Ones(), {});
  // Inches to metres; the data's z stays z although the file says Y_UP.
  expectBounds(*mesh, Vector3d::Zero(), kCuboidHi * 0.0254, 1e-15);
  expectOutwardFaces(*mesh);
}

TEST_F(SceneLoaderTest, ColladaZUpRootRotationIgnoredAndNoUnitMeansMetres) {
  // assimp rotates Z_UP files to Y-up in the root node; RViz ignores that, and so do we.
  const MeshPtr mesh = loader_.loadMesh(kMeshes + "/cuboid.dae", "", Vector3d::Ones(), {});
  expectBounds(*mesh, Vector3d::Zero(), kCuboidHi, 0.0);
}

TEST_F(SceneLoaderTest, ColladaChildNodeTransformsAreApplied) {
  // From the file's comment, worked by hand: [4,5] x [0,0.5] x [2.5,4] m (float rotation of 90
  // degrees: cos is ~4e-8, not 0).
  const MeshPtr mesh = loader_.loadMesh(kMeshes + "/cuboid_nodes.dae", "", Vector3d(1, 1, 2), {});
  expectBounds(*mesh, Vector3d(4, 0, 5), Vector3d(5, 0.5, 8), 1e-6);
  expectOutwardFaces(*mesh);
}

TEST_F(SceneLoaderTest, MirroringNodeKeepsFacesOutward) {
  const MeshPtr mesh = loader_.loadMesh(kMeshes + "/cuboid_mirrored.dae", "", Vector3d::Ones(), {});
  expectBounds(*mesh, Vector3d(-1, 0, 0), Vector3d(0, 2, 3), 0.0);
  expectOutwardFaces(*mesh);
}

// ---------------------------------------------------------------------------------------------------
// Links, joints, frames

TEST_F(SceneLoaderTest, FixedLinksAreMergedIntoTheTopmostFrame) {
  const std::string fixed_origin = "<origin xyz=\"0 0 1\" rpy=\"0 0 1.5707963267948966\"/>";
  const std::string sensor_origin = "<origin xyz=\"0.5 0 0\" rpy=\"0.1 0 0\"/>";
  const LoadedModel model = load(robot(
      boxLink("base") +
      "<link name=\"plate\"><visual><origin xyz=\"0 0.2 0\"/><geometry><box size=\"1 2 3\"/>"
      "</geometry></visual></link>" +
      boxLink("arm") + "<link name=\"sensor\"/>" +
      joint("base_to_plate", "fixed", "base", "plate", fixed_origin) +
      joint("plate_to_sensor", "fixed", "plate", "sensor", sensor_origin) +
      joint("plate_to_arm", "revolute", "plate", "arm", "<origin xyz=\"1 0 0\"/>",
            "<axis xyz=\"0 0 2\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/>")));
  EXPECT_EQ(model.root_link, "base");
  EXPECT_EQ(model.links, 4u);
  EXPECT_EQ(model.bodies, 3u);
  EXPECT_EQ(scene_.frames(), (std::vector<std::string>{"base", "arm"}));
  std::set<std::string> labels(scene_.labels().begin(), scene_.labels().end());
  EXPECT_EQ(labels, (std::set<std::string>{"base", "plate", "arm"}));

  const Eigen::Isometry3d base_from_plate = pose({0, 0, 1}, {0, 0, M_PI / 2});
  ASSERT_EQ(model.link_frames.size(), 4u);
  EXPECT_EQ(model.link_frames.at("base").first, "base");
  expectPose(model.link_frames.at("base").second, Eigen::Isometry3d::Identity());
  EXPECT_EQ(model.link_frames.at("plate").first, "base");
  expectPose(model.link_frames.at("plate").second, base_from_plate);
  EXPECT_EQ(model.link_frames.at("sensor").first, "base");
  expectPose(model.link_frames.at("sensor").second,
             base_from_plate * pose({0.5, 0, 0}, {0.1, 0, 0}));
  EXPECT_EQ(model.link_frames.at("arm").first, "arm");
  expectPose(model.link_frames.at("arm").second, Eigen::Isometry3d::Identity());

  for (int b = 0; b < 3; ++b) {
    SCOPED_TRACE(labelOf(scene_, b));
    if (labelOf(scene_, b) == "plate") {
      EXPECT_EQ(frameOf(scene_, b), "base");
      expectPose(scene_.bodies()[b].frame_from_body, base_from_plate * pose({0, 0.2, 0}));
    } else {
      EXPECT_EQ(frameOf(scene_, b), labelOf(scene_, b));
      expectPose(scene_.bodies()[b].frame_from_body, Eigen::Isometry3d::Identity());
    }
  }

  ASSERT_EQ(model.joints.size(), 3u);
  for (const ModelJoint& j : model.joints) {
    SCOPED_TRACE(j.name);
    if (j.name == "plate_to_arm") {
      EXPECT_EQ(j.type, ModelJoint::Type::kRevolute);
      EXPECT_EQ(j.parent_link, "plate");
      EXPECT_EQ(j.child_link, "arm");
      EXPECT_EQ(j.axis, Vector3d::UnitZ());  // normalised
      expectPose(j.parent_from_joint, pose({1, 0, 0}));
    } else {
      EXPECT_EQ(j.type, ModelJoint::Type::kFixed);
    }
    if (j.name == "base_to_plate") expectPose(j.parent_from_joint, base_from_plate);
  }
}

TEST_F(SceneLoaderTest, PrimitivesKeepTheirExactSizesAndOrigins) {
  load(robot(
      "<link name=\"l\">"
      "<visual><origin xyz=\"1 2 3\" rpy=\"0.1 0.2 0.3\"/><geometry><box size=\"0.1 0.2 0.3\"/>"
      "</geometry></visual>"
      "<visual><origin xyz=\"-1 0 0.5\"/><geometry><cylinder radius=\"0.15\" length=\"0.5\"/>"
      "</geometry></visual>"
      "<visual><geometry><sphere radius=\"0.25\"/></geometry></visual></link>"));
  ASSERT_EQ(scene_.bodies().size(), 3u);
  const auto& box = std::get<core::Box>(scene_.bodies()[0].shape);
  EXPECT_EQ(box.size, Vector3d(0.1, 0.2, 0.3));
  expectPose(scene_.bodies()[0].frame_from_body, pose({1, 2, 3}, {0.1, 0.2, 0.3}));
  const auto& cylinder = std::get<core::Cylinder>(scene_.bodies()[1].shape);
  EXPECT_EQ(cylinder.radius, 0.15);
  EXPECT_EQ(cylinder.length, 0.5);
  expectPose(scene_.bodies()[1].frame_from_body, pose({-1, 0, 0.5}));
  EXPECT_EQ(std::get<core::Sphere>(scene_.bodies()[2].shape).radius, 0.25);
  for (int b = 0; b < 3; ++b) EXPECT_EQ(labelOf(scene_, b), "l");
}

const std::string kSelectionRobot = robot(
    "<link name=\"both\"><visual><geometry><box size=\"1 1 1\"/></geometry></visual>"
    "<collision><geometry><sphere radius=\"2\"/></geometry></collision></link>"
    "<link name=\"collision_only\"><collision><geometry><cylinder radius=\"1\" length=\"3\"/>"
    "</geometry></collision><collision><geometry><sphere radius=\"4\"/></geometry></collision>"
    "</link>"
    "<link name=\"visual_only\"><visual><geometry><sphere radius=\"5\"/></geometry></visual>"
    "</link>" +
    joint("j1", "fixed", "both", "collision_only") + joint("j2", "fixed", "both", "visual_only"));

// label -> shape type index, for each body.
std::multimap<std::string, std::size_t> shapesByLabel(const core::Scene& scene) {
  std::multimap<std::string, std::size_t> out;
  for (int b = 0; b < static_cast<int>(scene.bodies().size()); ++b) {
    out.emplace(labelOf(scene, b), scene.bodies()[b].shape.index());
  }
  return out;
}

TEST_F(SceneLoaderTest, VisualFallsBackToCollisionPerLink) {
  const LoadedModel model = load(kSelectionRobot);
  EXPECT_EQ(model.bodies, 4u);
  const std::multimap<std::string, std::size_t> expected = {
      {"both", 0}, {"collision_only", 1}, {"collision_only", 2}, {"visual_only", 2}};
  EXPECT_EQ(shapesByLabel(scene_), expected);
}

TEST_F(SceneLoaderTest, CollisionLoadsOnlyCollisionElements) {
  LoaderOptions options;
  options.geometry = GeometrySource::kCollision;
  const LoadedModel model = load(kSelectionRobot, options);
  EXPECT_EQ(model.bodies, 3u);
  const std::multimap<std::string, std::size_t> expected = {
      {"both", 2}, {"collision_only", 1}, {"collision_only", 2}};
  EXPECT_EQ(shapesByLabel(scene_), expected);
}

TEST_F(SceneLoaderTest, IgnoredLinksHaveNoBodiesButKeepTheirFrames) {
  LoaderOptions options;
  options.ignore_links = {"collision_only", "not_a_link"};
  const LoadedModel model = load(kSelectionRobot, options);
  EXPECT_EQ(model.bodies, 2u);
  EXPECT_EQ(shapesByLabel(scene_).count("collision_only"), 0u);
  EXPECT_EQ(model.link_frames.count("collision_only"), 1u);
}

TEST_F(SceneLoaderTest, TfPrefixNamesFramesLabelsLinksAndJoints) {
  LoaderOptions options;
  options.tf_prefix = "robot2/";
  const LoadedModel model =
      load(robot(boxLink("base") + boxLink("plate") + boxLink("arm") +
                 joint("fixed", "fixed", "base", "plate") +
                 joint("hinge", "continuous", "plate", "arm", "", "<axis xyz=\"0 1 0\"/>")),
           options);
  EXPECT_EQ(model.root_link, "robot2/base");
  EXPECT_EQ(scene_.frames(), (std::vector<std::string>{"robot2/base", "robot2/arm"}));
  std::set<std::string> labels(scene_.labels().begin(), scene_.labels().end());
  EXPECT_EQ(labels, (std::set<std::string>{"robot2/base", "robot2/plate", "robot2/arm"}));
  ASSERT_EQ(model.link_frames.count("robot2/plate"), 1u);
  EXPECT_EQ(model.link_frames.at("robot2/plate").first, "robot2/base");
  EXPECT_EQ(model.link_frames.at("robot2/arm").first, "robot2/arm");
  for (const ModelJoint& j : model.joints) {
    EXPECT_EQ(j.parent_link.rfind("robot2/", 0), 0u) << j.parent_link;
    EXPECT_EQ(j.child_link.rfind("robot2/", 0), 0u) << j.child_link;
  }
}

TEST_F(SceneLoaderTest, MeshesAreSharedPerFileAndScale) {
  const std::string stl = kMeshes + "/cuboid_ascii.stl";
  const std::string urdf = robot(meshLink("a", stl) + meshLink("b", stl) +
                                 meshLink("c", stl, "1 1 2") + joint("j1", "fixed", "a", "b") +
                                 joint("j2", "revolute", "a", "c", "",
                                       "<limit lower=\"0\" upper=\"1\" effort=\"1\" "
                                       "velocity=\"1\"/>"));
  const LoadedModel first = load(urdf);
  EXPECT_EQ(first.bodies, 3u);
  EXPECT_EQ(first.triangles, 36u);  // per instance
  // Two meshes built (one per scale), each holding at least its indices and the BVH's corner
  // copies (12 + 72 bytes a triangle). glibc's allocator counts them; AddressSanitizer's replaces
  // it, and then only the meshes' input is counted.
  EXPECT_EQ(first.mesh_triangles_built, 24u);
#ifndef __SANITIZE_ADDRESS__
  EXPECT_GE(first.mesh_bytes_built, 24u * (12 + 72));
#endif
  EXPECT_EQ(meshOf(scene_, 0), meshOf(scene_, 1));
  EXPECT_NE(meshOf(scene_, 0), meshOf(scene_, 2));
  EXPECT_EQ(loader_.meshesLoaded(), 2u);

  // A second model shares the cache: nothing read, no BVH built.
  LoaderOptions options;
  options.tf_prefix = "second/";
  const LoadedModel second = load(urdf, options);
  EXPECT_EQ(loader_.meshesLoaded(), 2u);
  EXPECT_EQ(meshOf(scene_, 3), meshOf(scene_, 0));
  EXPECT_EQ(meshOf(scene_, 5), meshOf(scene_, 2));
  EXPECT_EQ(second.bvh_build_seconds, 0.0);
  EXPECT_EQ(second.mesh_triangles_built, 0u);
  EXPECT_EQ(second.mesh_bytes_built, 0u);
  EXPECT_EQ(scene_.bodies().size(), 6u);
}

}  // namespace
}  // namespace laser_raycast_test
