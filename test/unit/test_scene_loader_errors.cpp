// SceneLoader on bad input: an error, or with skip_bad_geometry a warning, naming file and link.
#include <console_bridge/console.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "laser_raycast/loader/scene_loader.h"
#include "scene_loader_fixture.h"
#include "temp_files.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast;

using Eigen::Vector3d;

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

// Regression (found by test/fuzz/fuzz_urdf_loader): urdfdom passes text it cannot read to
// console_bridge as the format of its message, and "%n" in an origin's xyz crashed the loader in
// vsnprintf. Such text is an error (or with skip_bad_geometry a warning) naming the link, as
// urdfdom says it with '_' for '%', under the link's own name; '%' elsewhere (a link's name) loads.
TEST_F(SceneLoaderTest, PercentSignsInTheUrdfAreNeverAFormat) {
  const std::string bad_origin =
      "<origin xyz=\"0 %n%n%n%n%s%s%p 0\"/><geometry><box size=\"1 1 1\"/></geometry>";
  for (const std::string link : {"bad", "bad%n%s"}) {
    SCOPED_TRACE(link);
    const std::string xml =
        robot(boxLink("good") + visualLink(link, bad_origin) + joint("j", "fixed", "good", link));
    core::Scene scene;
    try {
      loader_.addUrdfString(xml, "", {}, &scene, "the test URDF");
      ADD_FAILURE() << "no exception";
    } catch (const SceneLoadError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("the test URDF"), std::string::npos) << what;
      EXPECT_NE(what.find("'" + link + "'"), std::string::npos) << what;
      EXPECT_NE(what.find("_n_n_n_n_s_s_p"), std::string::npos) << what;
    }
    LoaderOptions options;
    options.skip_bad_geometry = true;
    const LoadedModel model = loader_.addUrdfString(xml, "", options, &scene, "the test URDF");
    EXPECT_EQ(model.bodies, 1u);
    ASSERT_EQ(model.warnings.size(), 1u);
    EXPECT_NE(model.warnings[0].find("'" + link + "'"), std::string::npos) << model.warnings[0];
  }
  core::Scene scene;
  const LoadedModel model = loader_.addUrdfString(
      robot(boxLink("wheel%n%s") + boxLink("b") + joint("j", "fixed", "wheel%n%s", "b")), "", {},
      &scene);
  EXPECT_EQ(model.bodies, 2u);
  EXPECT_TRUE(model.warnings.empty());
  ASSERT_EQ(scene.bodies().size(), 2u);
  EXPECT_EQ(scene.labels()[scene.bodies()[0].label], "wheel%n%s");
  // Malformed with a '%': an error naming the source.
  EXPECT_THROW(loader_.addUrdfString("<robot name=\"%n%s\"><link name=\"%n\"", "", {}, &scene),
               SceneLoadError);
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

}  // namespace
}  // namespace laser_raycast_test
