// SceneLoader: URIs, mesh formats, Collada units and nodes, fixed-joint merging, primitives,
// geometry selection, the mesh cache, bad input, and the real TurtleBot3 data in ../shared when
// present (see shared_data.h).
//
// Expected numbers come from the test files' own contents (the cuboid below, the Collada numbers,
// STL headers), never from the loader.
#include <console_bridge/console.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <regex>
#include <set>
#include <sstream>

#include "laser_raycast/loader/package_resolver.h"
#include "laser_raycast/loader/scene_loader.h"
#include "shared_data.h"
#include "temp_files.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast;

namespace fs = std::filesystem;
using Eigen::Vector3d;
using MeshPtr = std::shared_ptr<const core::Mesh>;

const std::string kSourceDir = LASER_RAYCAST_SOURCE_DIR;
const std::string kMeshes = kSourceDir + "/test/data/meshes";

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

std::string robot(const std::string& body) {
  return "<?xml version=\"1.0\"?><robot name=\"test\">" + body + "</robot>";
}

std::string meshLink(const std::string& link, const std::string& filename,
                     const std::string& scale = "1 1 1") {
  return "<link name=\"" + link + "\"><visual><geometry><mesh filename=\"" + filename +
         "\" scale=\"" + scale + "\"/></geometry></visual></link>";
}

std::string boxLink(const std::string& link, const std::string& size = "1 1 1") {
  return "<link name=\"" + link + "\"><visual><geometry><box size=\"" + size +
         "\"/></geometry></visual></link>";
}

std::string joint(const std::string& name, const std::string& type, const std::string& parent,
                  const std::string& child, const std::string& origin = "",
                  const std::string& extra = "") {
  return "<joint name=\"" + name + "\" type=\"" + type + "\"><parent link=\"" + parent +
         "\"/><child link=\"" + child + "\"/>" + origin + extra + "</joint>";
}

MeshPtr meshOf(const core::Scene& scene, int body) {
  const auto* mesh = std::get_if<MeshPtr>(&scene.bodies().at(body).shape);
  return mesh ? *mesh : nullptr;
}

const std::string& frameOf(const core::Scene& scene, int body) {
  return scene.frames().at(scene.bodies().at(body).frame);
}

const std::string& labelOf(const core::Scene& scene, int body) {
  return scene.labels().at(scene.bodies().at(body).label);
}

void expectBounds(const core::Mesh& mesh, const Vector3d& lo, const Vector3d& hi, double tol) {
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(mesh.bounds().lo[k], lo[k], tol) << "axis " << k;
    EXPECT_NEAR(mesh.bounds().hi[k], hi[k], tol) << "axis " << k;
  }
}

// For a convex mesh: every triangle's normal points away from the centre.
void expectOutwardFaces(const core::Mesh& mesh) {
  const Vector3d center = mesh.bounds().center();
  for (std::uint32_t t = 0; t < mesh.triangles().size(); ++t) {
    Vector3d centroid = Vector3d::Zero();
    for (std::uint32_t v : mesh.triangles()[t]) centroid += mesh.vertices()[v] / 3;
    EXPECT_GT(mesh.normal(t).dot(centroid - center), 0) << "triangle " << t;
  }
}

void expectPose(const Eigen::Isometry3d& actual, const Eigen::Isometry3d& expected,
                double tol = 1e-12) {
  EXPECT_TRUE(actual.isApprox(expected, tol)) << "actual\n"
                                              << actual.matrix() << "\nexpected\n"
                                              << expected.matrix();
}

Eigen::Isometry3d pose(const Vector3d& xyz, const Vector3d& rpy = Vector3d::Zero()) {
  // URDF: fixed axes roll about x, then pitch about y, then yaw about z.
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = xyz;
  t.linear() = (Eigen::AngleAxisd(rpy.z(), Vector3d::UnitZ()) *
                Eigen::AngleAxisd(rpy.y(), Vector3d::UnitY()) *
                Eigen::AngleAxisd(rpy.x(), Vector3d::UnitX()))
                   .toRotationMatrix();
  return t;
}

