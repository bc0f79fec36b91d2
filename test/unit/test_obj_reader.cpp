// The loader's reader of plain OBJ files (src/loader/obj_reader.h) against assimp, which reads
// every other OBJ and stays the reference: on files of vertices and triangles written by the test
// (negative and forward vertex numbers, comments, an object name, smoothing groups, CRLF line ends,
// a vertex given twice, an unused one, more than one read chunk) the two give the same triangles
// over the same vertices in the same order, bit for bit where the numbers are exact in binary and
// within an ulp of float where assimp's parser rounds them off (the reader's are correctly
// rounded); and everything else an OBJ may hold is left to assimp (nullopt), the repository's own
// OBJ test meshes included.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "laser_raycast/core/mesh.h"
#include "laser_raycast/loader/errors.h"
#include "mesh_import.h"
#include "obj_reader.h"
#include "loader_against_assimp.h"
#include "temp_files.h"

namespace laser_raycast_test {
namespace {

using Eigen::Vector3d;
using laser_raycast::mesh_file::importMeshInProcess;
using laser_raycast::mesh_file::MeshData;
using laser_raycast::mesh_file::readPlainObj;

// The reader's mesh and assimp's of one file: the same triangles (vertex indices) and as many
// vertices, each coordinate within `ulps` ulps of float of assimp's, and no surface attributes.
void expectSameAsAssimp(const std::string& path, const Vector3d& scale, int ulps) {
  SCOPED_TRACE(path);
  const std::optional<MeshData> ours = readPlainObj(path, scale);
  ASSERT_TRUE(ours.has_value());
  const MeshData theirs = importMeshInProcess(path, scale);
  EXPECT_EQ(ours->triangles, theirs.triangles);
  ASSERT_EQ(ours->vertices.size(), theirs.vertices.size());
  int differ = 0;
  for (std::size_t v = 0; v < ours->vertices.size(); ++v) {
    for (int a = 0; a < 3; ++a) {
      const double x = ours->vertices[v][a], y = theirs.vertices[v][a];
      const float unscaled = static_cast<float>(x / scale[a]);
      const double ulp = std::abs(std::nextafter(unscaled, INFINITY) - unscaled) * scale[a];
      differ += x != y;
      ASSERT_LE(std::abs(x - y), ulps * ulp * 1.0000001) << "vertex " << v << " axis " << a;
    }
  }
  if (ulps == 0) {
    EXPECT_EQ(differ, 0);
  }
  EXPECT_EQ(ours->surface, nullptr);
  EXPECT_EQ(theirs.surface, nullptr);
}

// A pseudo-random float in ±[2^-21, 2^19): LCG bits scaled by a random power of two.
class Numbers {
 public:
  float next() {
    state_ = state_ * 1664525u + 1013904223u;
    return std::ldexp(float(state_ >> 8) / float(1 << 24) - 0.5f, int(state_ % 40) - 20);
  }
  std::uint32_t below(std::uint32_t n) {
    state_ = state_ * 1664525u + 1013904223u;
    return (state_ >> 8) % n;
  }

