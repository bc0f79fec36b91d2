#include "import_protocol.h"

#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>

namespace laser_raycast {
namespace import_protocol {
namespace {

constexpr char kRequestMagic[4] = {'L', 'R', 'M', 'Q'};
constexpr char kReplyMagic[4] = {'L', 'R', 'M', 'I'};
constexpr std::uint32_t kVersion = 2;
constexpr std::size_t kHeaderBytes = 12;          // magic, version, status (or path length)
constexpr std::uint32_t kMaxPathBytes = 1 << 16;  // far beyond PATH_MAX

// The arrays go out as they lie in memory.
static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double), "Vector3d must be 3 packed doubles");
static_assert(sizeof(core::TriangleIndices) == 3 * sizeof(std::uint32_t),
              "TriangleIndices must be 3 packed u32");
constexpr std::uint64_t kVertexBytes = sizeof(Eigen::Vector3d);
constexpr std::uint64_t kTriangleBytes = sizeof(core::TriangleIndices);

bool writeAll(int fd, const void* data, std::size_t size) {
  const char* p = static_cast<const char*>(data);
  bool socket = true;
  while (size > 0) {
    // send() on a socket whose reader has gone returns EPIPE instead of raising SIGPIPE, which
    // would end the loader's process (the node). Anything else (a pipe, a file) takes write().
    const ssize_t n = socket ? ::send(fd, p, size, MSG_NOSIGNAL) : ::write(fd, p, size);
    if (n < 0 && socket && errno == ENOTSOCK) {
      socket = false;
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

bool writeHeader(int fd, const char (&magic)[4], std::uint32_t word) {
  return writeAll(fd, magic, sizeof(magic)) && writeAll(fd, &kVersion, sizeof(kVersion)) &&
         writeAll(fd, &word, sizeof(word));
}

// Reads exactly size bytes; returns how many came before the end of input.
std::size_t readAll(int fd, void* data, std::size_t size) {
  char* p = static_cast<char*>(data);
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::read(fd, p + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    done += static_cast<std::size_t>(n);
  }
  return done;
}

// Reads fixed-size fields from a reply in memory, failing on truncation.
class Reader {
 public:
  explicit Reader(const std::string& bytes) : bytes_(bytes) {}

  bool has(std::size_t size) const { return size <= remaining(); }
  void read(void* out, std::size_t size, const char* what) {
    if (!has(size)) {
      throw SceneLoadError(std::string("the importer's reply is truncated (in ") + what + ")");
    }
    if (size == 0) return;  // out may be an empty vector's data(), null (memcpy must not see it)
    std::memcpy(out, bytes_.data() + pos_, size);
    pos_ += size;
  }
  template <typename T>
  T read(const char* what) {
    T value;
    read(&value, sizeof(value), what);
    return value;
  }
  std::size_t remaining() const { return bytes_.size() - pos_; }

 private:
  const std::string& bytes_;
  std::size_t pos_ = 0;
};

// The reply's header; throws for anything but a reply of this version.
Status readReplyHeader(Reader* in) {
  char magic[sizeof(kReplyMagic)];
  in->read(magic, sizeof(magic), "the header");
  if (std::memcmp(magic, kReplyMagic, sizeof(magic)) != 0) {
    throw SceneLoadError("the importer's reply does not start with its magic number");
  }
  const auto version = in->read<std::uint32_t>("the header");
  if (version != kVersion) {
    throw SceneLoadError("the importer speaks version " + std::to_string(version) +
                         " of the protocol, the loader " + std::to_string(kVersion) +
                         " (a mixed installation)");
  }
  const auto status = in->read<std::uint32_t>("the header");
  if (status > static_cast<std::uint32_t>(Status::kOutOfMemory)) {
    throw SceneLoadError("the importer's reply has an unknown status " + std::to_string(status));
  }
  return static_cast<Status>(status);
}

// The surface attributes' bytes (writeMesh's layout), empty for none.
std::string surfaceBytes(const core::SurfaceAttributes* surface) {
  std::string out;
  if (!surface) return out;
  auto put = [&out](const void* data, std::size_t size) {
    out.append(static_cast<const char*>(data), size);
  };
  const std::uint64_t counts[4] = {surface->colors.size(), surface->uvs.size(),
                                   surface->normals.size(), surface->triangle_material.size()};
  const auto materials = static_cast<std::uint32_t>(surface->materials.size());
  put(counts, sizeof(counts));
  put(&materials, sizeof(materials));
  for (const Eigen::Vector3f& c : surface->colors) put(c.data(), 3 * sizeof(float));
  for (const Eigen::Vector2f& uv : surface->uvs) put(uv.data(), 2 * sizeof(float));
  for (const Eigen::Vector3f& n : surface->normals) put(n.data(), 3 * sizeof(float));
  put(surface->triangle_material.data(), counts[3] * sizeof(std::uint32_t));
  for (const core::SurfaceMaterial& m : surface->materials) {
    const std::uint8_t has_diffuse = m.has_diffuse ? 1 : 0;
    put(&has_diffuse, 1);
    put(m.diffuse.data(), 3 * sizeof(double));
    const std::uint32_t size[2] = {m.texture ? static_cast<std::uint32_t>(m.texture->width) : 0u,
                                   m.texture ? static_cast<std::uint32_t>(m.texture->height) : 0u};
    put(size, sizeof(size));
    if (m.texture) put(m.texture->rgb.data(), m.texture->rgb.size());
  }
  return out;
}

template <typename Vector>
void readVectors(Reader* in, std::uint64_t count, std::vector<Vector>* out, const char* what) {
  constexpr std::size_t kBytes = Vector::SizeAtCompileTime * sizeof(typename Vector::Scalar);
  if (count > in->remaining() / kBytes) {
    throw SceneLoadError(std::string("the importer's reply is truncated (in ") + what + ")");
  }
  out->resize(count);
  for (Vector& v : *out) in->read(v.data(), kBytes, what);
}

// The surface attributes of a mesh of `vertices` and `triangles`; null for none.
std::shared_ptr<core::SurfaceAttributes> parseSurface(const std::string& bytes,
                                                      std::uint64_t vertices,
                                                      std::uint64_t triangles) {
  if (bytes.empty()) return nullptr;
  Reader in(bytes);
  std::uint64_t counts[4];
  in.read(counts, sizeof(counts), "the surface counts");
  const auto materials = in.read<std::uint32_t>("the surface counts");
  auto surface = std::make_shared<core::SurfaceAttributes>();
  readVectors(&in, counts[0], &surface->colors, "the colours");
  readVectors(&in, counts[1], &surface->uvs, "the texture coordinates");
  readVectors(&in, counts[2], &surface->normals, "the normals");
  if (counts[3] > in.remaining() / sizeof(std::uint32_t)) {
    throw SceneLoadError("the importer's reply is truncated (in the triangles' materials)");
  }
  surface->triangle_material.resize(counts[3]);
  in.read(surface->triangle_material.data(), counts[3] * sizeof(std::uint32_t),
          "the triangles' materials");
  for (std::uint32_t m = 0; m < materials; ++m) {
    core::SurfaceMaterial material;
    material.has_diffuse = in.read<std::uint8_t>("a material") != 0;
    in.read(material.diffuse.data(), 3 * sizeof(double), "a material");
    std::uint32_t size[2];
    in.read(size, sizeof(size), "a material");
    if (size[0] > 0 || size[1] > 0) {
      const std::uint64_t bytes_needed = 3ull * size[0] * size[1];
      if (bytes_needed > in.remaining()) {
        throw SceneLoadError("the importer's reply is truncated (in a texture)");
      }
      auto texture = std::make_shared<core::Texture>();
      texture->width = static_cast<int>(size[0]);
      texture->height = static_cast<int>(size[1]);
      texture->rgb.resize(bytes_needed);
      in.read(texture->rgb.data(), bytes_needed, "a texture");
      material.texture = std::move(texture);
    }
    surface->materials.push_back(std::move(material));
  }
  if (in.remaining() != 0) throw SceneLoadError("the importer's reply has trailing bytes");
  try {
    surface->validate(vertices, triangles);
  } catch (const std::invalid_argument& e) {
    throw SceneLoadError(std::string("the importer's reply has bad surface attributes: ") +
                         e.what());
  }
  return surface;
}

mesh_file::MeshData parseMesh(Reader* in) {
  const auto vertices = in->read<std::uint64_t>("the vertex count");
  const auto triangles = in->read<std::uint64_t>("the triangle count");
  const auto attributes = in->read<std::uint64_t>("the surface byte count");
  // The counts must match the bytes that came, before anything is allocated for them.
  const std::uint64_t remaining = in->remaining();
  if (vertices > remaining / kVertexBytes || triangles > remaining / kTriangleBytes ||
      attributes > remaining ||
      vertices * kVertexBytes + triangles * kTriangleBytes + attributes != remaining) {
    throw SceneLoadError("the importer's reply does not hold the " + std::to_string(vertices) +
                         " vertices and " + std::to_string(triangles) + " triangles it announces");
  }
  mesh_file::MeshData mesh;
  mesh.vertices.resize(vertices);
  mesh.triangles.resize(triangles);
  in->read(mesh.vertices.data(), vertices * kVertexBytes, "the vertices");
  in->read(mesh.triangles.data(), triangles * kTriangleBytes, "the triangles");
  std::string surface(attributes, '\0');
  in->read(surface.data(), attributes, "the surface attributes");
  for (const Eigen::Vector3d& v : mesh.vertices) {
    if (!v.allFinite()) throw SceneLoadError("the importer's reply has a non-finite vertex");
  }
  for (const core::TriangleIndices& t : mesh.triangles) {
    for (const std::uint32_t index : t) {
      if (index >= vertices) {
        throw SceneLoadError("the importer's reply has a vertex index out of range");
      }
    }
  }
  mesh.surface = parseSurface(surface, vertices, triangles);
  return mesh;
}

}  // namespace

bool writeRequest(int fd, const std::string& path, const Eigen::Vector3d& scale) {
  const auto length = static_cast<std::uint32_t>(path.size());
  return path.size() <= kMaxPathBytes && writeHeader(fd, kRequestMagic, length) &&
         writeAll(fd, path.data(), path.size()) && writeAll(fd, scale.data(), 3 * sizeof(double));
}

bool writeMesh(int fd, const mesh_file::MeshData& mesh) {
  const std::uint64_t vertices = mesh.vertices.size();
  const std::uint64_t triangles = mesh.triangles.size();
  const std::string surface = surfaceBytes(mesh.surface.get());
  const std::uint64_t attributes = surface.size();
  return writeHeader(fd, kReplyMagic, static_cast<std::uint32_t>(Status::kMesh)) &&
         writeAll(fd, &vertices, sizeof(vertices)) && writeAll(fd, &triangles, sizeof(triangles)) &&
         writeAll(fd, &attributes, sizeof(attributes)) &&
         writeAll(fd, mesh.vertices.data(), vertices * kVertexBytes) &&
         writeAll(fd, mesh.triangles.data(), triangles * kTriangleBytes) &&
         writeAll(fd, surface.data(), surface.size());
}

bool writeFailure(int fd, Status status, const char* message) {
  const std::size_t length = std::strlen(message);
  const auto size = static_cast<std::uint32_t>(
      std::min<std::size_t>(length, std::numeric_limits<std::uint32_t>::max()));
  return writeHeader(fd, kReplyMagic, static_cast<std::uint32_t>(status)) &&
         writeAll(fd, &size, sizeof(size)) && writeAll(fd, message, size);
}

bool readRequest(int fd, std::string* path, Eigen::Vector3d* scale) {
  char header[kHeaderBytes];
  const std::size_t got = readAll(fd, header, sizeof(header));
  if (got == 0) return false;
  std::uint32_t version = 0, length = 0;
  std::memcpy(&version, header + 4, sizeof(version));
  std::memcpy(&length, header + 8, sizeof(length));
  if (got != sizeof(header) || std::memcmp(header, kRequestMagic, sizeof(kRequestMagic)) != 0 ||
      version != kVersion || length > kMaxPathBytes) {
    throw SceneLoadError("malformed request (not from this version of the loader)");
  }
  path->assign(length, '\0');
  if (readAll(fd, path->data(), length) != length ||
      readAll(fd, scale->data(), 3 * sizeof(double)) != 3 * sizeof(double)) {
    throw SceneLoadError("truncated request");
  }
  return true;
}

std::optional<std::uint64_t> replySize(const std::string& prefix) {
  Reader in(prefix);
  if (!in.has(kHeaderBytes)) return std::nullopt;
  const Status status = readReplyHeader(&in);
  if (status != Status::kMesh) {
    if (!in.has(sizeof(std::uint32_t))) return std::nullopt;
    return kHeaderBytes + sizeof(std::uint32_t) + in.read<std::uint32_t>("the message length");
  }
  if (!in.has(3 * sizeof(std::uint64_t))) return std::nullopt;
  const auto vertices = in.read<std::uint64_t>("the vertex count");
  const auto triangles = in.read<std::uint64_t>("the triangle count");
  const auto attributes = in.read<std::uint64_t>("the surface byte count");
  // Counts that no reply could hold (their bytes would overflow) are garbage.
  constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max() / 64;
  if (vertices > kMax / kVertexBytes || triangles > kMax / kTriangleBytes || attributes > kMax) {
    throw SceneLoadError("the importer's reply announces an impossible size");
  }
  return kHeaderBytes + 3 * sizeof(std::uint64_t) + vertices * kVertexBytes +
         triangles * kTriangleBytes + attributes;
}

Reply parseReply(const std::string& bytes) {
  Reader in(bytes);
  Reply reply;
  reply.status = readReplyHeader(&in);
  if (reply.status == Status::kMesh) {
    reply.mesh = parseMesh(&in);
    return reply;
  }
  const auto length = in.read<std::uint32_t>("the message length");
  if (length != in.remaining()) {
    throw SceneLoadError("the importer's reply has a message of the wrong length");
  }
  reply.message = bytes.substr(bytes.size() - length);
  return reply;
}

}  // namespace import_protocol
}  // namespace laser_raycast