class SceneLoaderTest : public ::testing::Test {
 protected:
  SceneLoaderTest()
      : loader_([this](const std::string& package) -> std::optional<std::string> {
          resolved_.push_back(package);
          if (package == "test_pkg") return kSourceDir + "/test/data";
          return std::nullopt;
        }) {}

  LoadedModel load(const std::string& xml, const LoaderOptions& options = {},
                   const std::string& base_dir = "") {
    return loader_.addUrdfString(xml, base_dir, options, &scene_);
  }

  SceneLoader loader_;
  std::vector<std::string> resolved_;
  core::Scene scene_;
};

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
  EXPECT_EQ(scene_.bodies().size(), 6u);
}

// ---------------------------------------------------------------------------------------------------
// Bad input: an error naming the URDF file, the link and the problem; or, with skip_bad_geometry,
// a warning saying the same while the rest loads.

struct BadCase {
  std::string name;
  std::string element;             // the bad link's <visual> content
  std::vector<std::string> words;  // besides the URDF path and the link name
};

std::string visualLink(const std::string& link, const std::string& geometry) {
  return "<link name=\"" + link + "\"><visual>" + geometry + "</visual></link>";
}

std::vector<BadCase> badCases() {
  const std::string empty_file = writeFile("zero_bytes.stl", "");
  const std::string mesh = "<geometry><mesh filename=\"";
  const std::string end = "\"/></geometry>";
  return {
      {"missing mesh", mesh + "no_such_mesh.stl" + end, {"no_such_mesh.stl", "not found"}},
      {"unknown scheme",
       mesh + "http://example.com/m.stl" + end,
       {"http://example.com/m.stl", "scheme"}},
      {"model scheme", mesh + "model://m/meshes/m.dae" + end, {"model://m/meshes/m.dae", "scheme"}},
      {"unknown package",
       mesh + "package://no_pkg/m.stl" + end,
       {"package://no_pkg/m.stl", "unknown package 'no_pkg'"}},
      {"empty file", mesh + empty_file + end, {"zero_bytes.stl", "empty"}},
      {"empty mesh", mesh + kMeshes + "/empty.stl" + end, {"empty.stl", "empty mesh"}},
      {"lines only", mesh + kMeshes + "/lines_only.obj" + end, {"lines_only.obj", "no triangles"}},
      {"nan vertex", mesh + kMeshes + "/nan_vertex.stl" + end, {"nan_vertex.stl", "not finite"}},
      {"not a mesh", mesh + kSourceDir + "/package.xml" + end, {"package.xml", "assimp"}},
      {"directory", mesh + kMeshes + end, {"not a regular file"}},
      {"empty filename", mesh + end, {"filename is empty"}},
      {"zero mesh scale",
       mesh + kMeshes + "/cuboid.obj\" scale=\"0 1 1" + end,
       {"cuboid.obj", "scale", "> 0"}},
      {"negative box", "<geometry><box size=\"1 -1 1\"/></geometry>", {"box size y", "> 0"}},
      {"zero length",
       "<geometry><cylinder radius=\"1\" length=\"0\"/></geometry>",
       {"cylinder length", "> 0"}},
      {"negative radius", "<geometry><sphere radius=\"-1\"/></geometry>", {"sphere radius", "> 0"}},
      // urdfdom drops these elements with an error log and a successful parse.
      {"nan box", "<geometry><box size=\"nan 1 1\"/></geometry>", {"dropped", "[nan]"}},
      {"inf scale",
       mesh + kMeshes + "/cuboid.obj\" scale=\"inf 1 1" + end,
       {"dropped", "scale", "[inf]"}},
      {"no geometry", "<geometry></geometry>", {"dropped", "no child element"}},
  };
}

