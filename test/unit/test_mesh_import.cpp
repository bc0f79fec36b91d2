// The bounded mesh import: the loader reads meshes in a child process (laser_raycast_mesh_import)
// under MeshImportBounds. The corrupt files fuzzing found (test/fuzz/corpus/mesh_loader/
// regression_*; before, some made assimp allocate until the machine's memory ran out, some
// crashed the caller, one hung it) are refused with a SceneLoadError that names the file and the
// bound or the crash; a refused file does not stop the next one from loading; and every way the
// importer process can fail (stand-ins given through $LASER_RAYCAST_MESH_IMPORT) is an error, not a
// crash or a hang of the caller.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "expect_invalid.h"
#include "laser_raycast/loader/scene_loader.h"
#include "temp_files.h"

namespace laser_raycast_test {
namespace {

using namespace laser_raycast;
namespace fs = std::filesystem;
using Eigen::Vector3d;

const std::string kSourceDir = LASER_RAYCAST_SOURCE_DIR;
const std::string kCorpus = kSourceDir + "/test/fuzz/corpus/mesh_loader";
const std::string kCuboid = kSourceDir + "/test/data/meshes/cuboid.obj";

// What each regression input does to assimp, found by changing one byte of a TurtleBot3 Collada
// file or of the test cuboid: in <p> (the triangles' indices) a character that is not a digit makes
// assimp's Collada parser allocate without end; in a <float_array>'s count attribute, it crashes;
// the PLY header's line break replaced by a space makes its parser loop without allocating. The
// STL reader refuses a binary STL cut short or counting more triangles than it holds, and an ASCII
// one cut short (assimp read 7 of its 12 triangles without a word), saying what is wrong.
enum class Harm { kAllocates, kCrashes, kLoops, kRefused };
const std::map<std::string, Harm> kRegressions = {
    {"regression_cuboid_ascii_truncated.stl", Harm::kRefused},
    {"regression_cuboid_binary_count_high.stl", Harm::kRefused},
    {"regression_cuboid_binary_truncated.stl", Harm::kRefused},
    {"regression_cuboid_ply_header_newline.ply", Harm::kLoops},
    {"regression_hexagon_float_array_count_letter.dae", Harm::kCrashes},
    {"regression_hexagon_p_quote.dae", Harm::kAllocates},
    {"regression_waffle_base_float_array_count_letter.dae", Harm::kCrashes},
    {"regression_waffle_base_p_letter.dae", Harm::kAllocates},
    {"regression_wall_float_array_count_minus.dae", Harm::kCrashes},
    {"regression_wall_float_array_count_renamed.dae", Harm::kCrashes},
    {"regression_wall_p_byte_ff.dae", Harm::kAllocates},
    {"regression_wall_p_letter.dae", Harm::kAllocates},
    {"regression_wall_p_quote.dae", Harm::kAllocates},
};

std::string contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos ? "" : "'" + part + "' missing in: " + text;
}

std::string meshUrdf(const std::string& file) {
  return "<robot name=\"r\"><link name=\"base\"><visual><geometry><box size=\"1 1 1\"/></geometry>"
         "</visual></link><link name=\"shell\"><visual><geometry><mesh filename=\"" +
         file +
         "\"/></geometry></visual></link><joint name=\"j\" type=\"fixed\"><parent "
         "link=\"base\"/><child link=\"shell\"/></joint></robot>";
}

// Each regression input is refused, naming the file and the bound it exceeded or the crash. With
// bounds smaller than the defaults, to keep the test short (assimp reaches 256 MB in ~0.2 s).
TEST(MeshImport, CorruptFilesFoundByFuzzingAreRefused) {
  std::set<std::string> files;
  for (const auto& entry : fs::directory_iterator(kCorpus)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("regression_", 0) == 0) files.insert(name);
  }
  for (const std::string& name : files) EXPECT_EQ(kRegressions.count(name), 1u) << name;
  MeshImportBounds bounds;
  bounds.max_memory_mb = 256;
  bounds.max_seconds = 1;
  SceneLoader loader(nullptr);
  for (const auto& [name, harm] : kRegressions) {
    SCOPED_TRACE(name);
    EXPECT_EQ(files.count(name), 1u);
    const std::string file = kCorpus + "/" + name;
    try {
      loader.loadMesh(file, "", Vector3d::Ones(), {}, bounds);
      ADD_FAILURE() << "loaded";
    } catch (const MeshImportBoundError& e) {
      EXPECT_NE(harm, Harm::kCrashes) << e.what();
      EXPECT_EQ(contains(e.what(), file), "");
      if (harm == Harm::kAllocates) {
        EXPECT_EQ(e.bound(), MeshImportBoundError::Bound::kMemory);
        EXPECT_EQ(e.limit(), 256);
        EXPECT_EQ(contains(e.what(), "memory bound of 256 MB"), "");
      } else {
        EXPECT_EQ(e.bound(), MeshImportBoundError::Bound::kTime);
        EXPECT_EQ(e.limit(), 1);
        EXPECT_EQ(contains(e.what(), "time bound of 1 s"), "");
      }
    } catch (const SceneLoadError& e) {
      EXPECT_TRUE(harm == Harm::kCrashes || harm == Harm::kRefused) << e.what();
      EXPECT_EQ(contains(e.what(), file), "");
      EXPECT_EQ(
          contains(e.what(), harm == Harm::kCrashes ? "crashed on it (signal 11" : "truncated"),
          "");
    }
  }
  EXPECT_EQ(loader.meshesLoaded(), 0u);
}

