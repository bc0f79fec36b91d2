#include "stl_reader.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <sstream>
#include <string_view>
#include <vector>

#include "vertex_joiner.h"

namespace laser_raycast {
namespace mesh_file {
namespace {

namespace fs = std::filesystem;

// Binary STL is little-endian, and its records are read as they lie in memory.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "the binary STL reader needs little-endian");

constexpr std::uint64_t kHeaderBytes = 84;      // 80 bytes of anything, then the u32 triangle count
constexpr std::uint64_t kRecordBytes = 50;      // normal, 3 corners (12 floats), u16 attributes
constexpr std::size_t kChunkRecords = 1 << 16;  // 3.2 MB read at a time

std::string inQuotes(std::string_view s) { return "'" + std::string(s) + "'"; }

// A file that is not ASCII STL after all (readStl then says what it is not as binary STL either).
class NotAscii : public SceneLoadError {
 public:
  using SceneLoadError::SceneLoadError;
};

std::string coordinates(const float* corner) {
  std::ostringstream out;
  out << corner[0] << " " << corner[1] << " " << corner[2];
  return out.str();
}

// ---------------------------------------------------------------------------------------------------
// Binary: a header of 80 bytes, the u32 count, then per triangle a normal, three corners (float
// x y z each) and two attribute bytes. The normal and the attributes are not used.

MeshData readBinary(std::FILE* file, std::uint32_t count, const Eigen::Vector3d& scale) {
  if (count == 0)
    throw SceneLoadError("it has no triangles (an empty mesh: a binary STL whose header counts 0)");
  MeshData out;
  out.triangles.reserve(count);
  VertexJoiner joiner(scale, &out.vertices);
  joiner.reserve(count / 2 + 2);  // a closed surface has about half as many vertices as triangles
  std::vector<unsigned char> chunk(kChunkRecords * kRecordBytes);
  if (std::fseek(file, kHeaderBytes, SEEK_SET) != 0) {
    throw SceneLoadError(std::string("reading it failed: ") + std::strerror(errno));
  }
  std::vector<float> corners(kChunkRecords * 9);
  std::vector<std::uint32_t> indices(kChunkRecords * 3);
  for (std::uint64_t done = 0; done < count;) {
    const auto n = static_cast<std::size_t>(std::min<std::uint64_t>(kChunkRecords, count - done));
    if (std::fread(chunk.data(), kRecordBytes, n, file) != n) {
      // The size was checked: the file changed or could not be read.
      throw SceneLoadError("reading it failed after " + std::to_string(done) + " triangles");
    }
    for (std::size_t i = 0; i < n; ++i) {
      float* c = &corners[9 * i];
      std::memcpy(c, chunk.data() + i * kRecordBytes + 12, 9 * sizeof(float));
      for (int k = 0; k < 3; ++k, c += 3) {
        if (!(std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]))) {
          throw SceneLoadError("vertex " + std::to_string(k) + " of triangle " +
                               std::to_string(done + i) + " is not finite (" + coordinates(c) +
                               ")");
        }
      }
    }
    joiner.addAll(corners.data(), 3 * n, indices.data());
    for (std::size_t i = 0; i < n; ++i) {
      out.triangles.push_back({indices[3 * i], indices[3 * i + 1], indices[3 * i + 2]});
    }
    done += n;
  }
  return out;
}

// ---------------------------------------------------------------------------------------------------
// ASCII: words separated by white space, read through a buffer refilled from the file.
//
//   solid [name]
//     facet normal nx ny nz
//       outer loop
//         vertex x y z      (three times)
//       endloop
//     endfacet
//   endsolid [name]
//
// and further solids after the first. Keywords are lower case (assimp reads no others); the names
// are the rest of their line. Anything else, a facet of other than three vertices, or a file that
// ends before "endsolid" is an error naming the line: assimp skips unknown words, drops a fourth
// vertex and takes a truncated file for a whole one.

class WordReader {
 public:
  explicit WordReader(std::FILE* file) : file_(file), buffer_(std::size_t(1) << 20) {}