 private:
  std::uint32_t state_ = 2024;
};

// An OBJ of `vertices` random vertices (9 significant digits: every float back exactly; or, with
// exact, small multiples of 1/8) and `triangles` triangles over them, each corner numbered from the
// start or from the end at random, with the variants the reader accepts sprinkled in.
std::string randomObj(int vertices, int triangles, bool exact, const std::string& eol) {
  Numbers random;
  std::ostringstream out;
  out.precision(9);
  out << "# written by test_obj_reader" << eol << eol << "o random_mesh" << eol;
  const auto coordinate = [&] {
    return exact ? static_cast<float>(static_cast<int>(random.below(2001)) - 1000) / 8
                 : random.next();
  };
  std::vector<std::array<float, 3>> given;
  for (int v = 0; v < vertices; ++v) {
    std::array<float, 3> p{coordinate(), coordinate(), coordinate()};
    if (v % 97 == 5) p = given[random.below(static_cast<std::uint32_t>(given.size()))];  // twice
    given.push_back(p);
    out << (v % 13 == 0 ? "v\t" : "v ") << p[0] << " " << p[1] << "  " << p[2] << eol;
  }
  out << "s off" << eol;
  for (int t = 0; t < triangles; ++t) {
    if (t % 500 == 7) out << "# a comment between faces" << eol << "s 1" << eol;
    out << "f";
    for (int k = 0; k < 3; ++k) {
      // The last vertex is never used.
      const std::uint32_t v = random.below(static_cast<std::uint32_t>(vertices - 1));
      if (random.below(4) == 0) {
        out << " " << static_cast<long>(v) - vertices;  // from the end: -1 is the last
      } else {
        out << " " << v + 1;
      }
    }
    out << eol;
  }
  return out.str();
}

TEST(ObjReader, PlainTrianglesAsAssimpReadsThem) {
  // About 2.6 MB: lines cross the reader's 1 MB chunks.
  const std::string exact = writeFile("exact.obj", randomObj(20000, 40000, true, "\n"));
  expectSameAsAssimp(exact, Vector3d::Ones(), 0);
  expectSameAsAssimp(exact, Vector3d(0.001, 0.002, 0.003), 0);
  const std::string crlf = writeFile("crlf.obj", randomObj(3000, 6000, true, "\r\n"));
  expectSameAsAssimp(crlf, Vector3d::Ones(), 0);
  const std::string digits = writeFile("digits.obj", randomObj(5000, 9000, false, "\n"));
  expectSameAsAssimp(digits, Vector3d::Ones(), 1);
}

// A vertex a face names before the line that gives it, and a last line without a newline.
TEST(ObjReader, ForwardNumbersAndNoFinalNewline) {
  const std::string path =
      writeFile("forward.obj", "f 1 2 4\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf -4 -1 -2");
  expectSameAsAssimp(path, Vector3d::Ones(), 0);
  const std::optional<MeshData> mesh = readPlainObj(path, Vector3d::Ones());
  ASSERT_TRUE(mesh.has_value());
  EXPECT_EQ(mesh->vertices.size(), 4u);
  EXPECT_EQ(mesh->triangles.size(), 2u);
}

// Through the scene loader, whose importer process reads the file: the mesh assimp gives, scaled.
TEST(ObjReader, TheLoaderGivesAssimpsMesh) {
  expectLoaderGivesAssimpsMesh(writeFile("loaded.obj", randomObj(2000, 4000, true, "\n")),
                               Vector3d(0.5, 2, 0.25));
}

// Each of these holds something beyond plain vertices and triangles, or is broken: assimp reads it
// (or says what is wrong).
TEST(ObjReader, LeavesEverythingElseToAssimp) {
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"texture_coordinates", tri + "vt 0 0\nf 1 2 3\n"},
      {"normals", tri + "vn 0 0 1\nf 1 2 3\n"},
      {"slashes", tri + "f 1/1 2/2 3/3\n"},
      {"double_slashes", tri + "f 1//1 2//1 3//1\n"},
      {"material_library", "mtllib x.mtl\n" + tri + "f 1 2 3\n"},
      {"material", tri + "usemtl red\nf 1 2 3\n"},
      {"quad", tri + "v 1 1 0\nf 1 2 4 3\n"},
      {"two_corners", tri + "f 1 2\n"},
      {"homogeneous_vertex", "v 0 0 0 1\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
      {"vertex_colour", "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
      {"two_coordinates", "v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
      {"second_group", tri + "g a\nf 1 2 3\ng b\nf 3 2 1\n"},
      {"second_object", tri + "f 1 2 3\no b\nf 3 2 1\n"},
      {"vertex_zero", tri + "f 0 1 2\n"},
      {"beyond_the_last", tri + "f 1 2 4\n"},
      {"before_the_first", tri + "f -1 -2 -4\n"},
      {"not_a_number", "v 0 0 x\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
      {"nan", "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
      {"infinite", "v 0 0 inf\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
      {"plus_sign", "v +1 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
      {"continued_line", tri + "f 1 2 \\\n 3\n"},
      {"line", tri + "l 1 2\nf 1 2 3\n"},
      {"points_only", tri},
      {"empty", ""},
      {"binary", std::string("\x7f\x45\x4c\x46\x02\x01\x00\x00", 8)},
  };
  for (const auto& [name, text] : cases) {
    EXPECT_FALSE(readPlainObj(writeFile(name + ".obj", text), Vector3d::Ones()).has_value())
        << name;
  }
  // The repository's OBJ test meshes: quads, lines only, texture coordinates and a material.
  for (const std::string mesh : {"meshes/cuboid.obj", "meshes/lines_only.obj",
                                 "surfaces/checker_wall.obj", "surfaces/tilted_normals.obj"}) {
    EXPECT_FALSE(
        readPlainObj(std::string(LASER_RAYCAST_SOURCE_DIR) + "/test/data/" + mesh, Vector3d::Ones())
            .has_value())
        << mesh;
  }
}

TEST(ObjReader, AFileThatCannotBeOpenedIsAnError) {
  EXPECT_THROW(readPlainObj((tempDir() / "missing.obj").string(), Vector3d::Ones()),
               laser_raycast::SceneLoadError);
}

}  // namespace
}  // namespace laser_raycast_test
