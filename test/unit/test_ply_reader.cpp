// The loader's reader of plain binary PLY files (src/loader/ply_reader.h) against assimp, which
// reads every other PLY and stays the reference: on files of float vertices and triangles written
// by the test (8-, 16- and 32-bit indices, signed and unsigned; comments; a vertex given twice;
// unused vertices; "vertex_index"), the two give the same triangles over the same vertices in the
// same order, bit for bit, and no surface attributes; and everything else a PLY may hold is left to
// assimp (nullopt).
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "laser_raycast/core/mesh.h"
#include "laser_raycast/loader/errors.h"
#include "mesh_import.h"
#include "ply_reader.h"
#include "loader_against_assimp.h"
#include "temp_files.h"

namespace laser_raycast_test {
namespace {

using Eigen::Vector3d;
using laser_raycast::mesh_file::importMeshInProcess;
using laser_raycast::mesh_file::MeshData;
using laser_raycast::mesh_file::readPlainPly;

// A PLY's parts: the header's lines between the format and end_header, and the binary body.
struct Ply {
  std::string header;
  std::string body;
  std::string text(const std::string& format = "binary_little_endian 1.0") const {
    return "ply\nformat " + format + "\n" + header + "end_header\n" + body;
  }
};

template <class T>
void append(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out->append(bytes, sizeof(T));
}

// A pseudo-random sequence (an LCG).
class Numbers {
 public:
  std::uint32_t below(std::uint32_t n) {
    state_ = state_ * 1664525u + 1013904223u;
    return (state_ >> 8) % n;
  }
  // A float in ±[2^-7, 2^19) (rarely nearer 0), its bits random. Not smaller: assimp's
  // JoinIdenticalVertices also joins some vertices that are only near each other (seen with
  // every coordinate below 1e-5), which the reader, as readStl, keeps apart.
  float next() {
    const float mantissa = static_cast<float>(below(1 << 24)) / float(1 << 24) - 0.5f;
    return std::ldexp(mantissa, static_cast<int>(below(26)) - 6);
  }