  // The next word, or "" at the end of the file; valid until the next call.
  std::string_view next() {
    for (;;) {
      while (pos_ < end_ && isSpace(buffer_[pos_])) line_ += buffer_[pos_++] == '\n';
      if (pos_ < end_ || !fill()) break;
    }
    word_line_ = line_;
    std::size_t length = 0;
    for (;;) {
      while (pos_ + length < end_ && !isSpace(buffer_[pos_ + length])) ++length;
      if (pos_ + length < end_) break;
      if (length > kMaxWord)
        throw error("a word of more than " + std::to_string(kMaxWord) + " bytes");
      if (!fill()) break;
    }
    const std::string_view word(buffer_.data() + pos_, length);
    pos_ += length;
    return word;
  }

  // Skips the rest of the current line (a solid's name).
  void skipLine() {
    for (;;) {
      const void* newline = std::memchr(buffer_.data() + pos_, '\n', end_ - pos_);
      if (newline) {
        pos_ = static_cast<const char*>(newline) - buffer_.data() + 1;
        ++line_;
        return;
      }
      pos_ = end_;
      if (!fill()) return;
    }
  }

  // The last word's line, from 1.
  std::size_t line() const { return word_line_; }
  // What is wrong at the last word.
  NotAscii error(const std::string& what) const {
    return NotAscii("line " + std::to_string(word_line_) + ": " + what);
  }

 private:
  static constexpr std::size_t kMaxWord = 4096;

  // NUL too: some writers pad the end of the file with it.
  static bool isSpace(char c) { return c == ' ' || (c >= '\t' && c <= '\r') || c == '\0'; }

  // Moves the unread bytes to the front and reads more after them; false at the end of the file.
  bool fill() {
    if (eof_) return false;
    std::memmove(buffer_.data(), buffer_.data() + pos_, end_ - pos_);
    end_ -= pos_;
    pos_ = 0;
    const std::size_t n = std::fread(buffer_.data() + end_, 1, buffer_.size() - end_, file_);
    if (n == 0) {
      if (std::ferror(file_)) throw SceneLoadError("reading it failed");
      eof_ = true;
      return false;
    }
    end_ += n;
    return true;
  }

