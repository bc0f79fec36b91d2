#include "bench_load.h"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <stdexcept>

#include "bench_methods.h"
#include "bench_peers.h"
#include "bench_report.h"
#include "bench_run.h"
#include "laser_raycast/loader/scene_loader.h"

namespace laser_raycast {
namespace bench {
namespace {

// The soup as a binary STL: an 80-byte header, the count, and per triangle a zero normal, its
// vertices in float and two zero bytes.
void writeStl(const MeshData& soup, const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  char header[80] = "laser_raycast bench";
  out.write(header, sizeof header);
  const auto count = static_cast<std::uint32_t>(soup.triangles.size());
  out.write(reinterpret_cast<const char*>(&count), 4);
  std::vector<char> record(50, 0);
  for (const core::TriangleIndices& tri : soup.triangles) {
    for (int k = 0; k < 3; ++k) {
      for (int a = 0; a < 3; ++a) {
        const auto f = static_cast<float>(soup.vertices[tri[k]][a]);
        std::memcpy(record.data() + 12 + 12 * k + 4 * a, &f, 4);
      }
    }
    out.write(record.data(), static_cast<std::streamsize>(record.size()));
  }
  if (!out) throw std::runtime_error("writing " + path + " failed");
}

// The soup as a Wavefront OBJ: its vertices (to float precision, as the STL has them) and faces.
void writeObj(const MeshData& soup, const std::string& path) {
  std::ofstream out(path);
  char line[96];
  for (const Eigen::Vector3d& v : soup.vertices) {
    std::snprintf(line, sizeof line, "v %.9g %.9g %.9g\n", static_cast<float>(v.x()),
                  static_cast<float>(v.y()), static_cast<float>(v.z()));
    out << line;
  }
  for (const core::TriangleIndices& tri : soup.triangles) {
    out << "f " << tri[0] + 1 << " " << tri[1] + 1 << " " << tri[2] + 1 << "\n";
  }
  if (!out) throw std::runtime_error("writing " + path + " failed");
}

// The soup as a binary little-endian PLY: its vertices in float, faces of three int indices.
void writePly(const MeshData& soup, const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  out << "ply\nformat binary_little_endian 1.0\ncomment laser_raycast bench\nelement vertex "
      << soup.vertices.size() << "\nproperty float x\nproperty float y\nproperty float z\n"
      << "element face " << soup.triangles.size()
      << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const Eigen::Vector3d& v : soup.vertices) {
    const float xyz[3] = {static_cast<float>(v.x()), static_cast<float>(v.y()),
                          static_cast<float>(v.z())};
    out.write(reinterpret_cast<const char*>(xyz), sizeof xyz);
  }
  char face[13] = {3};
  for (const core::TriangleIndices& tri : soup.triangles) {
    for (int k = 0; k < 3; ++k) {
      const auto index = static_cast<std::int32_t>(tri[k]);
      std::memcpy(face + 1 + 4 * k, &index, 4);
    }
    out.write(face, sizeof face);
  }
  if (!out) throw std::runtime_error("writing " + path + " failed");
}

// The loader's time from nothing to the mesh built, as a node's start-up spends it (its importer
// process started, the file read, the BVHs built).
double loaderSeconds(const std::string& path, int threads) {
  const auto start = std::chrono::steady_clock::now();
  SceneLoader loader([](const std::string&) { return std::optional<std::string>(); });
  core::BvhConfig bvh;
  bvh.threads = threads;
  const std::shared_ptr<const core::Mesh> mesh =
      loader.loadMesh(path, "", Eigen::Vector3d::Ones(), bvh);
  return secondsSince(start);
}

}  // namespace

std::vector<LoadRow> measureLoads(const BenchScene& scene, const std::vector<std::string>& formats,
                                  int rounds, int threads) {
  std::vector<LoadRow> rows;
  if (scene.soup.triangles.size() < kLoadMinTriangles) return rows;
  char dir_template[] = "/tmp/laser_raycast_bench_XXXXXX";
  if (!mkdtemp(dir_template)) throw std::runtime_error("cannot make a temporary directory");
  const std::filesystem::path dir(dir_template);
  try {
    for (const std::string& format : formats) {
      const std::string path = (dir / (scene.name + "." + format)).string();
      if (format == "stl") {
        writeStl(scene.soup, path);
      } else if (format == "ply") {
        writePly(scene.soup, path);
      } else {
        writeObj(scene.soup, path);
      }
      std::vector<int> thread_counts{1};
      if (threads != 1) thread_counts.push_back(threads);
      for (const int t : thread_counts) {
        LoadRow row;
        row.scene = scene.name;
        row.format = format;
        row.triangles = scene.soup.triangles.size();
        row.file_bytes = std::filesystem::file_size(path);
        row.threads = t;
        for (int r = 0; r < rounds; ++r) {
          row.ours_seconds.push_back(loaderSeconds(path, t));
          const std::optional<double> peer = assimpEmbreeLoadSeconds(path);
          if (peer) row.peer_seconds.push_back(*peer);
        }
        std::cerr << "  load " << format << " (" << row.file_bytes / 1e6 << " MB, threads " << t
                  << "): ours " << median(row.ours_seconds) << " s";
        if (!row.peer_seconds.empty()) {
          std::cerr << ", assimp + Embree " << median(row.peer_seconds) << " s";
        }
        std::cerr << "\n";
        rows.push_back(std::move(row));
      }
      std::filesystem::remove(path);
    }
  } catch (...) {
    std::filesystem::remove_all(dir);
    throw;
  }
  std::filesystem::remove_all(dir);
  return rows;
}

}  // namespace bench
}  // namespace laser_raycast
