#include "ply_reader.h"

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

// A header longer than this is not a plain one.
constexpr std::size_t kMaxHeaderBytes = 1 << 16;

// The header's words, line by line.
class HeaderLines {
 public:
  explicit HeaderLines(std::string_view header) : rest_(header) {}

  // The next line's words; false at the header's end.
  bool next(std::vector<std::string_view>* words) {
    if (rest_.empty()) return false;
    const std::size_t newline = rest_.find('\n');
    std::string_view line = rest_.substr(0, newline);
    rest_ = newline == std::string_view::npos ? std::string_view() : rest_.substr(newline + 1);
    words->clear();
    std::size_t pos = 0;
    while (pos < line.size()) {
      while (pos < line.size() && isBlank(line[pos])) ++pos;
      if (pos == line.size()) break;
      std::size_t end = pos;
      while (end < line.size() && !isBlank(line[end])) ++end;
      words->push_back(line.substr(pos, end - pos));
      pos = end;
    }
    return true;
  }

 private:
  static bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r'; }
  std::string_view rest_;
};

bool parseCount(std::string_view word, std::uint64_t* out) {
  const char* end = word.data() + word.size();
  const auto [ptr, ec] = std::from_chars(word.data(), end, *out);
  return ec == std::errc() && ptr == end;
}

// The bytes of an integer type's name that a face list may use (0: not one), and whether it is
// signed.
int integerBytes(std::string_view type, bool* is_signed) {
  *is_signed = type == "char" || type == "int8" || type == "short" || type == "int16" ||
               type == "int" || type == "int32";
  if (type == "char" || type == "int8" || type == "uchar" || type == "uint8") return 1;
  if (type == "short" || type == "int16" || type == "ushort" || type == "uint16") return 2;
  if (type == "int" || type == "int32" || type == "uint" || type == "uint32") return 4;
  return 0;
}

// A little-endian integer of `bytes` bytes at p.
std::int64_t readInteger(const unsigned char* p, int bytes, bool is_signed) {
  std::uint32_t u = 0;
  for (int k = 0; k < bytes; ++k) u |= static_cast<std::uint32_t>(p[k]) << (8 * k);
  if (!is_signed) return u;
  const int shift = 32 - 8 * bytes;
  return static_cast<std::int32_t>(u << shift) >> shift;
}

// What a plain header says.
struct Layout {
  std::uint64_t vertices = 0, faces = 0;
  int count_bytes = 0, index_bytes = 0;
  bool index_signed = false;
};

// Reads the header (text up to and including "end_header\n"): false if it is not a plain one.
bool readHeader(std::string_view header, Layout* layout) {
  HeaderLines lines(header);
  std::vector<std::string_view> w;
  if (!lines.next(&w) || w.size() != 1 || w[0] != "ply") return false;
  if (!lines.next(&w) || w.size() != 3 || w[0] != "format" || w[1] != "binary_little_endian" ||
      w[2] != "1.0") {
    return false;
  }
  // Where the header is: 0 before the vertex element, 1-3 after its line and x, y, 4 after z, 5
  // after the face element's line, 6 after its list.
  int stage = 0;
  const char* const axes = "xyz";
  while (lines.next(&w)) {
    if (w.empty()) return false;
    if (w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") return w.size() == 1 && stage == 6;
    if (stage == 0 && w.size() == 3 && w[0] == "element" && w[1] == "vertex") {
      if (!parseCount(w[2], &layout->vertices)) return false;
    } else if (stage >= 1 && stage <= 3 && w.size() == 3 && w[0] == "property" &&
               (w[1] == "float" || w[1] == "float32") &&
               w[2] == std::string_view(axes + stage - 1, 1)) {
    } else if (stage == 4 && w.size() == 3 && w[0] == "element" && w[1] == "face") {
      if (!parseCount(w[2], &layout->faces)) return false;
    } else if (stage == 5 && w.size() == 5 && w[0] == "property" && w[1] == "list" &&
               (w[4] == "vertex_indices" || w[4] == "vertex_index")) {
      bool count_signed = false;
      layout->count_bytes = integerBytes(w[2], &count_signed);
      layout->index_bytes = integerBytes(w[3], &layout->index_signed);
      if (layout->count_bytes == 0 || count_signed || layout->index_bytes == 0) return false;
    } else {
      return false;
    }
    ++stage;
  }
  return false;
}

}  // namespace