  std::FILE* file_;
  std::vector<char> buffer_;
  std::size_t pos_ = 0, end_ = 0;
  bool eof_ = false;
  std::size_t line_ = 1, word_line_ = 1;
};

bool startsWith(std::string_view word, std::string_view prefix) {
  return word.substr(0, prefix.size()) == prefix;
}

void expectWord(WordReader* in, std::string_view keyword) {
  const std::string_view word = in->next();
  if (word != keyword) {
    throw in->error((word.empty() ? std::string("the end of the file") : inQuotes(word)) +
                    " where " + inQuotes(keyword) + " was expected" +
                    (word.empty() ? " (truncated?)" : ""));
  }
}

// A number as a float, correctly rounded (assimp's own parser may differ in the last bit); one out
// of float's range becomes infinite or (too small) rounds through double.
float readNumber(WordReader* in) {
  const std::string_view word = in->next();
  const char* first = word.data();
  const char* const last = first + word.size();
  if (first != last && *first == '+' && last - first > 1 && first[1] != '-') ++first;
  float value = 0;
  auto result = std::from_chars(first, last, value);
  if (result.ec == std::errc::result_out_of_range) {
    double wide = 0;
    result = std::from_chars(first, last, wide);
    value = result.ec == std::errc() ? static_cast<float>(wide)
                                     : std::numeric_limits<float>::infinity();
    if (result.ec == std::errc::result_out_of_range) result.ec = std::errc();
  }
  if (result.ec != std::errc() || result.ptr != last) {
    throw in->error((word.empty() ? std::string("the end of the file") : inQuotes(word)) +
                    " where a number was expected");
  }
  return value;
}

// One facet, after its "facet" keyword.
core::TriangleIndices readFacet(WordReader* in, VertexJoiner* joiner) {
  expectWord(in, "normal");
  for (int i = 0; i < 3; ++i) readNumber(in);  // not used (core::Mesh computes its own)
  expectWord(in, "outer");
  expectWord(in, "loop");
  core::TriangleIndices tri;
  for (int k = 0; k < 3; ++k) {
    expectWord(in, "vertex");
    float c[3];
    for (float& x : c) x = readNumber(in);
    if (!(std::isfinite(c[0]) && std::isfinite(c[1]) && std::isfinite(c[2]))) {
      throw SceneLoadError("line " + std::to_string(in->line()) + ": a vertex is not finite (" +
                           coordinates(c) + ")");
    }
    tri[k] = joiner->add(c[0], c[1], c[2]);
  }
  expectWord(in, "endloop");
  expectWord(in, "endfacet");
  return tri;
}

MeshData readAscii(std::FILE* file, const Eigen::Vector3d& scale) {
  MeshData out;
  VertexJoiner joiner(scale, &out.vertices);
  WordReader in(file);
  std::string_view word = in.next();
  if (!startsWith(word, "solid")) throw in.error("it does not start with 'solid'");
  while (startsWith(word, "solid")) {
    in.skipLine();  // the name
    for (word = in.next(); word == "facet"; word = in.next()) {
      if (out.triangles.size() >= std::numeric_limits<std::uint32_t>::max()) {
        throw SceneLoadError("more triangles than 32-bit indices can address");
      }
      out.triangles.push_back(readFacet(&in, &joiner));
    }
    if (word.empty()) throw in.error("the file ends before 'endsolid' (truncated?)");
    if (!startsWith(word, "endsolid")) {
      throw in.error(inQuotes(word) + " where 'facet' or 'endsolid' was expected");
    }
    in.skipLine();
    word = in.next();
  }
  if (!word.empty()) {
    throw in.error(inQuotes(word) +
                   " after 'endsolid', where the file should end or a 'solid' begin");
  }
  if (out.triangles.empty())
    throw SceneLoadError("it has no triangles (an empty mesh: an ASCII STL without facets)");
  return out;
}

}  // namespace

bool isStlPath(const std::string& path) { return lowerExtension(path) == ".stl"; }

MeshData readStl(const std::string& path, const Eigen::Vector3d& scale) {
  const File file = openMeshFile(path);
  std::error_code ec;
  const std::uint64_t size = fs::file_size(path, ec);
  if (ec) throw SceneLoadError("cannot tell its size: " + ec.message());
  unsigned char header[kHeaderBytes];
  const std::size_t got = std::fread(header, 1, sizeof(header), file.get());
  std::uint32_t count = 0;
  std::string as_binary = "which has at least 84 bytes; the file has " + std::to_string(size);
  if (got == kHeaderBytes) {
    std::memcpy(&count, header + 80, sizeof(count));
    const std::uint64_t expected = kHeaderBytes + kRecordBytes * count;
    if (expected == size) return readBinary(file.get(), count, scale);
    as_binary = "its header counts " + std::to_string(count) + " triangles, which take " +
                std::to_string(expected) + " bytes; the file has " + std::to_string(size) +
                (size < expected ? ": truncated, or a wrong count" : ": a wrong count");
  }
  std::rewind(file.get());
  try {
    return readAscii(file.get(), scale);
  } catch (const NotAscii& e) {
    // A file whose first bytes are all text was not meant as binary: what is wrong with it as
    // binary would only distract.
    const bool text = std::all_of(header, header + got, [](unsigned char c) {
      return (c >= 0x20 && c < 0x7f) || c == '\t' || c == '\n' || c == '\r';
    });
    if (text) throw SceneLoadError(std::string("not a valid ASCII STL: ") + e.what());
    throw SceneLoadError(std::string("not an ASCII STL (") + e.what() + ") nor a binary one (" +
                         as_binary + ")");
  }
}

}  // namespace mesh_file
}  // namespace laser_raycast
