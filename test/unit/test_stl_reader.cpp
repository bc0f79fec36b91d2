// The loader's own STL reader (src/loader/stl_reader.h) against assimp, which read every STL file
// before it and stays the reference here: on the TurtleBot3 meshes (../shared, when present) and
// on files written by the test, binary and ASCII, the two give the same triangles, each corner at
// the same point, and the same set of distinct points. The reader joins every vertex of equal
// coordinates (assimp keeps a copy per facet normal); it parses ASCII numbers correctly rounded
// (assimp's parser is off by one bit in some, so ASCII coordinates are compared to within one ulp
// of float); and it refuses what is not a whole STL file, saying what is wrong.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "laser_raycast/loader/errors.h"
#include "mesh_import.h"
#include "shared_data.h"
#include "stl_reader.h"
#include "temp_files.h"

namespace laser_raycast_test {
namespace {

using Eigen::Vector3d;
using laser_raycast::SceneLoadError;
using laser_raycast::mesh_file::importMeshInProcess;
using laser_raycast::mesh_file::MeshData;
using laser_raycast::mesh_file::readStl;

using Triangle = std::array<float, 9>;  // three corners, x y z each

std::string contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos ? "" : "'" + part + "' missing in: " + text;
}

// A binary STL of the triangles, the header's count replaced by `count` if given and the file cut
// to `keep` bytes if given.
std::string writeBinary(const std::string& name, const std::vector<Triangle>& triangles,
                        const std::string& header = "binary", std::int64_t count = -1,
                        std::int64_t keep = -1) {
  std::string bytes = header;
  bytes.resize(80, ' ');
  const auto n = static_cast<std::uint32_t>(count >= 0 ? count : triangles.size());
  bytes.append(reinterpret_cast<const char*>(&n), 4);
  for (const Triangle& t : triangles) {
    const float normal[3] = {0, 0, 1};
    bytes.append(reinterpret_cast<const char*>(normal), sizeof normal);
    bytes.append(reinterpret_cast<const char*>(t.data()), sizeof(float) * 9);
    bytes.append(2, '\0');
  }
  if (keep >= 0) bytes.resize(keep);
  return writeFile(name, bytes);
}

// ASCII STL text of the triangles as one solid, numbers with 9 significant digits (enough to give
// every float back exactly), lines ending in `eol`.
std::string asciiSolid(const std::vector<Triangle>& triangles, const std::string& name,
                       const std::string& eol = "\n") {
  std::ostringstream out;
  out.precision(9);
  out << "solid " << name << eol;
  for (const Triangle& t : triangles) {
    out << "  facet normal 0 0 1" << eol << "    outer loop" << eol;
    for (int k = 0; k < 3; ++k) {
      out << "      vertex " << t[3 * k] << " " << t[3 * k + 1] << " " << t[3 * k + 2] << eol;
    }
    out << "    endloop" << eol << "  endfacet" << eol;
  }
  out << "endsolid " << name << eol;
  return out.str();
}

// A closed box of 12 triangles, front faces out, corners at 0 and the given extents; and one with a
// -0 corner, so that a vertex is given as both 0 and -0.
std::vector<Triangle> box(float x, float y, float z) {
  const float c[8][3] = {{0, 0, 0}, {x, 0, 0}, {x, y, 0}, {0, y, 0},
                         {0, 0, z}, {x, 0, z}, {x, y, z}, {0, y, z}};
  const int faces[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                            {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  std::vector<Triangle> out;
  for (const auto& f : faces) {
    Triangle t;
    for (int k = 0; k < 3; ++k) std::memcpy(&t[3 * k], c[f[k]], sizeof c[0]);
    out.push_back(t);
  }
  out[0][0] = -0.0f;
  return out;
}

// Triangles as their corners' points, in file order; and the distinct points.
std::vector<std::array<Vector3d, 3>> corners(const MeshData& mesh) {
  std::vector<std::array<Vector3d, 3>> out;
  for (const auto& t : mesh.triangles) {
    out.push_back({mesh.vertices.at(t[0]), mesh.vertices.at(t[1]), mesh.vertices.at(t[2])});
  }
  return out;
}
std::set<std::array<double, 3>> points(const MeshData& mesh) {
  std::set<std::array<double, 3>> out;
  for (const Vector3d& v : mesh.vertices) out.insert({v.x() + 0.0, v.y() + 0.0, v.z() + 0.0});
  return out;
}

// The reader's mesh and assimp's of one file: the same triangles in the same order (a file of one
// solid), each corner within `ulps` ulps of float of the other's, and with ulps 0 the same set of
// points; the reader's points all distinct.
void expectSameAsAssimp(const std::string& path, const Vector3d& scale = Vector3d::Ones(),
                        int ulps = 0) {
  SCOPED_TRACE(path);
  const MeshData ours = readStl(path, scale), theirs = importMeshInProcess(path, scale);
  ASSERT_EQ(ours.triangles.size(), theirs.triangles.size());
  const auto a = corners(ours), b = corners(theirs);
  int differ = 0;
  for (std::size_t t = 0; t < a.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      for (int c = 0; c < 3; ++c) {
        const double x = a[t][k][c], y = b[t][k][c];
        const double ulp = std::abs(std::nextafter(float(x), INFINITY) - float(x));
        differ += x != y;
        ASSERT_LE(std::abs(x - y), ulps * ulp * std::max(scale.maxCoeff(), 1.0))
            << "triangle " << t << " corner " << k;
      }
    }
  }
  if (ulps == 0) {
    EXPECT_EQ(differ, 0);
    EXPECT_EQ(points(ours), points(theirs));
  }
  EXPECT_EQ(points(ours).size(), ours.vertices.size()) << "a point given twice";
  EXPECT_LE(ours.vertices.size(), theirs.vertices.size());
}

// The message of the reader's refusal of the file ("" if it read it).
std::string refusal(const std::string& path) {
  try {
    readStl(path, Vector3d::Ones());
  } catch (const SceneLoadError& e) {
    return e.what();
  }
  return "";
}

TEST(StlReader, TheTurtleBot3MeshesAsAssimpReadsThem) {
  REQUIRE_SHARED_DATA();
  const std::string waffle = tb3WorldData() + "/meshes/waffle/";
  for (const char* name : {"lds.stl", "left_tire.stl", "right_tire.stl"}) {
    expectSameAsAssimp(waffle + name);
    expectSameAsAssimp(waffle + name, Vector3d(0.001, 0.002, 0.003));
  }
  // Joined on position alone: lds.stl's 14,566 triangles share 7,231 points, which assimp keeps as
  // 29,862 vertices (one per facet normal meeting there).
  EXPECT_EQ(readStl(waffle + "lds.stl", Vector3d::Ones()).vertices.size(), 7231u);
}

TEST(StlReader, ABinaryBoxIsEightVerticesAndTwelveTriangles) {
  const std::string path = writeBinary("box.stl", box(1, 2, 3));
  expectSameAsAssimp(path);
  expectSameAsAssimp(path, Vector3d(2, 0.5, 1e-3));
  const MeshData mesh = readStl(path, Vector3d::Ones());
  EXPECT_EQ(mesh.vertices.size(), 8u);  // -0 is 0
  EXPECT_EQ(mesh.triangles.size(), 12u);
}

// A header that starts with "solid", as some writers give binary files, is still binary when the
// size fits its count.
TEST(StlReader, ABinaryHeaderMayStartWithSolid) {
  const std::string path = writeBinary("solid_header.stl", box(1, 1, 1), "solid box");
  expectSameAsAssimp(path);
}

// Every float back exactly from 9 digits: the ASCII file gives the binary file's mesh, bit for bit.
TEST(StlReader, AsciiNumbersAreCorrectlyRounded) {
  std::vector<Triangle> triangles;
  std::uint32_t state = 12345;
  const auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return std::ldexp(float(state >> 8) / float(1 << 24) - 0.5f, int(state % 40) - 20);
  };
  for (int t = 0; t < 500; ++t) {
    Triangle tri;
    for (float& x : tri) x = next();
    triangles.push_back(tri);
  }
  const MeshData binary = readStl(writeBinary("random.stl", triangles), Vector3d::Ones());
  const std::string ascii = writeFile("random_ascii.stl", asciiSolid(triangles, "random"));
  const MeshData text = readStl(ascii, Vector3d::Ones());
  EXPECT_EQ(text.vertices, binary.vertices);
  EXPECT_EQ(text.triangles, binary.triangles);
  expectSameAsAssimp(ascii, Vector3d::Ones(), 2);
}

// A name of several words, CRLF line ends, "+" signs, exponents, tabs, and two solids (assimp makes
// a mesh of each, in reverse order, so the triangles are compared as sets here).
TEST(StlReader, AsciiVariants) {
  const std::vector<Triangle> a = box(1, 2, 3), b = box(4, 5, 6);
  const std::string crlf = writeFile("crlf.stl", asciiSolid(a, "my box part", "\r\n"));
  expectSameAsAssimp(crlf);
  const std::string signs = writeFile(
      "signs.stl",
      "solid\n facet normal +0 -0 1e0\n\touter loop\n vertex +1.5e0 0 0\n vertex 0 2.5E+00 -0\n"
      "vertex 0.25 0.125e1 1.\n endloop\n endfacet\nendsolid\n");
  expectSameAsAssimp(signs);
  EXPECT_EQ(corners(readStl(signs, Vector3d::Ones()))[0][2], Vector3d(0.25, 1.25, 1));
  const std::string two =
      writeFile("two.stl", asciiSolid(a, "first") + asciiSolid(b, "second", "\r\n"));
  const MeshData ours = readStl(two, Vector3d::Ones()),
                 theirs = importMeshInProcess(two, {1, 1, 1});
  EXPECT_EQ(ours.triangles.size(), 24u);
  const auto asSet = [](const MeshData& mesh) {
    std::multiset<std::array<double, 9>> out;
    for (const auto& t : corners(mesh)) {
      std::array<double, 9> x;
      for (int i = 0; i < 9; ++i) x[i] = t[i / 3][i % 3] + 0.0;
      out.insert(x);
    }
    return out;
  };
  EXPECT_EQ(asSet(ours), asSet(theirs));
  EXPECT_EQ(points(ours), points(theirs));
  EXPECT_EQ(ours.vertices.size(), 15u);  // the boxes share the point 0
}

// Degenerate triangles stay, as assimp keeps them (core::Mesh leaves them out of its BVH): two
// corners at one point (one vertex index twice) and three in a line.
TEST(StlReader, DegenerateTrianglesAreKept) {
  std::vector<Triangle> triangles = box(1, 1, 1);
  triangles.push_back({0, 0, 0, 1, 1, 1, 0, 0, 0});
  triangles.push_back({0, 0, 0, 1, 1, 1, 2, 2, 2});
  const std::string binary = writeBinary("degenerate.stl", triangles);
  expectSameAsAssimp(binary);
  const MeshData mesh = readStl(binary, Vector3d::Ones());
  ASSERT_EQ(mesh.triangles.size(), 14u);
  EXPECT_EQ(mesh.triangles[12][0], mesh.triangles[12][2]);
  expectSameAsAssimp(writeFile("degenerate_ascii.stl", asciiSolid(triangles, "d")));
}

// A non-finite corner refuses the file, as the assimp path did, naming the triangle (binary) or
// the line (ASCII); a non-finite normal is not used, and does not.
TEST(StlReader, ANonFiniteVertexIsRefused) {
  std::vector<Triangle> triangles = box(1, 1, 1);
  triangles[5][4] = NAN;
  EXPECT_EQ(contains(refusal(writeBinary("nan.stl", triangles)),
                     "vertex 1 of triangle 5 is not finite (1 nan"),
            "");
  triangles[5][4] = -INFINITY;
  EXPECT_EQ(contains(refusal(writeBinary("inf.stl", triangles)), "(1 -inf"), "");
  EXPECT_EQ(contains(refusal(writeFile("nan_ascii.stl", asciiSolid(triangles, "n"))),
                     "line 40: a vertex is not finite"),
            "");
  const std::string overflow = "solid\nfacet normal 0 0 1\nouter loop\nvertex 1e39 0 0\n";
  EXPECT_EQ(
      contains(refusal(writeFile("overflow.stl", overflow)), "line 4: a vertex is not finite"), "");
  const std::string nan_normal = writeFile(
      "nan_normal.stl",
      "solid\nfacet normal nan 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
      "endloop\nendfacet\nendsolid\n");
  EXPECT_EQ(readStl(nan_normal, Vector3d::Ones()).triangles.size(), 1u);
  expectSameAsAssimp(nan_normal);
}

// Cut anywhere, or with a header count that does not fit the size, a binary file is refused,
// saying so (assimp refuses these too, as neither binary nor ASCII); so is one without triangles.
TEST(StlReader, TruncatedOrMiscountedBinaryIsRefused) {
  const std::vector<Triangle> triangles = box(1, 1, 1);  // 684 bytes
  for (const std::int64_t keep : {683, 600, 134, 84, 83, 10}) {
    SCOPED_TRACE(keep);
    const std::string path = writeBinary("cut.stl", triangles, "binary", -1, keep);
    const std::string message = refusal(path);
    if (keep >= 84) {
      EXPECT_EQ(contains(message,
                         "not an ASCII STL (line 1: it does not start with 'solid') nor a "
                         "binary one (its header counts 12 triangles, which take 684 "
                         "bytes; the file has " +
                             std::to_string(keep) + ": truncated, or a wrong count)"),
                "");
    } else if (keep > 80) {  // part of the count: not text
      EXPECT_EQ(contains(message, "nor a binary one (which has at least 84 bytes; the file has " +
                                      std::to_string(keep) + ")"),
                "");
    } else {  // only the header's text: not meant as binary
      EXPECT_EQ(contains(message, "not a valid ASCII STL: line 1: it does not start with 'solid'"),
                "");
    }
    EXPECT_THROW(importMeshInProcess(path, Vector3d::Ones()), SceneLoadError);
  }
  EXPECT_EQ(contains(refusal(writeBinary("more.stl", triangles, "binary", 13)),
                     "counts 13 triangles, which take 734 bytes; the file has 684: truncated"),
            "");
  EXPECT_EQ(contains(refusal(writeBinary("fewer.stl", triangles, "binary", 11)),
                     "counts 11 triangles, which take 634 bytes; the file has 684: a wrong count"),
            "");
  // Starting with "solid", it is tried as ASCII first: both are said.
  EXPECT_EQ(
      contains(refusal(writeBinary("solid_cut.stl", triangles, "solid x", -1, 600)), "line 1: "),
      "");
  EXPECT_EQ(contains(refusal(writeBinary("solid_cut.stl", triangles, "solid x", -1, 600)),
                     "the file has 600: truncated"),
            "");
  EXPECT_EQ(contains(refusal(writeBinary("none.stl", {})), "no triangles (an empty mesh"), "");
}

// An ASCII file cut short, or with a facet that is not a triangle, a word that is not a number or
// keyword, or anything after its last solid, is refused naming the line.
TEST(StlReader, MalformedAsciiIsRefusedNamingTheLine) {
  const std::string whole = asciiSolid(box(1, 1, 1), "b");  // 86 lines
  const auto expectRefused = [](const std::string& name, const std::string& text,
                                const std::string& part) {
    SCOPED_TRACE(name);
    EXPECT_EQ(contains(refusal(writeFile(name, text)), part), "");
  };
  expectRefused("cut_in_facet.stl", whole.substr(0, whole.find("endloop", 300)),
                "the end of the file where 'endloop' was expected (truncated?)");
  expectRefused("cut_in_number.stl", whole.substr(0, whole.find("vertex 1") + 7),
                "where a number was expected");
  expectRefused("no_endsolid.stl", whole.substr(0, whole.rfind("endsolid")),
                "line 86: the file ends before 'endsolid' (truncated?)");
  std::string four = whole;
  four.insert(four.find("    endloop"), "      vertex 1 1 1\n");
  expectRefused("four.stl", four, "line 7: 'vertex' where 'endloop' was expected");
  std::string two = whole;  // the second vertex line of the first facet left out
  const std::size_t second = two.find("      vertex", two.find("      vertex") + 1);
  two.erase(second, two.find('\n', second) + 1 - second);
  expectRefused("two.stl", two, "line 6: 'endloop' where 'vertex' was expected");
  std::string comma = whole;
  comma.replace(comma.find("vertex 1 0 0") + 7, 1, "1,5");
  expectRefused("comma.stl", comma, "'1,5' where a number was expected");
  expectRefused(
      "after.stl", whole + "garbage\n",
      "line 87: 'garbage' after 'endsolid', where the file should end or a 'solid' begin");
  expectRefused("no_facets.stl", "solid empty\nendsolid empty\n", "no triangles (an empty mesh");
  expectRefused("long_word.stl", "solid x\n" + std::string(5000, 'a'), "a word of more than");
  expectRefused("not_stl.stl", "ply\nformat ascii 1.0\n", "does not start with 'solid'");
  // NUL padding after the end is white space.
  EXPECT_EQ(refusal(writeFile("padded.stl", whole + std::string(100, '\0'))), "");
}

TEST(StlReader, ReadsStlByItsExtension) {
  using laser_raycast::mesh_file::isStlPath;
  EXPECT_TRUE(isStlPath("/a/b/mesh.stl"));
  EXPECT_TRUE(isStlPath("MESH.STL"));
  EXPECT_TRUE(isStlPath("x.Stl"));
  EXPECT_FALSE(isStlPath("mesh.dae"));
  EXPECT_FALSE(isStlPath("stl"));
  EXPECT_FALSE(isStlPath("mesh.stl.gz"));
}

}  // namespace
}  // namespace laser_raycast_test
