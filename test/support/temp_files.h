// Files a test writes: a fresh directory per test process, removed at exit.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

namespace laser_raycast_test {

struct TempDir {
  TempDir()
      : path(std::filesystem::temp_directory_path() /
             ("laser_raycast_test_" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  std::filesystem::path path;
};

inline const std::filesystem::path& tempDir() {
  static const TempDir dir;
  return dir.path;
}

// Writes content to name in tempDir(); returns its path.
inline std::string writeFile(const std::string& name, const std::string& content) {
  const std::filesystem::path path = tempDir() / name;
  std::ofstream(path, std::ios::binary) << content;
  return path.string();
}

// Writes a binary STL of `triangles` triangles to name in tempDir(): a flat sheet of 1 cm squares,
// two triangles each, facing +z, in rows of 1000 squares; returns its path.
inline std::string writeBinaryStlGrid(const std::string& name, std::uint32_t triangles) {
  const std::filesystem::path path = tempDir() / name;
  std::ofstream out(path, std::ios::binary);
  const std::string header(80, '\0');
  out.write(header.data(), header.size());
  out.write(reinterpret_cast<const char*>(&triangles), sizeof triangles);
  for (std::uint32_t t = 0; t < triangles; ++t) {
    const std::uint32_t square = t / 2;
    const float x = 0.01f * (square % 1000), y = 0.01f * (square / 1000), d = 0.01f;
    const float upper[9] = {x, y, 0, x + d, y, 0, x, y + d, 0};
    const float lower[9] = {x + d, y, 0, x + d, y + d, 0, x, y + d, 0};
    const float normal[3] = {0, 0, 1};
    char record[50] = {};  // normal, three vertices, attribute count
    std::memcpy(record, normal, sizeof normal);
    std::memcpy(record + 12, t % 2 ? lower : upper, sizeof upper);
    out.write(record, sizeof record);
  }
  return path.string();
}

}  // namespace laser_raycast_test