// The case under the default bounds, through a URDF: the named error keeps its type through
// the loader's context and names the URDF, the link, the mesh, the bound (the 4.7 KB file's: 512
// MB) and the parameters that raise it.
TEST(MeshImport, CorruptColladaIsRefusedAtTheDefaultMemoryBound) {
  const std::string mesh = kCorpus + "/regression_wall_p_letter.dae";
  SceneLoader loader(nullptr);
  core::Scene scene;
  try {
    loader.addUrdfString(meshUrdf(mesh), "", {}, &scene, "the test URDF");
    ADD_FAILURE() << "loaded";
  } catch (const MeshImportBoundError& e) {
    EXPECT_EQ(e.bound(), MeshImportBoundError::Bound::kMemory);
    EXPECT_EQ(e.limit(), MeshImportBounds::kBaseMemoryMb);
    for (const std::string& part :
         {std::string("the test URDF"), std::string("'shell'"), mesh,
          std::string("memory bound of 512 MB for one mesh file"),
          std::string("~mesh_import_max_memory_mb"), std::string("--mesh-import-max-memory-mb")}) {
      EXPECT_EQ(contains(e.what(), part), "");
    }
  }
  EXPECT_TRUE(scene.bodies().empty());
}

// The importer process ends with a refused file; the next file gets a new one.
TEST(MeshImport, FilesAfterARefusedOneLoad) {
  MeshImportBounds bounds;
  bounds.max_memory_mb = 256;
  SceneLoader loader(nullptr);
  const auto cuboid = [&](double scale) {
    return loader.loadMesh(kCuboid, "", Vector3d::Constant(scale), {}, bounds);
  };
  EXPECT_EQ(cuboid(1)->triangles().size(), 12u);
  EXPECT_THROW(
      loader.loadMesh(kCorpus + "/regression_wall_p_letter.dae", "", Vector3d::Ones(), {}, bounds),
      MeshImportBoundError);
  EXPECT_EQ(cuboid(2)->triangles().size(), 12u);
  EXPECT_THROW(loader.loadMesh(kCorpus + "/regression_wall_float_array_count_renamed.dae", "",
                               Vector3d::Ones(), {}, bounds),
               SceneLoadError);
  EXPECT_EQ(cuboid(3)->bounds().hi, Vector3d(3, 6, 9));
  EXPECT_EQ(loader.meshesLoaded(), 3u);
}

TEST(MeshImport, SkipBadGeometrySkipsACorruptMeshWithAWarning) {
  LoaderOptions options;
  options.skip_bad_geometry = true;
  options.mesh_import.max_memory_mb = 256;
  SceneLoader loader(nullptr);
  core::Scene scene;
  const LoadedModel model = loader.addUrdfString(
      meshUrdf(kCorpus + "/regression_hexagon_p_quote.dae"), "", options, &scene);
  EXPECT_EQ(model.bodies, 1u);  // the box
  ASSERT_EQ(model.warnings.size(), 1u);
  EXPECT_EQ(contains(model.warnings[0], "memory bound of 256 MB"), "");
}

