#include "obj_reader.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <string_view>
#include <vector>

#include "laser_raycast/loader/errors.h"
#include "vertex_joiner.h"

namespace laser_raycast {
namespace mesh_file {
namespace {

constexpr std::size_t kChunkBytes = std::size_t(1) << 20;  // read at a time

// What the lines read so far hold: the vertices' coordinates, x y z each, and the triangles'
// corners as vertex numbers from 0 (checked against the vertex count at the end: a face may name a
// vertex that a later line gives).
struct Plain {
  std::vector<float> xyz;
  std::vector<std::int64_t> corners;
};

bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

// The line's words, at most kMaxWords of them (a line with more is not plain).
class Words {
 public:
  static constexpr int kMaxWords = 4;

  explicit Words(std::string_view line) {
    std::size_t pos = 0;
    while (pos < line.size()) {
      while (pos < line.size() && isBlank(line[pos])) ++pos;
      if (pos == line.size()) break;
      std::size_t end = pos;
      while (end < line.size() && !isBlank(line[end])) ++end;
      if (count_ == kMaxWords) {
        too_many_ = true;
        return;
      }
      words_[count_++] = line.substr(pos, end - pos);
      pos = end;
    }
  }

  int count() const { return too_many_ ? kMaxWords + 1 : count_; }
  std::string_view operator[](int k) const { return words_[k]; }

 private:
  std::string_view words_[kMaxWords];
  int count_ = 0;
  bool too_many_ = false;
};

// The whole word as a finite float, correctly rounded.
bool parseCoordinate(std::string_view word, float* out) {
  const char* end = word.data() + word.size();
  const auto [ptr, ec] = std::from_chars(word.data(), end, *out, std::chars_format::general);
  return ec == std::errc() && ptr == end && std::isfinite(*out);
}

// The whole word as a vertex number: from 1, or negative, counted back from the last of `count`
// vertices so far. Out: the vertex's index from 0 (perhaps beyond the vertices so far).
bool parseCorner(std::string_view word, std::size_t count, std::int64_t* out) {
  const char* end = word.data() + word.size();
  std::int64_t number = 0;
  const auto [ptr, ec] = std::from_chars(word.data(), end, number);
  if (ec != std::errc() || ptr != end || number == 0) return false;
  *out = number > 0 ? number - 1 : static_cast<std::int64_t>(count) + number;
  return *out >= 0;
}

// Reads one line into plain; false if the line holds what the reader leaves to assimp.
bool readLine(std::string_view line, Plain* plain) {
  const Words words(line);
  if (words.count() == 0 || words[0][0] == '#') return true;
  const std::string_view keyword = words[0];
  if (keyword == "v") {
    float v[3];
    if (words.count() != 4) return false;
    for (int a = 0; a < 3; ++a) {
      if (!parseCoordinate(words[a + 1], &v[a])) return false;
    }
    plain->xyz.insert(plain->xyz.end(), v, v + 3);
    return true;
  }
  if (keyword == "f") {
    if (words.count() != 4) return false;
    std::int64_t corner[3];
    for (int k = 0; k < 3; ++k) {
      if (!parseCorner(words[k + 1], plain->xyz.size() / 3, &corner[k])) return false;
    }
    plain->corners.insert(plain->corners.end(), corner, corner + 3);
    return true;
  }
  if (keyword == "s") return true;
  // assimp makes a mesh of each object or group that has faces: one name before the faces keeps
  // them one mesh.
  if (keyword == "o" || keyword == "g") return plain->corners.empty();
  return false;
}

}  // namespace

bool isObjPath(const std::string& path) { return lowerExtension(path) == ".obj"; }

std::optional<MeshData> readPlainObj(const std::string& path, const Eigen::Vector3d& scale) {
  const File file = openMeshFile(path);
  Plain plain;
  std::vector<char> buffer;
  std::size_t kept = 0;  // bytes of an unfinished line at the buffer's start
  for (bool at_end = false; !at_end;) {
    buffer.resize(kept + kChunkBytes);
    const std::size_t got = std::fread(buffer.data() + kept, 1, kChunkBytes, file.get());
    if (got < kChunkBytes) {
      if (std::ferror(file.get())) {
        throw SceneLoadError(std::string("reading it failed: ") + std::strerror(errno));
      }
      at_end = true;
    }
    const std::size_t size = kept + got;
    std::size_t start = 0;
    for (;;) {
      const void* newline = std::memchr(buffer.data() + start, '\n', size - start);
      // The last line of the file needs no newline.
      if (!newline && !(at_end && start < size)) break;
      const std::size_t end = newline ? static_cast<const char*>(newline) - buffer.data() : size;
      const std::string_view line(buffer.data() + start, end - start);
      // A backslash at a line's end continues it on the next line: assimp reads that.
      const std::size_t last = line.find_last_not_of('\r');
      if (last != std::string_view::npos && line[last] == '\\') return std::nullopt;
      if (!readLine(line, &plain)) return std::nullopt;
      if (!newline) break;  // that was the file's last line
      start = end + 1;
    }
    kept = size - start;
    std::memmove(buffer.data(), buffer.data() + start, kept);
  }
  const std::size_t vertex_count = plain.xyz.size() / 3;
  if (plain.corners.empty()) return std::nullopt;  // assimp says what such a file is
  if (vertex_count >= std::numeric_limits<std::uint32_t>::max()) return std::nullopt;
  // A vertex is joined the first time a face uses it, in the order of the faces' corners: the
  // order in which the assimp path gets its vertices (a vertex per corner, then joined).
  constexpr std::uint32_t kUnjoined = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> joined(vertex_count, kUnjoined);
  MeshData out;
  VertexJoiner joiner(scale, &out.vertices);
  joiner.reserve(std::min(vertex_count, plain.corners.size()));
  out.triangles.reserve(plain.corners.size() / 3);
  for (std::size_t t = 0; t < plain.corners.size(); t += 3) {
    core::TriangleIndices tri;
    for (int k = 0; k < 3; ++k) {
      const std::int64_t v = plain.corners[t + k];
      if (v >= static_cast<std::int64_t>(vertex_count)) return std::nullopt;  // assimp reports it
      if (joined[v] == kUnjoined) {
        const float* p = &plain.xyz[3 * v];
        joined[v] = joiner.add(p[0], p[1], p[2]);
      }
      tri[k] = joined[v];
    }
    out.triangles.push_back(tri);
  }
  return out;
}

}  // namespace mesh_file
}  // namespace laser_raycast