 private:
  std::uint32_t state_ = 2025;
};

// `vertices` random float vertices (some given twice, the last never used) and `triangles`
// triangles over them, the face list's count of type C and indices of type I.
template <class C, class I>
Ply randomPly(int vertices, int triangles, const std::string& count_type,
              const std::string& index_type, const std::string& list_name = "vertex_indices") {
  Numbers random;
  Ply ply;
  ply.header = "comment written by test_ply_reader\nelement vertex " + std::to_string(vertices) +
               "\nproperty float x\nproperty float32 y\nproperty float z\nobj_info a note\n"
               "element face " +
               std::to_string(triangles) + "\nproperty list " + count_type + " " + index_type +
               " " + list_name + "\n";
  std::vector<std::array<float, 3>> given;
  for (int v = 0; v < vertices; ++v) {
    std::array<float, 3> p{random.next(), random.next(), random.next()};
    if (v % 89 == 7) p = given[random.below(static_cast<std::uint32_t>(given.size()))];
    given.push_back(p);
    for (const float c : p) append(&ply.body, c);
  }
  for (int t = 0; t < triangles; ++t) {
    append(&ply.body, static_cast<C>(3));
    for (int k = 0; k < 3; ++k) {
      append(&ply.body, static_cast<I>(random.below(static_cast<std::uint32_t>(vertices - 1))));
    }
  }
  return ply;
}

// The reader's mesh and assimp's of one file: the same triangles over the same vertices, bit for
// bit, and no surface attributes.
void expectSameAsAssimp(const std::string& path, const Vector3d& scale) {
  SCOPED_TRACE(path);
  const std::optional<MeshData> ours = readPlainPly(path, scale);
  ASSERT_TRUE(ours.has_value());
  const MeshData theirs = importMeshInProcess(path, scale);
  EXPECT_EQ(ours->triangles, theirs.triangles);
  EXPECT_EQ(ours->vertices, theirs.vertices);
  // No material: assimp's white one for a file without any is its own, not the file's.
  EXPECT_EQ(ours->surface, nullptr);
  EXPECT_EQ(theirs.surface, nullptr);
}

TEST(PlyReader, PlainTrianglesAsAssimpReadsThem) {
  const std::string big = writeFile(
      "big.ply", randomPly<std::uint8_t, std::int32_t>(30000, 60000, "uchar", "int").text());
  expectSameAsAssimp(big, Vector3d::Ones());
  expectSameAsAssimp(big, Vector3d(0.001, 0.002, 0.003));
  expectSameAsAssimp(
      writeFile("uint.ply",
                randomPly<std::uint8_t, std::uint32_t>(500, 900, "uint8", "uint32").text()),
      Vector3d::Ones());
  expectSameAsAssimp(writeFile("short.ply", randomPly<std::uint16_t, std::int16_t>(
                                                300, 500, "ushort", "short", "vertex_index")
                                                .text()),
                     Vector3d::Ones());
  expectSameAsAssimp(
      writeFile("byte.ply",
                randomPly<std::uint32_t, std::uint8_t>(200, 400, "uint", "uchar").text()),
      Vector3d::Ones());
}

// Through the scene loader, whose importer process reads the file: the mesh assimp gives, scaled.
TEST(PlyReader, TheLoaderGivesAssimpsMesh) {
  expectLoaderGivesAssimpsMesh(
      writeFile("loaded.ply",
                randomPly<std::uint8_t, std::int32_t>(2000, 4000, "uchar", "int").text()),
      Vector3d(0.5, 2, 0.25));
}

// Each of these holds something beyond plain float vertices and triangles, or is broken: assimp
// reads it (or says what is wrong).
TEST(PlyReader, LeavesEverythingElseToAssimp) {
  const Ply plain = randomPly<std::uint8_t, std::int32_t>(10, 8, "uchar", "int");
  // Replaces the first `from` in a copy of the header.
  const auto header = [&](const std::string& from, const std::string& to) {
    Ply ply = plain;
    const std::size_t at = ply.header.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    ply.header.replace(at, from.size(), to);
    return ply;
  };
  Ply quad = plain;
  quad.body[10 * 12] = 4;  // the first face's count
  Ply beyond = plain;
  const std::int32_t eleven = 11;
  std::memcpy(&beyond.body[10 * 12 + 1], &eleven, 4);
  Ply negative = plain;
  const std::int32_t minus_one = -1;
  std::memcpy(&negative.body[10 * 12 + 1], &minus_one, 4);
  Ply nan = plain;
  const float not_a_number = std::nanf("");
  std::memcpy(&nan.body[4], &not_a_number, 4);
  Ply unused_nan = plain;  // the last vertex, which no face uses
  std::memcpy(&unused_nan.body[9 * 12], &not_a_number, 4);
  Ply trailing = plain;
  trailing.body += "\n";
  Ply truncated = plain;
  truncated.body.pop_back();
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"ascii", plain.text("ascii 1.0")},
      {"big_endian", plain.text("binary_big_endian 1.0")},
      {"double", header("property float x\n", "property double x\n").text()},
      {"normal", header("property float z\n", "property float z\nproperty float nx\n").text()},
      {"colour", header("property float z\n", "property float z\nproperty uchar red\n").text()},
      {"axes_swapped", header("property float x\n", "property float q\n").text()},
      {"texture_coordinates",
       header("vertex_indices\n", "vertex_indices\nproperty list uchar float texcoord\n").text()},
      {"other_element", header("element face",
                               "element edge 0\nproperty int vertex1\n"
                               "element face")
                            .text()},
      {"signed_count", header("list uchar", "list char").text()},
      {"float_index", header("uchar int", "uchar float").text()},
      {"quad", quad.text()},
      {"beyond_the_last", beyond.text()},
      {"negative", negative.text()},
      {"nan", nan.text()},
      {"unused_nan", unused_nan.text()},
      {"trailing_byte", trailing.text()},
      {"truncated", truncated.text()},
      {"no_faces",
       header("element face 8", "element face 0").text().substr(0, plain.text().size() - 8 * 13)},
      {"crlf_header",
       "ply\r\nformat binary_little_endian 1.0\r\n" + plain.header + "end_header\r\n" + plain.body},
      {"no_end", "ply\nformat binary_little_endian 1.0\n" + plain.header},
      {"empty", ""},
  };
  for (const auto& [name, text] : cases) {
    EXPECT_FALSE(readPlainPly(writeFile(name + ".ply", text), Vector3d::Ones()).has_value())
        << name;
  }
  // assimp's path refuses a vertex that is not finite even where no face uses it.
  EXPECT_THROW(
      importMeshInProcess(writeFile("unused_nan.ply", unused_nan.text()), Vector3d::Ones()),
      laser_raycast::SceneLoadError);
}

TEST(PlyReader, AFileThatCannotBeOpenedIsAnError) {
  EXPECT_THROW(readPlainPly((tempDir() / "missing.ply").string(), Vector3d::Ones()),
               laser_raycast::SceneLoadError);
}

}  // namespace
}  // namespace laser_raycast_test