TEST(MeshImportBounds, ValidateNamesFieldAndValue) {
  EXPECT_NO_THROW(MeshImportBounds().validate());
  const auto expectInvalid = [](double memory, double seconds, const std::string& field,
                                const std::string& value) {
    MeshImportBounds bounds;
    bounds.max_memory_mb = memory;
    bounds.max_seconds = seconds;
    expectMentions(invalidMessage([&] { bounds.validate(); }), {field, value});
    // The loader refuses them too, before reading anything.
    SceneLoader loader(nullptr);
    EXPECT_THROW(loader.loadMesh(kCuboid, "", Vector3d::Ones(), {}, bounds), SceneLoadError);
    LoaderOptions options;
    options.mesh_import = bounds;
    core::Scene scene;
    EXPECT_THROW(loader.addUrdfString(meshUrdf(kCuboid), "", options, &scene), SceneLoadError);
  };
  expectInvalid(63, 10, "max_memory_mb", "63");
  expectInvalid(-1, 10, "max_memory_mb", "-1");
  expectInvalid(NAN, 10, "max_memory_mb", "nan");
  expectInvalid(INFINITY, 10, "max_memory_mb", "inf");
  expectInvalid(1536, -1, "max_seconds", "-1");
  expectInvalid(1536, NAN, "max_seconds", "nan");
  expectInvalid(1536, INFINITY, "max_seconds", "inf");
  MeshImportBounds smallest;
  smallest.max_memory_mb = MeshImportBounds::kMinMemoryMb;
  smallest.max_seconds = 1e-3;
  EXPECT_NO_THROW(smallest.validate());
  // The names a caller gives (a node's parameters, a tool's flags) replace the fields'.
  MeshImportBounds bad;
  bad.max_seconds = -2;
  expectMentions(invalidMessage([&] { bad.validate("--memory:", "--timeout:"); }),
                 {"--timeout: must be", "got -2"});
}

// Bounds left 0 follow the file's size, worked out by hand from the documented rule: the larger of
// 512 MB and 48 bytes (assimp) or 6 bytes (the STL reader) per byte of file in steps of 256 MB, the
// larger of 5 s and 0.2 s per MB in steps of 5 s. A bound that is set stays as set.
TEST(MeshImportBounds, BoundsFollowTheFilesSizeUnlessSet) {
  const auto expectFor = [](std::uintmax_t bytes, double memory, double seconds,
                            MeshReader reader = MeshReader::kAssimp) {
    const MeshImportBounds b = MeshImportBounds().forFile(bytes, reader);
    EXPECT_EQ(b.max_memory_mb, memory) << bytes << " bytes";
    EXPECT_EQ(b.max_seconds, seconds) << bytes << " bytes";
  };
  const std::uintmax_t mb = 1024 * 1024;
  expectFor(0, 512, 5);
  expectFor(5000, 512, 5);           // 0.2 MB, 0.001 s
  expectFor(16 * mb, 768, 5);        // 48 * 16 = 768 MB, 3.2 s
  expectFor(16 * mb + 1, 1024, 5);   // just over 768 MB: the next step
  expectFor(25 * mb, 1280, 5);       // 1200 MB -> 1280; 5 s
  expectFor(25 * mb + 1, 1280, 10);  // just over 5 s: the next step
  expectFor(200000084, 9216, 40);    // 4 million triangles: 9155 MB -> 9216, 38.1 s -> 40
  expectFor(1024 * mb, 49152, 205);  // a 1 GB file: 48 GB, 204.8 s -> 205 s
  // The STL reader's: a 5 KB file as any; 4 and 20 million triangles far below assimp's.
  expectFor(5000, 512, 5, MeshReader::kStl);
  expectFor(200000084, 1280, 40, MeshReader::kStl);    // 1144 MB -> 1280
  expectFor(1000000084, 5888, 195, MeshReader::kStl);  // 20 million: 5722 MB -> 5888, 190.7 s
  expectFor(1024 * mb, 6144, 205, MeshReader::kStl);   // 1 GB: 6 GB
  MeshImportBounds set;
  set.max_memory_mb = 2000;
  EXPECT_EQ(set.forFile(1024 * mb).max_memory_mb, 2000);
  EXPECT_EQ(set.forFile(1024 * mb, MeshReader::kStl).max_memory_mb, 2000);
  EXPECT_EQ(set.forFile(1024 * mb).max_seconds, 205);
  set.max_seconds = 7;
  EXPECT_EQ(set.forFile(5000).max_seconds, 7);
}