TEST_F(SceneLoaderTest, BadGeometryIsAnErrorNamingFileLinkAndProblem) {
  for (const BadCase& c : badCases()) {
    SCOPED_TRACE(c.name);
    const std::string urdf_path =
        writeFile("bad.urdf", robot(boxLink("good") + visualLink("bad_link", c.element) +
                                    joint("j", "fixed", "good", "bad_link")));
    core::Scene scene;
    try {
      loader_.addUrdfFile(urdf_path, {}, &scene);
      ADD_FAILURE() << "no exception";
    } catch (const SceneLoadError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(urdf_path), std::string::npos) << msg;
      EXPECT_NE(msg.find("'bad_link'"), std::string::npos) << msg;
      for (const std::string& word : c.words) EXPECT_NE(msg.find(word), std::string::npos) << msg;
    }
    EXPECT_TRUE(scene.bodies().empty());  // a failed load leaves the scene as it was
  }
}

TEST_F(SceneLoaderTest, SkipBadGeometryTurnsEachIntoAWarning) {
  LoaderOptions options;
  options.skip_bad_geometry = true;
  for (const BadCase& c : badCases()) {
    SCOPED_TRACE(c.name);
    const std::string urdf_path =
        writeFile("bad.urdf", robot(boxLink("good") + visualLink("bad_link", c.element) +
                                    joint("j", "fixed", "good", "bad_link")));
    core::Scene scene;
    const LoadedModel model = loader_.addUrdfFile(urdf_path, options, &scene);
    EXPECT_EQ(model.bodies, 1u);
    ASSERT_EQ(scene.bodies().size(), 1u);
    EXPECT_EQ(scene.labels()[scene.bodies()[0].label], "good");
    ASSERT_EQ(model.warnings.size(), 1u);
    const std::string& msg = model.warnings[0];
    EXPECT_NE(msg.find(urdf_path), std::string::npos) << msg;
    EXPECT_NE(msg.find("'bad_link'"), std::string::npos) << msg;
    for (const std::string& word : c.words) EXPECT_NE(msg.find(word), std::string::npos) << msg;
  }
}

// urdfdom 3 stops reading a link at an element it cannot parse, losing the link's later elements
// and (after a bad visual) all its collisions, and still reports success.
TEST_F(SceneLoaderTest, ElementsUrdfdomDropsAreReportedInBothModes) {
  const std::string xml = robot(
      "<link name=\"l\"><visual><geometry><sphere radius=\"1\"/></geometry></visual>"
      "<visual><geometry><box size=\"nan 1 1\"/></geometry></visual>"
      "<visual><geometry><sphere radius=\"2\"/></geometry></visual>"
      "<collision><geometry><sphere radius=\"3\"/></geometry></collision></link>");
  for (GeometrySource source : {GeometrySource::kVisual, GeometrySource::kCollision}) {
    SCOPED_TRACE(toString(source));
    LoaderOptions options;
    options.geometry = source;
    core::Scene scene;
    try {
      loader_.addUrdfString(xml, "", options, &scene);
      ADD_FAILURE() << "no exception";
    } catch (const SceneLoadError& e) {
      EXPECT_NE(std::string(e.what()).find("'l'"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("[nan]"), std::string::npos) << e.what();
    }
    options.skip_bad_geometry = true;
    const LoadedModel model = loader_.addUrdfString(xml, "", options, &scene);
    EXPECT_EQ(model.warnings.size(), 1u);
    // What urdfdom kept: the first visual; no collision.
    EXPECT_EQ(model.bodies, source == GeometrySource::kVisual ? 1u : 0u);
  }
}

TEST_F(SceneLoaderTest, DroppedElementsAreFoundWhenConsoleBridgeIsSilenced) {
  const console_bridge::LogLevel level = console_bridge::getLogLevel();
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_NONE);
  EXPECT_THROW(load(robot(visualLink("l", "<geometry><box size=\"nan 1 1\"/></geometry>"))),
               SceneLoadError);
  EXPECT_EQ(console_bridge::getLogLevel(), console_bridge::CONSOLE_BRIDGE_LOG_NONE);
  console_bridge::setLogLevel(level);
}