bool isPlyPath(const std::string& path) { return lowerExtension(path) == ".ply"; }

std::optional<MeshData> readPlainPly(const std::string& path, const Eigen::Vector3d& scale) {
  const File file = openMeshFile(path);
  std::vector<unsigned char> data;
  for (;;) {
    const std::size_t size = data.size();
    data.resize(size + (std::size_t(1) << 20));
    const std::size_t got = std::fread(data.data() + size, 1, data.size() - size, file.get());
    data.resize(size + got);
    if (got == 0) break;
  }
  if (std::ferror(file.get())) {
    throw SceneLoadError(std::string("reading it failed: ") + std::strerror(errno));
  }
  const std::string_view text(reinterpret_cast<const char*>(data.data()),
                              std::min(data.size(), kMaxHeaderBytes));
  const std::size_t end = text.find("end_header\n");
  if (end == std::string_view::npos) return std::nullopt;
  const std::size_t body = end + std::strlen("end_header\n");
  Layout layout;
  if (!readHeader(text.substr(0, body), &layout)) return std::nullopt;
  // The sizes, before any allocation: a face is its count and three indices.
  const std::size_t face_bytes = layout.count_bytes + 3 * layout.index_bytes;
  const std::size_t available = data.size() - body;
  if (layout.faces == 0 || layout.vertices >= std::numeric_limits<std::uint32_t>::max() ||
      layout.vertices > available / 12 ||
      layout.faces > (available - 12 * layout.vertices) / face_bytes) {
    return std::nullopt;  // assimp says what is wrong (or reads what follows: not plain)
  }
  const unsigned char* vertex_data = data.data() + body;
  const unsigned char* face_data = vertex_data + 12 * layout.vertices;
  if (face_data + face_bytes * layout.faces != data.data() + data.size()) return std::nullopt;
  // Which vertices the faces use; every face a triangle of vertices of the file.
  const auto vertex_count = static_cast<std::uint32_t>(layout.vertices);
  std::vector<std::uint32_t> corners(3 * layout.faces);
  std::vector<bool> used(vertex_count, false);
  for (std::uint64_t f = 0; f < layout.faces; ++f) {
    const unsigned char* p = face_data + f * face_bytes;
    if (readInteger(p, layout.count_bytes, false) != 3) return std::nullopt;
    for (int k = 0; k < 3; ++k) {
      const std::int64_t v = readInteger(p + layout.count_bytes + k * layout.index_bytes,
                                         layout.index_bytes, layout.index_signed);
      if (v < 0 || v >= vertex_count) return std::nullopt;
      corners[3 * f + k] = static_cast<std::uint32_t>(v);
      used[v] = true;
    }
  }
  // The used vertices joined in the file's order, as the assimp path keeps them. A vertex that is
  // not finite, used or not, the assimp path reports.
  constexpr std::uint32_t kUnused = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> joined(vertex_count, kUnused);
  MeshData out;
  VertexJoiner joiner(scale, &out.vertices);
  joiner.reserve(vertex_count);
  for (std::uint32_t v = 0; v < vertex_count; ++v) {
    float xyz[3];
    std::memcpy(xyz, vertex_data + 12 * static_cast<std::size_t>(v), sizeof xyz);
    if (!std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2])) {
      return std::nullopt;
    }
    if (used[v]) joined[v] = joiner.add(xyz[0], xyz[1], xyz[2]);
  }
  out.triangles.resize(layout.faces);
  for (std::size_t f = 0; f < out.triangles.size(); ++f) {
    for (int k = 0; k < 3; ++k) out.triangles[f][k] = joined[corners[3 * f + k]];
  }
  return out;
}

}  // namespace mesh_file
}  // namespace laser_raycast