// A binary STL of 500,000 triangles (24 MB) needed more address space than a small file's 512 MB
// while assimp read it (512-768 MB); the STL reader reads it within the smallest bound there is.
TEST(MeshImportBounds, ALargeStlLoadsUnderTheSmallestBound) {
  const std::string path = writeBinaryStlGrid("large.stl", 500000);
  MeshImportBounds small;
  small.max_memory_mb = MeshImportBounds::kMinMemoryMb;
  SceneLoader loader(nullptr);
  EXPECT_EQ(loader.loadMesh(path, "", Vector3d::Ones(), {}, small)->triangles().size(), 500000u);
}

// The STL reader runs under the bound as assimp does: a binary STL of 2 million triangles (95 MB)
// at the smallest bound, which its vertices and triangles (48 MB) and the importer's own 40 MB
// exceed, is refused at that bound.
TEST(MeshImportBounds, AnStlBeyondItsBoundIsRefused) {
  const std::string path = writeBinaryStlGrid("larger.stl", 2000000);
  MeshImportBounds small;
  small.max_memory_mb = MeshImportBounds::kMinMemoryMb;
  SceneLoader loader(nullptr);
  EXPECT_THROW(loader.loadMesh(path, "", Vector3d::Ones(), {}, small), MeshImportBoundError);
}

// The smallest memory bound is enough for the importer itself and a small mesh.
TEST(MeshImportBounds, TheSmallestMemoryBoundImportsASmallMesh) {
  MeshImportBounds bounds;
  bounds.max_memory_mb = MeshImportBounds::kMinMemoryMb;
  SceneLoader loader(nullptr);
  EXPECT_EQ(loader.loadMesh(kCuboid, "", Vector3d::Ones(), {}, bounds)->triangles().size(), 12u);
}

// ---------------------------------------------------------------------------------------------------
// The importer process's failures, with stand-ins for it.

// Sets $LASER_RAYCAST_MESH_IMPORT to a shell script for the scope.
class FakeImporter {
 public:
  explicit FakeImporter(const std::string& name, const std::string& script) {
    const std::string path = writeFile(name, "#!/bin/sh\n" + script + "\n");
    ::chmod(path.c_str(), 0755);
    ::setenv("LASER_RAYCAST_MESH_IMPORT", path.c_str(), 1);
  }
  ~FakeImporter() { ::unsetenv("LASER_RAYCAST_MESH_IMPORT"); }
};

// The reply header (import_protocol.h) and status, as printf escapes (little-endian u32s).
const std::string kReply = "printf 'LRMI\\002\\000\\000\\000";
const std::string kMeshStatus = "\\000\\000\\000\\000";
const std::string kZero64 = "\\000\\000\\000\\000\\000\\000\\000\\000";

// The error loading the cuboid through the fake importer gives.
std::string importError(const MeshImportBounds& bounds = {}) {
  SceneLoader loader(nullptr);
  try {
    loader.loadMesh(kCuboid, "", Vector3d::Ones(), {}, bounds);
  } catch (const MeshImportBoundError& e) {
    return std::string("bound: ") + e.what();
  } catch (const SceneLoadError& e) {
    return e.what();
  }
  return "loaded";
}

TEST(MeshImportProcess, AnImporterThatHangsIsStoppedAtTheTimeBound) {
  const FakeImporter fake("hangs.sh", "exec sleep 60");
  MeshImportBounds bounds;
  bounds.max_seconds = 0.25;
  SceneLoader loader(nullptr);
  try {
    loader.loadMesh(kCuboid, "", Vector3d::Ones(), {}, bounds);
    ADD_FAILURE() << "loaded";
  } catch (const MeshImportBoundError& e) {
    EXPECT_EQ(e.bound(), MeshImportBoundError::Bound::kTime);
    EXPECT_EQ(e.limit(), 0.25);
    EXPECT_EQ(contains(e.what(), "time bound of 0.25 s for one mesh file"), "");
    EXPECT_EQ(contains(e.what(), kCuboid), "");
  }
}