TEST_F(SceneLoaderTest, UnreadableMeshIsAnError) {
  if (::geteuid() == 0) GTEST_SKIP() << "root reads any file";
  const std::string path = writeFile("unreadable.stl", "solid x\nendsolid x\n");
  ::chmod(path.c_str(), 0);
  try {
    load(robot(meshLink("body", path)));
    ADD_FAILURE() << "no exception";
  } catch (const SceneLoadError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot be opened"), std::string::npos) << e.what();
  }
}

// Regression (found by test/fuzz/fuzz_urdf_loader): urdfdom accepts a joint whose parent is its
// child, and the loader returned a link without a frame.
TEST_F(SceneLoaderTest, ALinkThatIsItsOwnParentIsAnError) {
  const std::string xml =
      "<robot name=\"r\"><link name=\"base\"/><link name=\"ball\"><visual><geometry><sphere "
      "radius=\"0.1\"/></geometry></visual></link><joint name=\"loop\" type=\"fixed\"><parent "
      "link=\"ball\"/><child link=\"ball\"/></joint></robot>";
  SceneLoader loader(nullptr);
  core::Scene scene;
  try {
    loader.addUrdfString(xml, "", {}, &scene, "the test URDF");
    ADD_FAILURE() << "loaded";
  } catch (const SceneLoadError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("the test URDF: link 'ball' is not connected to the root link 'base'"),
              std::string::npos)
        << what;
  }
  EXPECT_TRUE(scene.bodies().empty());
}

TEST_F(SceneLoaderTest, MalformedUrdfIsAlwaysAnError) {
  LoaderOptions options;
  options.skip_bad_geometry = true;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "malformed"},
      {"not xml at all", "malformed"},
      {"<robot name=\"r\"/>", "malformed"},
      {robot(boxLink("a") + boxLink("b")), "Two root links"},
      {robot(boxLink("a") + boxLink("a")), "malformed"},
      {robot(boxLink("a") + boxLink("b") + joint("j", "fixed", "a", "nowhere")), "malformed"},
      {robot(boxLink("a") + boxLink("b") +
             joint("j", "continuous", "a", "b", "", "<axis xyz=\"0 0 0\"/>")),
       "axis"},
  };
  for (const auto& [xml, word] : cases) {
    SCOPED_TRACE(xml);
    const std::string path = writeFile("malformed.urdf", xml);
    try {
      loader_.addUrdfFile(path, options, &scene_);
      ADD_FAILURE() << "no exception";
    } catch (const SceneLoadError& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(word), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(loader_.addUrdfFile(kSourceDir + "/no_such.urdf", options, &scene_), SceneLoadError);
  EXPECT_THROW(loader_.addUrdfFile(kMeshes, options, &scene_), SceneLoadError);
  EXPECT_TRUE(scene_.bodies().empty());
}

TEST_F(SceneLoaderTest, LoadMeshRejectsBadScales) {
  const std::string file = kMeshes + "/cuboid.obj";
  for (const Vector3d& scale :
       {Vector3d(1, 0, 1), Vector3d(1, 1, -1), Vector3d(NAN, 1, 1), Vector3d(1, INFINITY, 1)}) {
    EXPECT_THROW(loader_.loadMesh(file, "", scale, {}), SceneLoadError) << scale.transpose();
  }
  EXPECT_EQ(loader_.meshesLoaded(), 0u);
}

TEST_F(SceneLoaderTest, WithoutAResolverPackageUrisAreAnError) {
  SceneLoader loader(nullptr);
  EXPECT_THROW(loader.loadMesh("package://test_pkg/meshes/cuboid.obj", "", Vector3d::Ones(), {}),
               SceneLoadError);
}

// ---------------------------------------------------------------------------------------------------
// The real TurtleBot3 data (../shared), counted independently of the loader.

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