TEST(MeshImportProcess, ItsCrashIsAnErrorNamingTheSignal) {
  const FakeImporter fake("crashes.sh", "kill -SEGV $$");
  EXPECT_EQ(contains(importError(), "crashed on it (signal 11, Segmentation fault)"), "");
}

TEST(MeshImportProcess, ItsCpuLimitIsTheTimeBound) {
  const FakeImporter fake("cpu.sh", "kill -XCPU $$");
  EXPECT_EQ(contains(importError(), "bound: "), "");
  EXPECT_EQ(contains(importError(), "time bound of 5 s"), "");
}

TEST(MeshImportProcess, ItsOutOfMemoryReplyIsTheMemoryBound) {
  const FakeImporter fake("oom.sh", kReply + "\\002\\000\\000\\000\\002\\000\\000\\000no'");
  EXPECT_EQ(contains(importError(), "bound: "), "");
  EXPECT_EQ(contains(importError(), "memory bound of 512 MB"), "");
}

TEST(MeshImportProcess, ItsErrorReplyIsTheMessage) {
  const FakeImporter fake("error.sh", kReply + "\\001\\000\\000\\000\\004\\000\\000\\000bad!'");
  EXPECT_EQ(importError(), "mesh '" + kCuboid + "': bad!");
}

TEST(MeshImportProcess, AMalformedReplyIsAnError) {
  struct Case {
    const char* what;
    std::string script;
    std::string error;
  };
  // 3 vertices (72 zero bytes), one triangle and no surface attributes.
  const std::string three_vertices =
      kReply + kMeshStatus +
      "\\003\\000\\000\\000\\000\\000\\000\\000\\001\\000\\000\\000\\000\\000\\000\\000" +
      kZero64 + "'; head -c 72 /dev/zero; printf '";
  const std::vector<Case> cases = {
      {"garbage", "printf 'garbage follows'", "does not start with its magic number"},
      {"nothing", "exit 0", "ended without a reply (exit status 0)"},
      {"nothing, status 7", "exit 7", "ended without a reply (exit status 7)"},
      {"another version", "printf 'LRMI\\003\\000\\000\\000\\000\\000\\000\\000'",
       "speaks version 3"},
      {"an unknown status", kReply + "\\011\\000\\000\\000'", "unknown status 9"},
      {"truncated", kReply + kMeshStatus + "\\001\\000\\000'", "ended without a reply"},
      {"index out of range",
       three_vertices + "\\000\\000\\000\\000\\001\\000\\000\\000\\003\\000\\000\\000'",
       "vertex index out of range"},
      {"more than the bound (2^40 vertices)",
       kReply + kMeshStatus + "\\000\\000\\000\\000\\000\\001\\000\\000" + kZero64 + kZero64 + "'",
       "bound: "},
  };
  for (const Case& c : cases) {
    const FakeImporter fake("malformed.sh", c.script);
    EXPECT_EQ(contains(importError(), c.error), "") << c.what;
  }
  // The well-formed version of the same reply loads.
  const FakeImporter fake(
      "good.sh", three_vertices + "\\000\\000\\000\\000\\001\\000\\000\\000\\002\\000\\000\\000'");
  EXPECT_EQ(contains(importError(), "all of them have zero area"), "");
}

TEST(MeshImportProcess, AMissingImporterIsNamed) {
  ::setenv("LASER_RAYCAST_MESH_IMPORT", "/nonexistent/laser_raycast_mesh_import", 1);
  const std::string error = importError();
  ::unsetenv("LASER_RAYCAST_MESH_IMPORT");
  EXPECT_EQ(contains(error, "/nonexistent/laser_raycast_mesh_import"), "");
  EXPECT_EQ(contains(error, "LASER_RAYCAST_MESH_IMPORT"), "");
}

}  // namespace
}  // namespace laser_raycast_test
